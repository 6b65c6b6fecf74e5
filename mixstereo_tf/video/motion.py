"""The camera's motion between consecutive frames, so that a disparity prior follows it.

A video frame's prior is the previous frame's left disparity (`temporal.VideoState`), and
the matcher searches only narrow windows around it. Where the camera pans, the scene
moves across the frame by a few pixels a frame, and a prior left in place puts every
depth edge that many pixels off, outside the windows: on the 1280x720 benchmark clip
(a pan of 8 px a frame) the default's left view fell from 35.4 dB on the shot's first
frame to 29.5 dB twelve frames later (experiments/BENCHMARKS.md 38).

`translation` estimates the frame-to-frame translation by phase correlation of gray,
area-reduced copies (`motion_copy`, at most `width` px wide; OpenCV's `phaseCorrelate`
with a Hann window), black bars at the frame's edges left out; `global_shift` takes it
where the correlation peaks at `min_response` or more (else no single translation
explains the change: a zoom, objects moving on their own, a flash; no shift).
`shift_map` moves the prior by it, whole pixels, NaN where the frame shows what the
previous one did not (there the matcher searches the valid prior's range nearby).
"""

import dataclasses
from typing import Optional, Tuple

import cv2
import numpy as np

from mixstereo_tf.core import image_range
from mixstereo_tf.core import planning_copies


@dataclasses.dataclass(frozen=True)
class MotionConfig:
  """How the prior follows the camera.

  Attributes:
    enabled: off: the prior stays where the previous frame had it.
    width: the gray copies are area-reduced to at most this width (one copy pixel is
      W / width frame pixels; the estimate is sub-pixel on the copy).
    min_response: the smallest phase-correlation peak (0..1) taken as a translation.
      Measured on 1280x720 frames of 36 images (`experiments/results/motion_response.md`):
      unrelated pairs peak at 0.02 (median) to 0.20; one moved by up to 30 px, blurred
      with noise of 8 levels, at 0.53 (a colour wheel without texture, 2.2 px off) to
      0.99; a 2% zoom at 0.66 or more, a 1-degree turn at 0.78 or more.
    border_level: rows and columns of the copies darker than this ([0, 1]) at the frame's
      edges are black bars, left out (their static edges pulled a pan of 8 px to 5-7 px
      on pillarboxed 1280x720 photo frames, one to (-1, 2)).
  """
  enabled: bool = True
  width: int = 320
  min_response: float = 0.3
  border_level: float = 0.06

  def __post_init__(self):
    if not (self.width >= 16 and 0.0 <= self.min_response < 1.0 and
            0.0 <= self.border_level < 1.0):
      raise ValueError(f'MotionConfig needs width >= 16, min_response and border_level in '
                       f'[0, 1); got {self}.')


def motion_copy(image: np.ndarray, width: int) -> np.ndarray:
  """float32 [h, w] gray copy of an [H, W, C] frame (uint8, uint16 or [0, 1] float; its
  channels averaged, [0, 1]), area-reduced to at most `width` px wide a frame
  (`planning_copies`; reduced first: a 720p frame in 2 ms, not the 19 ms of converting it
  whole)."""
  image = np.asarray(image)
  image = planning_copies.area_copy(image, width)
  gray = image_range.to_unit(image) if image.dtype.kind == 'u' else image
  gray = np.asarray(gray, np.float32)
  return np.ascontiguousarray(gray.mean(axis=-1) if gray.ndim == 3 else gray)


def translation(previous: np.ndarray, current: np.ndarray, frame_width: int,
                config: MotionConfig = MotionConfig()) -> Tuple[Tuple[float, float], float]:
  """((dx, dy) frame pixels, sub-pixel; the phase-correlation peak, 0..1) of two
  `motion_copy`s of one shape, their borders darker than config.border_level left out
  (`_content_box`); ((0, 0), 0) where nothing is left. The frame shows at (x, y) what the
  previous one showed at (x - dx, y - dy); frame_width: the frames' width, pixels (the
  copies' scale)."""
  scale = frame_width / previous.shape[1]
  box = _content_box(np.maximum(previous, current), config.border_level)
  if box is None:
    return (0.0, 0.0), 0.0
  previous, current = previous[box], current[box]
  window = cv2.createHanningWindow(previous.shape[::-1], cv2.CV_32F)
  # Windowed here: OpenCV's phaseCorrelate with a window multiplies its inputs in place.
  (dx, dy), peak = cv2.phaseCorrelate(previous * window, current * window)
  return (dx * scale, dy * scale), peak


def global_shift(previous: np.ndarray, current: np.ndarray, frame_width: int,
                 config: MotionConfig = MotionConfig()) -> Optional[Tuple[int, int]]:
  """`translation` in whole pixels; None where its peak is below config.min_response."""
  (dx, dy), peak = translation(previous, current, frame_width, config)
  if peak < config.min_response:
    return None
  return int(round(dx)), int(round(dy))


def _content_box(brightest: np.ndarray, level: float):
  """The (rows, columns) slices inside the frame's dark borders (letterbox or pillarbox
  bars: rows and columns whose brightest pixel stays below `level`, [0, 1]), which would
  pull the correlation towards no shift; None where less than a quarter is left."""
  rows = np.flatnonzero(brightest.max(axis=1) >= level)
  columns = np.flatnonzero(brightest.max(axis=0) >= level)
  if (rows.size < brightest.shape[0] // 4 or columns.size < brightest.shape[1] // 4 or
      min(rows[-1] - rows[0], columns[-1] - columns[0]) < 8):
    return None
  return np.s_[rows[0]:rows[-1] + 1, columns[0]:columns[-1] + 1]


def shift_map(values: np.ndarray, dx: int, dy: int) -> np.ndarray:
  """float32 copy of [H, W] `values` moved by (dx, dy): out[y, x] = values[y - dy, x - dx],
  NaN where that lies outside."""
  h, w = values.shape
  out = np.full((h, w), np.nan, np.float32)
  if abs(dx) >= w or abs(dy) >= h:
    return out
  out[max(0, dy):h + min(0, dy), max(0, dx):w + min(0, dx)] = \
      values[max(0, -dy):h - max(0, dy), max(0, -dx):w - max(0, dx)]
  return out
