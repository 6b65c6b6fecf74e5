"""The reduced copies that plan the work: encoding detection, eye order, disparity ranges,
a double image's self-matching and a video's camera motion each look at an area-reduced
copy of the image some `width` pixels wide, and search a fraction of that width.

A frame's disparities grow with its size; a panorama, or a strip cut from a frame, is wider
without larger disparities: a 12000 x 800 px panorama shows the depths of 1200 x 800 px
frames ten times over. Its copy 320 px wide was 21 px high (detection refused thinner ones),
and a search over a third of that width reached 4000 px of the panorama. So copies are
sized by the *frame width*, at most WIDEST_ASPECT times the height: a panorama is planned as
a row of frames of that aspect, each copied `width` px wide, and searches reach a fraction
of one frame. Images up to WIDEST_ASPECT : 1 (KITTI's 3.3 : 1 among them) are copied and
searched exactly as before (`frame_width` is then their width).

    size = copy_size(image.shape, 320)     # (w, h), cv2's order
    small = area_copy(image, 320)          # the image itself where nothing is reduced
    r = reach(small.shape, 1 / 3)          # pixels of the copy
"""

from typing import Sequence, Tuple

import cv2
import numpy as np

# The widest frame, width / height, whose disparities scale with its width: wider images are
# rows of such frames. 4: above the widest frames the methods were tuned and judged on
# (KITTI, 3.3) and the cinema's (2.76), below panoramas (a 360-degree one is 6-20).
WIDEST_ASPECT = 4.0


def frame_width(shape: Sequence[int]) -> int:
  """min(W, round(WIDEST_ASPECT * H)) of an [H, W, ...] shape, pixels: the width whose
  fractions bound its disparities."""
  return max(1, min(int(shape[1]), round(WIDEST_ASPECT * int(shape[0]))))


def copy_size(shape: Sequence[int], width: int) -> Tuple[int, int]:
  """(w, h), cv2's order: an [H, W, ...] shape reduced by frame_width / `width`, or as it
  is where its frame width is at most `width` (at most `width` px wide for images up to
  WIDEST_ASPECT : 1; sizes rounded, at least 1)."""
  height, full = int(shape[0]), int(shape[1])
  frame = frame_width(shape)
  if frame <= width:
    return full, height
  return max(1, round(full * width / frame)), max(1, round(height * width / frame))


def area_copy(image: np.ndarray, width: int) -> np.ndarray:
  """`image` [H, W, ...] area-averaged (cv2.INTER_AREA) to `copy_size`; itself where that
  is its size."""
  size = copy_size(image.shape, width)
  if size == (image.shape[1], image.shape[0]):
    return image
  return cv2.resize(image, size, interpolation=cv2.INTER_AREA)


def reach(shape: Sequence[int], fraction: float) -> int:
  """round(fraction * frame_width(shape)): a search's reach, pixels of that shape."""
  return round(fraction * frame_width(shape))
