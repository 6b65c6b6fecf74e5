"""Step 2 of encoding detection (`detection`): which variant of a family made an anaglyph.

At a matched, smooth pixel the colour c of a surface is seen as o = [odd channel at x,
other channels at x - d]. Under encoding h (matrices A_L, A_R) o = clip(M_h c) with
M_h = A_L + A_R and c in [0, 1]^3: the colour encoding explains every o; gray (the two
channels of one eye equal), optimized (a plane) and half-colour (a slab 0.299 thick)
explain less. The smallest set that explains the samples wins (`choose_variant`).

`config` is a `detection.DetectConfig` (noise, singular_share, gray_blur, gray_relative,
gray_detail, outside_penalty, share_softness, samples). Images are float32 [h, w, 3] on
0..255 (the detection's copy).
"""

from typing import Dict, Sequence, Tuple

import cv2
import numpy as np

from mixstereo_tf.core import mixtures
from mixstereo_tf.unmixing import channel_matching


def logistic(value: float) -> float:
  """1 / (1 + exp(-value))."""
  return float(1.0 / (1.0 + np.exp(-value)))


def colour_samples(small: np.ndarray, odd: int, matched: channel_matching.Matched,
                   config) -> np.ndarray:
  """[N, 3] colours o in [0, 1]: the odd channel at x, the others at x - d, at matched
  pixels whose 3x3-blurred gradient is at most the image's median at both ends."""
  others = [c for c in range(3) if c != odd]
  smooth = cv2.blur(small, (3, 3)) / 255.0
  grad = sum(np.abs(cv2.Sobel(smooth[..., c], cv2.CV_32F, 1, 0)) +
             np.abs(cv2.Sobel(smooth[..., c], cv2.CV_32F, 0, 1)) for c in range(3))
  ys, xs, xr = matched
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


def residuals(obs: np.ndarray, name: str) -> np.ndarray:
  """Squared residuals [N] of colour samples against clip(M c), c in the unit box."""
  m, clip = _matrix(name), mixtures.get_mixture(name).clip
  c = np.clip(obs @ np.linalg.pinv(m).T, 0.0, 1.0)
  step = 1.0 / np.linalg.norm(m, 2) ** 2
  for _ in range(60):  # Projected gradient on |clip(M c) - o|^2 over the unit box.
    predicted = m @ c.T
    inside = ((predicted > 0) & (predicted < 1)) if clip else 1.0
    c = np.clip(c - step * ((np.clip(predicted, 0, 1) - obs.T) * inside).T @ m, 0.0, 1.0)
  return ((obs - np.clip(c @ m.T, 0.0, 1.0)) ** 2).sum(axis=1)


def gray_tolerance(detail: np.ndarray, config) -> float:
  """Grey levels within which a gray encoding's two channels of one eye count as equal:
  noise / 2, or config.gray_relative times the singular_share quantile of `detail` (the
  detail of the odd channel minus the mean of the other two: where the eyes' channels
  are displaced) when larger. 4:2:0 images (JPEG, every video) keep colour at half
  resolution and quantise it, so G - B, which holds chroma only, is off by several
  levels where the eyes' channels differ most; a colour encoding's G - B is the scene's
  own colour, not a fraction of that detail."""
  return max(255.0 * config.noise / 2,
             config.gray_relative * float(np.quantile(detail, config.singular_share)))


def explained_share(small: np.ndarray, obs: np.ndarray, name: str, config) -> float:
  """The share of the image a smaller encoding explains: gray ones, the pixels whose two
  channels of one eye are equal (`gray_tolerance`) on a copy box-blurred over
  config.gray_blur px; others, the colour samples within noise of their set."""
  spec = mixtures.get_mixture(name)
  if not spec.transmits_colour:
    pair = next(eye for eye in spec.eye_channels if len(eye) == 2)
    odd = next(c for c in range(3) if c not in pair)
    blurred = cv2.blur(small, (config.gray_blur, config.gray_blur))
    difference = np.abs(blurred[..., pair[0]] - blurred[..., pair[1]])
    contrast = blurred[..., odd] - (blurred[..., pair[0]] + blurred[..., pair[1]]) / 2
    detail = np.abs(contrast - cv2.blur(contrast, (config.gray_detail, config.gray_detail)))
    return float((difference <= gray_tolerance(detail, config)).mean())
  if len(obs) < 50:
    return 0.0
  return float((residuals(obs, name) <= config.noise ** 2).mean())


def size(name: str) -> Tuple[int, float]:
  """(rank, |det|) of an encoding's M: smaller sets first."""
  m = _matrix(name)
  return int(np.linalg.matrix_rank(m, tol=1e-3)), abs(float(np.linalg.det(m)))


def needed_share(name: str, config) -> float:
  """The share of the image a smaller encoding must explain to be chosen: for c uniform
  in the box a sample inside the set (within noise) is 1 / V times likelier than under
  colour (V = max(|det M|, 2 noise)), one outside costs config.outside_penalty nats."""
  if not mixtures.get_mixture(name).transmits_colour:
    return config.singular_share
  gain = -np.log(max(size(name)[1], 2.0 * config.noise))
  return 1.0 - gain / (gain + config.outside_penalty)


def choose_variant(small: np.ndarray, obs: np.ndarray, names: Sequence[str], config
                   ) -> Tuple[str, float, Dict[str, float]]:
  """(encoding, confidence, explained shares): the smallest of `names` (encodings that
  transmit colour) that explains the samples, else the largest. The confidence is the
  explained share's distance to its threshold through a logistic of scale
  config.share_softness."""
  ordered = sorted(names, key=size)
  shares, closest = {}, -np.inf
  for name in ordered[:-1]:
    shares[name] = explained_share(small, obs, name, config)
    margin = (shares[name] - needed_share(name, config)) / config.share_softness
    if margin >= 0:
      return name, logistic(margin), shares
    closest = max(closest, margin)
  return ordered[-1], logistic(-closest), shares
