"""The learned matching stage of anaglyphs: learned descriptors, cosine costs, SGM.

For a colour anaglyph the classical matcher compares census codes of the left eye's channel
with those of the right eye's other channels, which doubles its errors against a gray
anaglyph of the same pair (experiments/results/same_channel.md). Here the eyes are matched
through learned descriptors (`models/matching_features.py`, one branch per eye):
  1. descriptors of both eyes from the mixture's eye channels;
  2. cost volume over the signed range: `census_weight` of the census matcher's cost (the
     eyes' census codes, `parallel_sgm.census_volume`) plus the rest of (1 - cosine) x
     `cost_scale` (`feature_costs.cosine_costs`), uint8;
  3. the numba SGM of a stored volume with the matcher's post-processing (median,
     left-right check, background-favouring fill; `parallel_sgm.match_cost_volume`);
  4. both views restored from the encoding's matrices and these disparities, as the
     classical method does (`Family.restore`).
Images whose volume would pass `max_cells` cells are matched at 1/f scale (f a power of 2,
area downsampling), and the upsampled result is the prior of the census matcher at full
scale, which then searches only windows of ceil(f) + 2 px around it (`matcher.match`).
A video frame with a prior (`hints.FrameHint.prior`) goes to the census matcher around it,
as in the classical method. `estimate_range` plans the range as the census matcher does
(`matcher.estimate_range`: a full search on a small copy, the dense consistent
disparities) with this stage's costs: on validation photo warps its colour-anaglyph
ranges are tighter (1.30x the true width on average, 1.77x at most, against census's 1.53x
and 3.61x) and cover more of the truth (99.7 against 99.1%). Intersecting it with the
census plan (`config.intersect_census_range`) is tighter still (1.17x) at the same bad-1,
but covers less (lowest 93.1 against 96.7%), and a range that cuts the truth costs far
more than a wide one: off. A 5 x 7 census window in the blend (`census_window`) lowered
the validation colour bad-1 from 27.5 to 25.5% with views +0.23 / -0.04 dB, but was mixed
on the evaluation scenes (docs/LEARNED_MATCHING.md): 7 x 9, the census matcher's, stays.
"""

import dataclasses
import math
from typing import Callable, Dict, Optional, Tuple

import cv2
import numpy as np
import tensorflow as tf

from mixstereo_tf.classical import anaglyph
from mixstereo_tf.classical import feature_costs
from mixstereo_tf.classical import matcher
from mixstereo_tf.classical import parallel_sgm
from mixstereo_tf.core import hints
from mixstereo_tf.core import image_range
from mixstereo_tf.models import matching_features
from mixstereo_tf.restoration import views
from mixstereo_tf.unmixing import families

_KEYS = ('left', 'right', 'disparity_left', 'disparity_right', 'consistent_left')
Descriptors = Callable[[tf.Tensor, tf.Tensor], Tuple[tf.Tensor, tf.Tensor]]


@dataclasses.dataclass(frozen=True)
class LearnedMatchConfig:
  """Parameters of the learned matching stage.

  Attributes:
    cost_scale: uint8 cost units per unit of 1 - cosine.
    census_weight: share of the census cost in the blended cost (0: learned cost only).
    p1, p2: SGM penalties, cost units.
    lr_threshold: largest accepted left-right difference, pixels.
    max_cells: above H * W * D cells the stage runs at a reduced scale (module docstring).
    intersect_census_range: `estimate_range` keeps the intersection of its plan and the
      census matcher's (its own plan where they do not overlap); off (module docstring).
    census_window: (height, width), odd, of the blended census cost (the census
      matcher's; 5 x 7 was tried, module docstring).
  """
  cost_scale: float = 32.0
  census_weight: float = 0.5
  p1: int = 12
  p2: int = 80
  lr_threshold: float = 1.0
  max_cells: int = 100_000_000
  intersect_census_range: bool = False
  census_window: Tuple[int, int] = (7, 9)

  def __post_init__(self):
    height, width = self.census_window
    if (not 0 < self.cost_scale <= 127 or not 0 < self.p1 <= self.p2 or
        self.max_cells <= 0 or not 0 <= self.census_weight < 1 or height % 2 == 0 or
        width % 2 == 0 or not 1 < height * width <= 65):
      raise ValueError(f'LearnedMatchConfig needs 0 < cost_scale <= 127, 0 < p1 <= p2, '
                       f'max_cells > 0, census_weight in [0, 1) and an odd census_window '
                       f'of 3 to 65 pixels; got {self}.')


def descriptor_function(model: matching_features.MatchingFeatures) -> Descriptors:
  """The model as a traced function of (single [1, H, W, 1], pair [1, H, W, 2])."""
  signature = [tf.TensorSpec([1, None, None, 1], tf.float32),
               tf.TensorSpec([1, None, None, 2], tf.float32)]
  return tf.function(lambda single, pair: model((single, pair)), input_signature=signature)


def _full_match(descriptors: Descriptors, mixture01: np.ndarray, name: str, low: int,
                high: int, config: LearnedMatchConfig, threads: int) -> dict:
  single, pair, single_is_left = matching_features.eye_inputs(mixture01, name)
  first, second = descriptors(tf.constant(single[None], tf.float32),
                              tf.constant(pair[None], tf.float32))
  left, right = (first, second) if single_is_left else (second, first)
  volume = feature_costs.cosine_costs(left[0].numpy(), right[0].numpy(), low,
                                      high - low + 1, config.cost_scale, threads=threads)
  if config.census_weight:
    census = parallel_sgm.census_volume(*anaglyph.eye_images(mixture01, name), low,
                                        high - low + 1, *config.census_window, threads)
    volume = feature_costs.blend(census, volume, config.census_weight, threads)
  return parallel_sgm.match_cost_volume(volume, low, config.p1, config.p2,
                                        config.lr_threshold)


def match(descriptors: Descriptors, mixture01: np.ndarray, name: str, low: int, high: int,
          config: LearnedMatchConfig = LearnedMatchConfig(),
          matching: matcher.MatcherConfig = matcher.MatcherConfig()) -> dict:
  """Left and right disparities of an anaglyph by the learned stage (steps 1-3).

  Args:
    descriptors: `descriptor_function` of a trained model.
    mixture01: float [H, W, 3] in [0, 1].
    name: its anaglyph encoding (eyes of one and two channels).
    low, high: inclusive signed range, pixels (clipped to |d| <= W - 1).
    config: the stage's parameters; matching: the census matcher's, for large images.

  Returns:
    As `matcher.match`.
  """
  h, w = mixture01.shape[:2]
  low, high = max(int(low), 1 - w), min(int(high), w - 1)
  if low >= high:
    raise ValueError(f'The disparity range [{low}, {high}] leaves no search in an image '
                     f'{w} px wide.')
  threads = matching.thread_count()
  factor = 1
  while h * w * (high - low + 1) > config.max_cells * factor ** 3 and min(h, w) / factor >= 64:
    factor *= 2
  if factor == 1:
    return _full_match(descriptors, mixture01, name, low, high, config, threads)
  small = cv2.resize(mixture01.astype(np.float32), (round(w / factor), round(h / factor)),
                     interpolation=cv2.INTER_AREA)
  scale = w / small.shape[1]
  coarse = _full_match(descriptors, small, name, math.floor(low / scale),
                       math.ceil(high / scale), config, threads)['disparity_left']
  prior = cv2.resize(coarse, (w, h), interpolation=cv2.INTER_LINEAR) * scale
  fine = dataclasses.replace(matching, prior_radius=math.ceil(scale) + 2,
                             prior_spread=math.ceil(scale) + 1)
  return matcher.match(*anaglyph.eye_images(mixture01, name), low, high, fine, prior)


def estimate_range(descriptors: Descriptors, image: np.ndarray, name: str,
                   matching: matcher.MatcherConfig = matcher.MatcherConfig(),
                   config: LearnedMatchConfig = LearnedMatchConfig()) -> Tuple[int, int]:
  """The signed disparity range of uint8 anaglyph `image` (module docstring): the stage's
  costs over +- matching.range_fraction of a copy matching.range_width px wide
  (`matcher.range_copy`), then `matcher.dense_range` of its consistent disparities; with
  config.intersect_census_range, intersected with `matcher.estimate_range` of the eyes."""
  mixture01 = image_range.u8_to_unit(image).astype(np.float32)
  (small,), scale, reach = matcher.range_copy((mixture01,), matching)
  out = _full_match(descriptors, small, name, -reach, reach, config, matching.thread_count())
  low, high = matcher.dense_range(out['disparity_left'][out['consistent_left']], reach,
                                  scale, image.shape[1], matching)
  if not config.intersect_census_range:
    return low, high
  census_low, census_high = matcher.estimate_range(*anaglyph.eye_images(mixture01, name),
                                                   matching)
  both = max(low, census_low), min(high, census_high)
  return both if both[0] < both[1] else (low, high)


def learned_unmix(descriptors: Descriptors, image: np.ndarray, name: str,
                  search: Tuple[int, int], hint: Optional[hints.FrameHint] = None,
                  config: LearnedMatchConfig = LearnedMatchConfig()) -> Dict[str, object]:
  """The stage on a uint8 anaglyph (steps 1-4): `steps.classical_unmix`'s outputs; the
  hint's on_disparity told the disparities before the views are restored (a video's
  next frame starts then, `video.frame_pipeline`)."""
  family = families.of(name)
  if hint is not None and hint.prior is not None:
    out = family.classical(image, name, search, hint)
    return {key: out[key] for key in _KEYS}
  mixture01 = image_range.u8_to_unit(image)
  matched = match(descriptors, mixture01, name, *search, config, family.matching(hint))
  if hint is not None and hint.on_disparity is not None:
    hint.on_disparity({key: matched[key] for key in _KEYS[2:]})
  views_from = hints.views_image(image, hint)
  restored = family.restore(image_range.to_unit(views_from), name, matched['disparity_left'],
                            matched['disparity_right'])
  return {**views.at_depth(restored, views_from.dtype),  # As _KEYS.
          'disparity_left': matched['disparity_left'],
          'disparity_right': matched['disparity_right'],
          'consistent_left': matched['consistent_left']}
