"""The disparity range of a double image from the image alone, before its matching.

`diplopia.unmix_diplopia` searches the range it is given; this plans one the way
`matcher.estimate_range` does for anaglyphs: a coarse self-matching of a small copy, the
lags its consistent matches crowd on, widened.
"""

import dataclasses
import math
from typing import Optional, Tuple

import cv2
import numpy as np

from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import diplopia_costs
from mixstereo_tf.classical import parallel_sgm
from mixstereo_tf.core import image_range
from mixstereo_tf.core import planning_copies

# The SGM penalties (P1, P2) of `estimate_range`, those its density threshold was chosen
# with: the matching's 16 / 160 left one of 16 validation double images with a bound
# below the true 99.5th percentile (0.98x), 8 / 64 none.
RANGE_PENALTIES = (8, 64)


def coarse_self_match(gray: np.ndarray, reach: int,
                      config: diplopia.DiplopiaConfig) -> dict:
  """`parallel_sgm.match_volume`'s output for the self-matching of float [h, w] `gray` (a
  planning copy, 0-255) over lags [1, reach] with `RANGE_PENALTIES`, whatever `config`'s:
  the range estimate's matching, and the tilt check's (`echo_tilt.consistent_share`)."""
  config = dataclasses.replace(config, matching=dataclasses.replace(
      config.matching, min_disparity=1, max_disparity=reach, p1=RANGE_PENALTIES[0],
      p2=RANGE_PENALTIES[1]))
  return parallel_sgm.match_volume(diplopia_costs.self_matching_volume(gray, config),
                                   config.matching)


def estimate_range(mixture, config: Optional[diplopia.DiplopiaConfig] = None, width: int = 320,
                   fraction: float = 1 / 3, density: float = 0.02,
                   margin: int = 3) -> Tuple[int, int]:
  """The (positive) disparity range of a double image from the image alone.

  The self-matching of `diplopia`'s step 2 over lags [1, fraction * width] on a
  copy area-downsampled to `width` px (a frame's: `planning_copies`); among the left-right
  consistent disparities, those whose 5-lag window holds >= `density` of them (surfaces;
  false matches spread over the search), widened by `margin` px of the copy and scaled
  back (as `matcher.estimate_range` does for anaglyphs). `density` 2 %, not the
  anaglyphs' 1 %: a double image's self-matching leaves more false consistent matches; on
  12 photo-warp pairs (training data, 640 px wide, true maxima 67-85 px) the bound over
  the true 99.5th percentile had median 1.95x (up to 3.2x) at 1 % and 1.11x (0.93x-2.65x)
  at 2 %. The matching runs with `RANGE_PENALTIES`, whatever `config`'s.

  Returns:
    (min, max) ints with 1 <= min < max: the whole search when nothing is consistent.

  Raises:
    ValueError: an image smaller than the ZNCC window (`diplopia.check_size`).
  """
  config = config or diplopia.DiplopiaConfig()
  diplopia.check_size(np.shape(mixture), config)
  gray = diplopia_costs.gray_255(image_range.as_unit_float(mixture, 'mixture'))
  full_width = gray.shape[1]
  scale = max(1.0, planning_copies.frame_width(gray.shape) / width)
  if scale > 1.0:
    gray = cv2.resize(gray, (max(1, round(full_width / scale)),
                             max(1, round(gray.shape[0] / scale))), interpolation=cv2.INTER_AREA)
  reach = max(2, planning_copies.reach(gray.shape, fraction))
  matched = coarse_self_match(gray, reach, config)
  found = matched['disparity_left'][matched['consistent_left']]
  counts = np.histogram(found, bins=np.arange(1, reach + 2))[0]  # counts[i]: lag i + 1.
  share = np.convolve(counts, np.ones(5), 'same') / max(1, found.size)
  dense = np.nonzero((share >= density) & (counts > 0))[0] + 1
  low, high = (dense.min() - margin, dense.max() + margin) if dense.size else (1, reach)
  low = max(1, math.floor(low * scale))
  return low, max(low + 1, min(math.ceil(high * scale), full_width - 1))
