"""Per-pixel disparity search windows around a prior disparity map.

The matcher (`matcher.match`) searches pixel (y, x) over lo[y, x] + [0, widths[y, x]):
around the previous video frame's disparities (a temporal prior) or around a coarse
solution (coarse-to-fine), so windows are narrow on smooth surfaces and wide only along
depth edges and where the prior is missing.
"""

from typing import Tuple

import cv2
import numpy as np


def around_prior(prior: np.ndarray, min_disparity: int, max_disparity: int,
                       radius: int, spread: int,
                       missing_spread: int = 0) -> Tuple[np.ndarray, np.ndarray]:
  """Per-pixel search windows around a prior disparity map.

  Args:
    prior: float [H, W] disparities, pixels (signed, left-referenced); NaN where there is
      no prior (e.g. the previous frame's match failed the left-right check): those
      pixels search the [min, max] of the valid prior within `missing_spread` px widened
      by `radius`, or the whole [min_disparity, max_disparity] where there is none.
    min_disparity, max_disparity: the windows are clipped to this range.
    radius: pixels added on both sides.
    spread: the prior's [min, max] is taken over the (2 * spread + 1)^2 neighbourhood
      (edges replicated), so a depth edge misplaced by up to `spread` px keeps both sides.
    missing_spread: the neighbourhood radius for NaN pixels (used when > spread).

  Returns:
    (lo, widths): int32 [H, W]; pixel (y, x) searches lo + [0, widths), widths >= 1.
  """
  prior = np.asarray(prior, np.float32)
  missing = np.isnan(prior)
  low, high = (np.where(missing, fill, prior) for fill in (np.inf, -np.inf))
  if spread > 0:  # NaN neighbours count neither in the min nor in the max.
    kernel = np.ones((2 * spread + 1, 2 * spread + 1), np.uint8)
    low = cv2.erode(low, kernel, borderType=cv2.BORDER_REPLICATE)
    high = cv2.dilate(high, kernel, borderType=cv2.BORDER_REPLICATE)
  if missing.any() and missing_spread > spread:
    # Missing pixels: the valid prior within missing_spread px (both sides of an edge).
    kernel = np.ones((2 * missing_spread + 1, 2 * missing_spread + 1), np.uint8)
    low[missing] = cv2.erode(low, kernel, borderType=cv2.BORDER_REPLICATE)[missing]
    high[missing] = cv2.dilate(high, kernel, borderType=cv2.BORDER_REPLICATE)[missing]
  lo = np.clip(np.floor(low) - radius, min_disparity, max_disparity)
  hi = np.clip(np.ceil(high) + radius, min_disparity, max_disparity)
  unknown = ~np.isfinite(low) | ~np.isfinite(high)  # No valid prior near: everything.
  lo[unknown], hi[unknown] = min_disparity, max_disparity
  return lo.astype(np.int32), (hi - lo + 1).astype(np.int32)
