"""Which anaglyph encoding made an image, from the image alone, with a confidence.

    found = detect(image)   # found.name: an encoding of CANDIDATES, or None
    found.confidence, found.reason, found.scores

Two questions, each answered by a physical property of the encodings (`mixtures`):
  1. **Glasses (family).** An anaglyph's channels come from two views: the channels of one
     eye are aligned with each other, those of different eyes are displaced by the
     disparities. On a copy area-downsampled to DetectConfig.width px, every pair of
     channels is matched with the census matcher over +- reach_fraction of the width; a
     pair's *displacement* is the fraction of left-right consistent pixels with |d| >= 1.5.
     Family f (its odd channel: R for red-cyan, G for green-magenta, B for amber-blue)
     scores min(displacement of the odd channel against the other two) - displacement of
     the other two against each other. An ordinary photo, a gray photo or a diplopia image
     (every channel holds both views, aligned) scores ~0 for every family and is refused.
  2. **Variant (colour, gray, half-colour, optimized, Dubois).** The odd channel is matched
     against the mean of the other two; at consistent, smooth pixels the colour c of the
     surface is seen as o = [odd channel at x, other channels at x - d]. Under encoding h
     (matrices A_L, A_R) o = clip(M_h c), M_h = A_L + A_R, c in [0, 1]^3. Each h is scored
     by the mean log-likelihood of a uniform c blurred by noise: -0.5 log det(M M^T +
     thickness^2 I) - |o - clip(M c*)|^2 / (2 noise^2) (c* the box-constrained fit; each
     sample's term capped at max_penalty). The colour encoding explains every o with
     volume 1; gray (R = G = B), optimized (a plane) and half-colour or Dubois (smaller
     parallelepipeds) explain less and so win wherever their samples fit them.
Confidence: the family's margin through a logistic, times the variant's posterior
(softmax of `evidence` x mean log-likelihood). Dubois red-cyan images are reported as
'dubois_ffmpeg': the two Dubois matrices of `mixtures` differ by < 0.03 per coefficient,
which an image cannot tell apart. Desaturated scenes hold little colour evidence, so there
colour, half-colour and Dubois are close (and close in what unmixing gives).
"""

import dataclasses
from typing import Dict, Optional

import cv2
import numpy as np

from mixstereo_tf import mixtures
from mixstereo_tf.baselines import matcher

# The channel each family's odd eye owns (red-cyan: R alone is the left eye).
FAMILY_ODD_CHANNEL = {'red_cyan': 0, 'green_magenta': 1, 'amber_blue': 2}
CANDIDATES = tuple(name for name in mixtures.ANAGLYPH_NAMES if name != 'dubois')
_PAIRS = ((0, 1), (0, 2), (1, 2))
# The colours of natural photographs, [0, 1] RGB: mean and covariance of every 7th pixel of
# scikit-image's astronaut, coffee, chelsea and rocket pictures (training data only).
NATURAL_MEAN = np.array([0.471, 0.345, 0.309])
NATURAL_COVARIANCE = np.array([[0.0854, 0.0547, 0.0316],
                               [0.0547, 0.0537, 0.0452],
                               [0.0316, 0.0452, 0.0502]])


@dataclasses.dataclass(frozen=True)
class DetectConfig:
  """Parameters of `detect` (module docstring); chosen on training scenes.

  Attributes:
    width: the analysed copy's width, pixels.
    reach_fraction: channels are matched over +- this fraction of that width.
    min_family_score: below this family score the image is not an anaglyph.
    family_softness: the logistic's scale on the family margin.
    noise: the colour residual's standard deviation, [0, 1] units.
    singular_share: a rank-deficient encoding (gray, optimized) is chosen when this share
      of pixels (gray: two channels of one eye equal within noise / 2) ...
    plane_share: ... or this share of colour samples within noise of its plane fits it.
    evidence: how many independent samples the mean log-likelihood stands for.
    samples: at most this many colour samples.
  """
  width: int = 320
  reach_fraction: float = 0.2
  min_family_score: float = 0.08
  family_softness: float = 0.03
  noise: float = 0.025
  singular_share: float = 0.9
  plane_share: float = 0.97
  evidence: float = 3.0
  samples: int = 20000


@dataclasses.dataclass(frozen=True)
class Detection:
  """What `detect` found.

  Attributes:
    name: the encoding (of CANDIDATES), or None when the image is not an anaglyph.
    confidence: in [0, 1]: of `name`, or that the image is no anaglyph when name is None.
    reason: one line saying why.
    scores: family scores ('family:<name>') and variant posteriors (encoding names).
  """
  name: Optional[str]
  confidence: float
  reason: str
  scores: Dict[str, float]


def _small(image: np.ndarray, width: int) -> np.ndarray:
  """float32 [h, w, 3] on 0..255, area-downsampled to at most `width` columns."""
  image = np.asarray(image)
  if image.ndim != 3 or image.shape[2] != 3:
    raise ValueError(f'detect needs an [H, W, 3] RGB image, got shape {image.shape}.')
  image = image.astype(np.float32) * (1.0 if image.dtype == np.uint8 else 255.0)
  h, w = image.shape[:2]
  if w > width:
    image = cv2.resize(image, (width, max(1, round(h * width / w))),
                       interpolation=cv2.INTER_AREA)
  return np.ascontiguousarray(image)


def _match(a: np.ndarray, b: np.ndarray, reach: int) -> dict:
  return matcher.match(a, b, -reach, reach, matcher.MatcherConfig(threads=1))


def family_scores(small: np.ndarray, config: DetectConfig) -> Dict[str, float]:
  """{family: score} (step 1 of the module docstring) of a 0..255 image."""
  reach = max(2, round(config.reach_fraction * small.shape[1]))
  displaced = {}
  for a, b in _PAIRS:
    out = _match(small[..., a], small[..., b], reach)
    moved = out['consistent_left'] & (np.abs(out['disparity_left']) >= 1.5)
    displaced[(a, b)] = float(moved.mean())
  scores = {}
  for family, odd in FAMILY_ODD_CHANNEL.items():
    others = tuple(c for c in range(3) if c != odd)
    cross = min(displaced[tuple(sorted((odd, o)))] for o in others)
    scores[family] = cross - displaced[others]
  return scores


def colour_samples(small: np.ndarray, odd: int, config: DetectConfig) -> np.ndarray:
  """[N, 3] colours o in [0, 1] (step 2): the odd channel at x, the others at x - d."""
  others = [c for c in range(3) if c != odd]
  reach = max(2, round(config.reach_fraction * small.shape[1]))
  out = _match(small[..., odd], small[..., others].mean(axis=2), reach)
  smooth = cv2.blur(small, (3, 3)) / 255.0
  grad = sum(np.abs(cv2.Sobel(smooth[..., c], cv2.CV_32F, 1, 0)) +
             np.abs(cv2.Sobel(smooth[..., c], cv2.CV_32F, 0, 1)) for c in range(3))
  h, w = small.shape[:2]
  ys, xs = np.nonzero(out['consistent_left'])
  xr = np.rint(xs - out['disparity_left'][ys, xs]).astype(int)
  keep = (xr >= 0) & (xr < w)
  ys, xs, xr = ys[keep], xs[keep], xr[keep]
  flat = (grad[ys, xs] <= np.median(grad)) & (grad[ys, xr] <= np.median(grad))
  ys, xs, xr = ys[flat], xs[flat], xr[flat]
  if ys.size > config.samples:
    pick = np.random.default_rng(0).choice(ys.size, config.samples, replace=False)
    ys, xs, xr = ys[pick], xs[pick], xr[pick]
  obs = np.empty((ys.size, 3), np.float64)
  obs[:, odd] = smooth[ys, xs, odd]
  obs[:, others] = smooth[ys, xr][:, others]
  return obs


def _matrix(name: str) -> np.ndarray:
  spec = mixtures.get_mixture(name)
  return np.asarray(spec.left_matrix) + np.asarray(spec.right_matrix)


def _fit(obs: np.ndarray, name: str) -> np.ndarray:
  """Squared residuals [N] of colour samples against clip(M c), c in the unit box."""
  m, clip = _matrix(name), mixtures.get_mixture(name).clip
  c = np.clip(obs @ np.linalg.pinv(m).T, 0.0, 1.0)
  step = 1.0 / np.linalg.norm(m, 2) ** 2
  for _ in range(60):  # Projected gradient on |clip(M c) - o|^2 over the unit box.
    predicted = m @ c.T
    inside = ((predicted > 0) & (predicted < 1)) if clip else 1.0
    c = np.clip(c - step * ((np.clip(predicted, 0, 1) - obs.T) * inside).T @ m, 0.0, 1.0)
  return ((obs - np.clip(c @ m.T, 0.0, 1.0)) ** 2).sum(axis=1)


def log_likelihood(obs: np.ndarray, name: str) -> float:
  """Mean log-likelihood of colour samples [N, 3] under a full-rank encoding (step 2):
  log N(M^-1 o; NATURAL_MEAN, NATURAL_COVARIANCE) - log |det M|."""
  m = _matrix(name)
  centred = obs @ np.linalg.inv(m).T - NATURAL_MEAN
  mahalanobis = np.einsum('ni,ij,nj->n', centred, np.linalg.inv(NATURAL_COVARIANCE), centred)
  return float(-0.5 * mahalanobis.mean() - np.linalg.slogdet(m)[1])


def fits_singular(small: np.ndarray, obs: np.ndarray, name: str,
                  config: DetectConfig) -> bool:
  """Whether a rank-deficient encoding explains the image (step 2): gray ones by the
  equality of the two channels of one eye on every pixel, others by the share of colour
  samples within 2 noise of their set."""
  spec = mixtures.get_mixture(name)
  if not spec.transmits_colour:
    pair = next(eye for eye in spec.eye_channels if len(eye) == 2)
    same = np.abs(small[..., pair[0]] - small[..., pair[1]]) <= 255.0 * config.noise / 2
    return bool(same.mean() >= config.singular_share)
  inside = _fit(obs, name) <= config.noise ** 2
  return bool(inside.mean() >= config.plane_share)


def _softmax(values: Dict[str, float], scale: float) -> Dict[str, float]:
  top = max(values.values())
  weights = {k: np.exp(scale * (v - top)) for k, v in values.items()}
  total = sum(weights.values())
  return {k: float(v / total) for k, v in weights.items()}


def detect(image: np.ndarray, config: DetectConfig = DetectConfig()) -> Detection:
  """The anaglyph encoding of an [H, W, 3] RGB image (uint8, or float in [0, 1])."""
  small = _small(image, config.width)
  if min(small.shape[:2]) < 16:
    raise ValueError(f'detect needs an image of at least 16x16 px after downsampling to '
                     f'{config.width} px wide; got {small.shape[1]}x{small.shape[0]}.')
  families = family_scores(small, config)
  scores = {f'family:{k}': round(v, 4) for k, v in families.items()}
  family = max(families, key=families.get)
  runner_up = max(v for k, v in families.items() if k != family)
  margin = min(families[family] - config.min_family_score, families[family] - runner_up)
  family_confidence = float(1.0 / (1.0 + np.exp(-margin / config.family_softness)))
  if families[family] < config.min_family_score:
    return Detection(None, 1.0 - family_confidence,
                     f'no colour channel is displaced against the others (best family '
                     f'{family}: {families[family]:.3f} < {config.min_family_score})', scores)
  obs = colour_samples(small, FAMILY_ODD_CHANNEL[family], config)
  names = [n for n in CANDIDATES if mixtures.get_mixture(n).family == family]
  singular = [n for n in names if np.linalg.matrix_rank(_matrix(n), tol=1e-3) < 3]
  fitting = [n for n in singular if fits_singular(small, obs, n, config)]
  if fitting:  # The lowest rank that fits: gray before optimized.
    best = min(fitting, key=lambda n: np.linalg.matrix_rank(_matrix(n), tol=1e-3))
    posterior = {n: float(n == best) for n in names}
  elif len(obs) < 50:
    full = [n for n in names if n not in singular]
    posterior = {n: 1.0 / len(full) for n in full}
  else:
    posterior = _softmax({n: log_likelihood(obs, n) for n in names
                          if n not in singular}, config.evidence)
  scores.update({n: round(p, 4) for n, p in posterior.items()})
  name = max(posterior, key=posterior.get)
  return Detection(name, family_confidence * posterior[name],
                   f'{family} channels displaced (score {families[family]:.3f}); '
                   f'{len(obs)} colour samples fit {name} best', scores)
