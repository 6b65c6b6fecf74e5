"""A peer baseline: OpenCV's StereoSGBM on an anaglyph's eye channels, untuned.

The left eye's channel(s) are matched against the mean of the right eye's channels
(`MixtureSpec.eye_channels`: red against mean(green, blue) for red-cyan), both as 8-bit
images, by `cv2.StereoSGBM` with OpenCV's documented smoothness recipe (block size 5,
P1 = 8 * 5^2, P2 = 32 * 5^2 for one channel) and every other parameter at OpenCV's default:
no tuning for cross-channel matching, which is what this baseline measures.

Units and signs: disparities are pixels of the input, signed, the project's convention
(a left-view pixel at column x matches the right view at column x - d_L; a right-view pixel
at column x matches the left view at x + d_R), which is also OpenCV's. SGBM's output is
sixteen times the disparity; pixels it leaves invalid (below minDisparity) are filled from
the nearest valid pixel to their left on the row (the first valid one to the right where
there is none on the left; the median of the image where a whole row is invalid).
"""

from typing import Tuple

import cv2
import numpy as np

from mixstereo_tf.classical import anaglyph
from mixstereo_tf.core import image_range

BLOCK_SIZE = 5
# OpenCV's documented P1 / P2 recipe for a one-channel image: 8 and 32 x channels x block^2.
P1 = 8 * BLOCK_SIZE ** 2
P2 = 32 * BLOCK_SIZE ** 2


def eye_pair(mixture, mixture_name: str) -> Tuple[np.ndarray, np.ndarray]:
  """(left-eye image, right-eye image), uint8 [H, W]: the mean of each eye's channels.

  Args:
    mixture: uint8 [H, W, 3] anaglyph, or float in [0, 1].
    mixture_name: an anaglyph encoding of `mixtures.ANAGLYPH_NAMES`.
  """
  left, right = anaglyph.eye_images(image_range.as_unit_float(mixture, 'mixture'),
                                    mixture_name)
  to_u8 = lambda eye: np.clip(np.rint(eye.mean(axis=-1)), 0, 255).astype(np.uint8)
  return to_u8(left), to_u8(right)


def sgbm_levels(min_disparity: int, max_disparity: int) -> Tuple[int, int]:
  """(minDisparity, numDisparities) covering [min, max]: a multiple of 16 levels."""
  if not min_disparity < max_disparity:
    raise ValueError(f'SGBM needs min < max disparity, got ({min_disparity}, '
                     f'{max_disparity}).')
  count = max_disparity - min_disparity + 1
  return int(min_disparity), int(-(-count // 16) * 16)


def fill_from_left(disparity: np.ndarray, valid: np.ndarray) -> np.ndarray:
  """`disparity` with each invalid pixel set to the nearest valid one to its left on the
  row, or the first valid one to its right where there is none on the left; rows with no
  valid pixel get the median of the valid pixels (0 where there are none)."""
  height, width = disparity.shape
  columns = np.broadcast_to(np.arange(width), (height, width))
  last = np.maximum.accumulate(np.where(valid, columns, -1), axis=1)
  following = np.minimum.accumulate(np.where(valid, columns, width)[:, ::-1], axis=1)[:, ::-1]
  source = np.where(last >= 0, last, following)
  rows = np.arange(height)[:, None]
  filled = disparity[rows, np.minimum(source, width - 1)]
  empty = ~valid.any(axis=1)
  if empty.any():
    filled[empty] = np.median(disparity[valid]) if valid.any() else 0.0
  return filled.astype(np.float32)


def match(left_u8: np.ndarray, right_u8: np.ndarray, min_disparity: int,
          max_disparity: int) -> Tuple[np.ndarray, np.ndarray]:
  """StereoSGBM's left disparity of a pair of 8-bit images, holes filled.

  Args:
    left_u8, right_u8: uint8 [H, W] images.
    min_disparity, max_disparity: the signed range to search, pixels (SGBM's level count
      is rounded up to a multiple of 16; what it finds beyond max is not kept).

  Returns:
    (disparity float32 [H, W], signed pixels within [min, max], left x matches right
    x - d; valid bool [H, W]: the pixels SGBM answered within [min, max] before the
    filling: answers beyond max, from the levels rounded up, are filled like holes).
  """
  low, levels = sgbm_levels(min_disparity, max_disparity)
  matcher = cv2.StereoSGBM.create(minDisparity=low, numDisparities=levels,
                                  blockSize=BLOCK_SIZE, P1=P1, P2=P2)
  raw = matcher.compute(np.ascontiguousarray(left_u8), np.ascontiguousarray(right_u8))
  valid = (raw >= low * 16) & (raw <= int(max_disparity) * 16)
  disparity = raw.astype(np.float32) / 16.0
  return fill_from_left(disparity, valid), valid


def match_anaglyph(mixture, mixture_name: str, min_disparity: int,
                   max_disparity: int) -> Tuple[np.ndarray, np.ndarray]:
  """(left, right) disparities of an anaglyph by SGBM on its eye images (`eye_pair`).

  The right disparity is SGBM's on the mirrored, swapped pair (the right eye's image
  flipped as the left, the left eye's flipped as the right), flipped back: same range and
  sign (a right-view pixel at x matches the left view at x + d_R).

  Returns:
    float32 [H, W] each, signed pixels.
  """
  left, right = eye_pair(mixture, mixture_name)
  d_left, _ = match(left, right, min_disparity, max_disparity)
  mirrored, _ = match(right[:, ::-1], left[:, ::-1], min_disparity, max_disparity)
  return d_left, np.ascontiguousarray(mirrored[:, ::-1])
