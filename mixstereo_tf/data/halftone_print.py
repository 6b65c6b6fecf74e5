"""A printed and scanned image, simulated: cyan, magenta and yellow ink in round dots on
screens at their own angles, rendered finer than the scan and area-averaged to its pixels.

    scan = halftone_print(image, period=5.0)  # uint8 RGB in, uint8 RGB out

The ink of a channel covers 1 - value of each cell, a round dot that grows until it fills
the cell (solid ink at 0; no black ink, no dot gain); screen angles
15 (cyan), 75 (magenta) and 0 degrees (yellow), as offset presses use. One of the two
halftone operators of `experiments/halftone.py` (the other is ImageMagick's ordered
dither), and the tests' known-answer prints (`classical.halftone`).
"""

from typing import Sequence

import cv2
import numpy as np

ANGLES = (15.0, 75.0, 0.0)  # Degrees of the cyan, magenta and yellow screens.


def _disc_in_cell(radius: np.ndarray) -> np.ndarray:
  """The area of a disc of `radius` (cells) centred in a unit cell, within the cell."""
  radius = np.minimum(radius, np.sqrt(0.5))
  corner = np.sqrt(np.maximum(radius ** 2 - 0.25, 0.0))  # Half chord beyond each side.
  cut = np.where(radius > 0.5, radius ** 2 * np.arccos(np.minimum(0.5 / np.maximum(
      radius, 1e-9), 1.0)) - 0.5 * corner, 0.0)
  return np.pi * radius ** 2 - 4.0 * cut


def halftone_print(image: np.ndarray, period: float, angles: Sequence[float] = ANGLES,
                   oversample: int = 3) -> np.ndarray:
  """uint8 RGB [H, W, 3] printed with screens of `period` pixels at `angles` (cyan,
  magenta, yellow), each dot's area in its cell its ink's coverage, rendered `oversample`
  times finer and area-averaged back (the scanner's pixels)."""
  height, width = image.shape[:2]
  fine = cv2.resize(image, (width * oversample, height * oversample),
                    interpolation=cv2.INTER_LINEAR).astype(np.float32) / 255.0
  yy, xx = np.mgrid[:height * oversample, :width * oversample].astype(np.float32)
  printed = np.empty_like(fine)
  for channel, angle in enumerate(angles):
    turn = np.deg2rad(angle)
    u = (xx * np.cos(turn) + yy * np.sin(turn)) / (period * oversample)
    v = (yy * np.cos(turn) - xx * np.sin(turn)) / (period * oversample)
    distance = np.hypot(u - np.round(u), v - np.round(v))  # To the cell's centre, in cells.
    # Inked where the disc through the point covers less of the cell than the ink's share.
    ink = 1.0 - fine[..., channel]
    printed[..., channel] = ~((_disc_in_cell(distance) < ink) | (ink >= 1.0))
  scan = cv2.resize(printed, (width, height), interpolation=cv2.INTER_AREA)
  return np.clip(np.round(scan * 255.0), 0, 255).astype(np.uint8)
