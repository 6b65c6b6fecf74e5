"""An anaglyph's channels matched against each other on a reduced copy: what encoding
detection (`detection`) measures its displacements, colours and Dubois leak on.

    small = downsampled(image, 320)                  # float32 0..255, 320 px a frame
    ys, xs, xr = eye_match(small, 0, span(small, 0.2))  # red's pixels and their matches

The census matcher (`classical.matcher`) compares each pixel only with its own
neighbourhood, so channels of one view that respond differently to the same surface still
match; channels of different views are displaced by the disparities.
"""

from typing import Tuple

import numpy as np

from mixstereo_tf.classical import matcher
from mixstereo_tf.core import planning_copies

Matched = Tuple[np.ndarray, np.ndarray, np.ndarray]


def downsampled(image: np.ndarray, width: int) -> np.ndarray:
  """float32 [h, w, 3] on 0..255 of an RGB image (uint8, or float in [0, 1]),
  area-downsampled to at most `width` columns a frame (`planning_copies`: a panorama wider
  than 4 : 1 keeps more).

  Raises:
    ValueError: an image that is not [H, W, 3].
  """
  image = np.asarray(image)
  if image.ndim != 3 or image.shape[2] != 3:
    raise ValueError(f'detect needs an [H, W, 3] RGB image, got shape {image.shape}.')
  image = image.astype(np.float32) * (1.0 if image.dtype == np.uint8 else 255.0)
  return np.ascontiguousarray(planning_copies.area_copy(image, width))


def span(small: np.ndarray, fraction: float) -> Tuple[int, int]:
  """(-r, r): disparities within `fraction` of the copy's frame width (at least 2 px)."""
  reach = max(2, planning_copies.reach(small.shape, fraction))
  return -reach, reach


def match(a: np.ndarray, b: np.ndarray, search: Tuple[int, int], strips: int = 1) -> dict:
  """`matcher.match` of [h, w] channels over `search` (min, max) px in `strips` strips, one
  thread each: the same result on any machine."""
  return matcher.match(a, b, *search, matcher.MatcherConfig(threads=strips, strips=strips))


def displaced_share(out: dict) -> float:
  """The share of pixels of a `match` output that are left-right consistent and displaced
  by 1.5 px or more: how far two channels are from showing one view."""
  return float((out['consistent_left'] & (np.abs(out['disparity_left']) >= 1.5)).mean())


def eye_match(small: np.ndarray, odd: int, search: Tuple[int, int],
              strips: int = 1) -> Matched:
  """(ys, xs, xr): the odd channel's left-right consistent pixels (y, x) and the columns
  xr = x - d where the mean of the other channels sees the same surface, d searched over
  `search` (`match`)."""
  others = [c for c in range(3) if c != odd]
  out = match(small[..., odd], small[..., others].mean(axis=2), search, strips)
  ys, xs = np.nonzero(out['consistent_left'])
  xr = np.rint(xs - out['disparity_left'][ys, xs]).astype(int)
  keep = (xr >= 0) & (xr < small.shape[1])
  return ys[keep], xs[keep], xr[keep]


def rescaled_search(matched: Matched, search: Tuple[int, int], scale: float,
                    width: int) -> Tuple[int, int]:
  """The dense range of `matched`'s disparities (found over `search` on a copy) scaled
  `scale` times for a copy `width` px wide (`matcher.dense_range`, as the range planning)."""
  return matcher.dense_range(matched[1] - matched[2], search[1], scale, width)
