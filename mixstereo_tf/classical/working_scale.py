"""Matching a large image on a reduced copy: the factor, the copy, and the way back.

A method tuned on images about a thousand pixels wide (windows, penalties, a disparity
range in pixels) sees a photograph four times as wide as four times finer texture and four
times larger disparities. `factor` picks the reduction that brings the width within
`max_width`, `reduce` makes the copy (area-averaged) with the disparity range and a prior
in its pixels, and `enlarge` brings the copy's disparities back to the full grid (bilinear,
times the width ratio). Disparities are horizontal, in pixels of the image they belong to.
"""

import dataclasses
import math
from typing import Optional, Tuple

import cv2
import numpy as np


@dataclasses.dataclass(frozen=True)
class Reduced:
  """A reduced copy: `image` [h, w, C]; `scale` = W / w (full pixels per copy pixel);
  `search` the (min, max) range in copy pixels; `prior` in copy pixels or None."""
  image: np.ndarray
  scale: float
  search: Tuple[int, int]
  prior: Optional[np.ndarray]


def factor(width: int, max_width: int) -> int:
  """The smallest whole reduction f >= 1 with ceil(width / f) <= max_width (1 when
  max_width is 0: no reduction)."""
  if max_width <= 0 or width <= max_width:
    return 1
  return math.ceil(width / max_width)


def reduce(image: np.ndarray, reduction: int, search: Tuple[int, int],
           prior: Optional[np.ndarray] = None) -> Reduced:
  """The copy reduced `reduction` times (sizes rounded up, `cv2.INTER_AREA`).

  Args:
    image: float [H, W, C].
    reduction: f >= 1.
    search: (min, max) disparities, full pixels, min >= 1; in the copy (floor(min / s)
      at least 1, ceil(max / s)) with s = W / w, kept at least one pixel wide.
    prior: float [H, W] disparities, full pixels (NaN: none there), or None; in the copy
      nearest-sampled and divided by s, NaN kept.
  """
  height, width = image.shape[:2]
  size = (-(-width // reduction), -(-height // reduction))  # (w, h), rounded up.
  small = cv2.resize(image, size, interpolation=cv2.INTER_AREA) if reduction > 1 else image
  scale = width / size[0]
  low = max(1, math.floor(search[0] / scale))
  high = max(low + 1, math.ceil(search[1] / scale))
  if prior is not None and reduction > 1:
    prior = cv2.resize(np.asarray(prior, np.float32), size,
                       interpolation=cv2.INTER_NEAREST) / np.float32(scale)
  return Reduced(small, scale, (low, high), prior)


def enlarge(disparity: np.ndarray, shape: Tuple[int, int], scale: float) -> np.ndarray:
  """float32 [H, W] = the copy's [h, w] disparities resized bilinearly to `shape` and
  multiplied by `scale` (the copy's pixels in full pixels); the same array when the
  shapes agree."""
  if disparity.shape == tuple(shape):
    return disparity
  big = cv2.resize(np.asarray(disparity, np.float32), (shape[1], shape[0]),
                   interpolation=cv2.INTER_LINEAR)
  big *= np.float32(scale)
  return big
