"""Which anaglyph encoding made an image, from the image alone, with a confidence.

    found = detect(image)   # found.name: an encoding of CANDIDATES, or None
    found.confidence, found.reason, found.scores

An image with one empty channel is a two-channel anaglyph (red-blue, red-green) or none
(`two_channel`). Otherwise two questions, each answered by a physical property of the
encodings (`mixtures`):
  1. **Glasses (family).** An anaglyph's channels come from two views: the channels of one
     eye are aligned with each other, those of different eyes are displaced by the
     disparities. On a copy area-downsampled to DetectConfig.width px, every pair of
     channels is matched with the census matcher over +- reach_fraction of the width; a
     pair's *displacement* is the fraction of left-right consistent pixels with |d| >= 1.5.
     Family f (its odd channel: R for red-cyan, G for green-magenta, B for amber-blue)
     scores min(displacement of the odd channel against the other two) - displacement of
     the other two against each other. An ordinary photo, a gray photo or a diplopia image
     (every channel holds both views, aligned) scores ~0 for every family and is refused.
  2. **Variant (colour, gray, half-colour, optimized).** The odd channel is matched
     against the mean of the other two; the colours seen at consistent, smooth pixels
     choose the smallest encoding that explains them (`colour_sets`); colour is the
     fallback. Gray: the two channels of one eye equal on singular_share of the pixels.
     A colour anaglyph of a scene without saturated colours lies inside the half-colour
     sets as well and is reported as half-colour.
  3. **Dubois ghosts.** Dubois matrices leak a little of the odd eye into the other
     channels (red-cyan: G gets -0.094 of the left view). Regressing the high-passed other
     channels at a right pixel on the high-passed odd channel at the matching left pixel and
     at the same pixel, the second coefficient is that leak (0 for colour, gray,
     half-colour; `dubois_leak`). Its projection on a Dubois encoding's expected leak, as
     a fraction of it, chooses the Dubois encoding at >= ghost_fraction and rules it
     out below; the colour samples then choose among the others. The leak is a pixel-scale
     signal: it is measured on its own copy, up to DetectConfig.ghost_width px wide and
     at most half the image's width: JPEG and video (4:2:0) keep colour at half the
     width, and above it every channel's detail is the luma's, which mixes both eyes.
Confidence: the family's margin through a logistic, times the variant's: the explained
share's distance to its threshold through a logistic of scale share_softness (1 for gray),
and for a decision read from the ghost, the leak's distance to ghost_fraction through one
of scale ghost_softness. Dubois red-cyan images are reported as 'dubois_ffmpeg': the two
Dubois matrices of `mixtures` differ by < 0.03 per coefficient, which an image cannot tell
apart.
"""

import dataclasses
from typing import Dict, Optional, Tuple

import numpy as np

from mixstereo_tf.core import mixtures
from mixstereo_tf.core import planning_copies
from mixstereo_tf.core import workers
from mixstereo_tf.restoration import dubois_leak
from mixstereo_tf.unmixing import channel_matching
from mixstereo_tf.unmixing import colour_sets
from mixstereo_tf.unmixing import margins
from mixstereo_tf.unmixing import two_channel

# The channel each family's odd eye owns (red-cyan: R alone is the left eye).
FAMILY_ODD_CHANNEL = {'red_cyan': 0, 'green_magenta': 1, 'amber_blue': 2}
CANDIDATES = tuple(name for name in mixtures.ANAGLYPH_NAMES if name != 'dubois')
_PAIRS = ((0, 1), (0, 2), (1, 2))


@dataclasses.dataclass(frozen=True)
class DetectConfig:
  """Parameters of `detect` (module docstring); chosen on training scenes.

  Attributes:
    width: the analysed copy's width, pixels (a frame's: `planning_copies`).
    reach_fraction: channels are matched over +- this fraction of that width.
    min_family_score: below this family score the image is not an anaglyph.
    family_softness: the logistic's scale on the family margin.
    noise: the colour residual's standard deviation, [0, 1] units.
    singular_share: a gray encoding is chosen when this share of pixels has the two
      channels of one eye equal within noise / 2 ...
    gray_blur: ... on a copy box-blurred over this many pixels (1 before; the three
      gray_ fields are for 4:2:0 images, JPEG and video: `DESIGN.md`) ...
    gray_relative: ... or within this fraction of the detail of the odd channel's
      difference from the others (`colour_sets.gray_tolerance`; 0 before) ...
    gray_detail: ... that detail being the difference minus its box blur over this many
      pixels ...
    outside_penalty: ... another smaller encoding by its share of colour samples outside
      it, each costing this many nats (step 2).
    share_softness: the logistic's scale on the explained share's margin.
    samples: at most this many colour samples.
    ghost_width: the ghost regression's copy is area-downsampled to at most this width
      (matched anew there): 960 (320 before), chosen on FFmpeg anaglyphs of training photo
      warps, where the colour encodings' leak reached 0.60 / 0.43 / 0.40 / 0.21 of the
      expected at 320 / 480 / 640 / 960 px (DESIGN.md, unmixing: the misreads) ...
    ghost_max_fraction: ... and to at most this fraction of the image's width (1 before):
      4:2:0 images keep colour at half the width (DESIGN.md, unmixing: stored images).
    ghost_sigma: the Gaussian high-pass of the ghost regression, pixels of its copy.
    ghost_correlation: ... over pixels matched with at least this correlation ...
    ghost_min_shift: ... at least this many pixels of displacement ...
    ghost_collinearity: ... and regressors correlated by less than this (`dubois_leak`).
    ghost_fraction: a Dubois encoding is chosen when at least this fraction of its
      expected leak is observed.
    ghost_softness: the logistic's scale on the leak's distance to ghost_fraction: 0.08,
      the standard deviation of the colour encodings' leaks above (0.083; a Dubois
      decision claimed confidence 1 before, whatever its leak).
    doubtful_family_score: a family score above min_family_score but below this is
      reported as a doubt (`Detection.doubt`): photographs with saturated colours reach
      up to 0.13 (8 of 36 photographs x 3 storages accepted, all as amber-blue;
      GreenMeadow 0.128) where FFmpeg anaglyphs score a median 0.53-0.71; the doubt falls
      on all 8 and on 4 / 17 / 21 of 279 / 266 / 263 accepted anaglyphs (png / jpeg /
      h264; `experiments/results/detection_photos.md`, before the two-channel check,
      which now refuses one of the 8: Blinds, its blue almost black).
    min_brightness: an image whose brightest channel's 99th percentile is below this
      (0..1) is too dark to tell (no encoding named): the frames of a fade from black,
      whose colours lie under the codec's noise, read as gray with confidence 1 (a colour
      video that faded in was unmixed gray throughout). 0.15: a fade's frames read so up
      to 13% of the picture's brightness, and from 20% on as the picture does.
  """
  width: int = 320
  reach_fraction: float = 0.2
  min_family_score: float = 0.08
  family_softness: float = 0.03
  noise: float = 0.025
  singular_share: float = 0.9
  gray_blur: int = 5
  gray_relative: float = 0.35
  gray_detail: int = 15
  outside_penalty: float = 40.0
  share_softness: float = 0.01
  samples: int = 20000
  ghost_width: int = 960
  ghost_max_fraction: float = 0.5
  ghost_sigma: float = 2.0
  ghost_correlation: float = 0.85
  ghost_min_shift: int = 3
  ghost_collinearity: float = 0.3
  ghost_fraction: float = 0.3
  ghost_softness: float = 0.08
  doubtful_family_score: float = 0.15
  min_brightness: float = 0.15


@dataclasses.dataclass(frozen=True)
class Detection:
  """What `detect` found.

  Attributes:
    name: the encoding (of CANDIDATES), or None when the image is not an anaglyph.
    confidence: in [0, 1]: of `name`, or that the image is no anaglyph when name is None.
    reason: one line saying why.
    scores: family scores ('family:<name>'), Dubois leaks ('ghost:<name>', as a fraction
      of the expected) and explained shares (encoding names).
    also_fits: the family's colour encoding when a smaller set (half-colour, optimized)
      was chosen: the colour encoding explains every image, so it fits as well.
    doubt: why an ordinary photograph might read so, when the family's channels are
      displaced only weakly (`DetectConfig.doubtful_family_score`); None otherwise.
  """
  name: Optional[str]
  confidence: float
  reason: str
  scores: Dict[str, float]
  also_fits: Optional[str] = None
  doubt: Optional[str] = None


def family_scores(small: np.ndarray, config: DetectConfig) -> Dict[str, float]:
  """{family: score} (step 1 of the module docstring) of a 0..255 image."""
  search = channel_matching.span(small, config.reach_fraction)
  match_pair = lambda pair: channel_matching.match(small[..., pair[0]], small[..., pair[1]],
                                                   search)
  # The pairs in threads: each match is one strip (the same result on any machine) and
  # numba releases the GIL.
  outs = workers.run_tasks(match_pair, _PAIRS, len(_PAIRS))
  displaced = {pair: channel_matching.displaced_share(out) for pair, out in zip(_PAIRS, outs)}
  scores = {}
  for family, odd in FAMILY_ODD_CHANNEL.items():
    others = tuple(c for c in range(3) if c != odd)
    cross = min(displaced[tuple(sorted((odd, o)))] for o in others)
    scores[family] = cross - displaced[others]
  return scores


def ghost_leak(image: np.ndarray, small: np.ndarray, odd: int,
               matched: channel_matching.Matched, config: DetectConfig) -> np.ndarray:
  """`dubois_leak.observed` (step 3) on a copy of `image` at most config.ghost_width px
  and config.ghost_max_fraction of the image's width wide (a frame's: `planning_copies`
  copies a panorama as a row of frames), its eyes matched anew there
  (in 2 strips) over the dense range of `matched`'s disparities scaled to it
  (`channel_matching.rescaled_search`); on `small` and its `matched` pixels when that
  copy is no wider."""
  wide = channel_matching.downsampled(
      image, min(config.ghost_width,
                 int(planning_copies.frame_width(image.shape) * config.ghost_max_fraction)))
  if wide.shape[1] > small.shape[1]:
    search = channel_matching.rescaled_search(
        matched, channel_matching.span(small, config.reach_fraction),
        wide.shape[1] / small.shape[1], wide.shape[1])
    small, matched = wide, channel_matching.eye_match(wide, odd, search, strips=2)
  return dubois_leak.observed(small, odd, matched, config.ghost_sigma,
                              config.ghost_correlation, config.ghost_min_shift,
                              config.ghost_collinearity)


def _doubt(family: str, score: float, config: DetectConfig) -> Optional[str]:
  """`Detection.doubt` of an accepted family of score `score`."""
  if score >= config.doubtful_family_score:
    return None
  return (f'its {family} channels are displaced only weakly (score {score:.3f} < '
          f'{config.doubtful_family_score}), as in some photographs with saturated colours')


def _copies(image: np.ndarray, config: DetectConfig) -> Tuple[np.ndarray, np.ndarray]:
  """(the image within its content box, its 0..255 copy config.width px a frame)."""
  if np.ndim(image) == 3 and np.size(image):  # Else `downsampled` says what is wrong.
    top, bottom, left, right = margins.content_box(image)
    image = image[top:bottom, left:right]
  small = channel_matching.downsampled(image, config.width)
  if min(small.shape[:2]) < 16:
    raise ValueError(f'detect needs an image of at least 16x16 px after downsampling to '
                     f'{config.width} px a frame; got {small.shape[1]}x{small.shape[0]}.')
  return image, small


def _too_dark(small: np.ndarray, config: DetectConfig) -> Optional[Detection]:
  """No encoding named where the copy is too dark to tell (config.min_brightness)."""
  brightness = float(np.percentile(small.max(axis=-1), 99.0)) / 255.0
  if brightness >= config.min_brightness:
    return None
  return Detection(None, 0.0, f'too dark to tell its encoding (99% of the pixels below '
                   f'{brightness:.2f} of full scale, < {config.min_brightness})',
                   {'brightness': round(brightness, 3)})


def _two_channel(small: np.ndarray, config: DetectConfig) -> Optional[Detection]:
  """A red-blue or red-green anaglyph (`two_channel`), or an image with an empty channel
  whose other two are not displaced (no anaglyph); None where no channel is empty."""
  found = two_channel.detect(small, config.reach_fraction, config.min_family_score,
                             config.family_softness)
  return None if found is None else Detection(*found, {})


def detect(image: np.ndarray, config: DetectConfig = DetectConfig()) -> Detection:
  """The anaglyph encoding of an [H, W, 3] RGB image (uint8, or float in [0, 1]); uniform
  margins (letterbox bars, a frame, a border) are left out (`margins.content_box`)."""
  image, small = _copies(image, config)
  first = _too_dark(small, config) or _two_channel(small, config)
  if first is not None:
    return first
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
  odd = FAMILY_ODD_CHANNEL[family]
  matched = channel_matching.eye_match(small, odd,
                                       channel_matching.span(small, config.reach_fraction))
  obs = colour_sets.colour_samples(small, odd, matched, config)
  names = [n for n in CANDIDATES if mixtures.get_mixture(n).family == family]
  gray = {n: colour_sets.explained_share(small, obs, n, config) for n in names
          if not mixtures.get_mixture(n).transmits_colour}
  scores.update({n: round(v, 4) for n, v in gray.items()})
  ghost = ghost_leak(image, small, odd, matched, config)
  expected = {n: dubois_leak.expected(n, odd) for n in names}
  leaky = {n: float(ghost @ e / (e @ e)) for n, e in expected.items() if np.abs(e).max() > 0.01}
  scores.update({f'ghost:{n}': round(t, 3) for n, t in leaky.items()})
  fitting = [n for n, share in gray.items() if share >= colour_sets.needed_share(n, config)]
  also_fits = None
  if fitting:  # Equal channels are the surest sign; a leak is measured less surely.
    name, variant_confidence = fitting[0], 1.0
  else:
    if any(t >= config.ghost_fraction for t in leaky.values()):
      names = [max(leaky, key=leaky.get)]
    else:
      names = [n for n in names if n not in leaky and n not in gray]
    name, variant_confidence, shares = colour_sets.choose_variant(small, obs, names, config)
    if leaky:
      variant_confidence *= colour_sets.logistic(abs(max(leaky.values()) - config.ghost_fraction)
                                      / config.ghost_softness)
    scores.update({n: round(v, 4) for n, v in shares.items()})
    largest = max(names, key=colour_sets.size)
    also_fits = largest if name != largest else None
  return Detection(name, family_confidence * variant_confidence,
                   f'{family} channels displaced (score {families[family]:.3f}); '
                   f'{len(obs)} colour samples: {name} is the smallest encoding that '
                   'explains them', scores, also_fits,
                   _doubt(family, families[family], config))
