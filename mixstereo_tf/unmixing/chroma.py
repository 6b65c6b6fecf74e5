"""Anaglyphs stored with their colour at half resolution (4:2:0 / 4:2:2 JPEG, lossy WebP,
most video): matched without the detail only the luminance keeps.

Such a file stores one luminance Y at full resolution and the colour differences at half
the width. Above the colour's resolution every channel of the decoded image carries the
same detail, that of Y, which mixes both eyes (a red-cyan anaglyph: 0.299 of the left
eye's red, 0.701 of the right eye's green and blue) and so matches at disparity 0. On the
Motorcycle colour anaglyph saved by Pillow at quality 90 (4:2:0) the default method's
median disparity fell from 40.9 to 22.2 px (truth 38.7) and bad-3 rose from 11.5% to
33.5%. Matching a copy reduced to the colour's resolution and enlarged back gives a median
of 39.1 px and bad-3 20.9% there (the classical method: 19.6 -> 36.4 px, 44.1 -> 25.8%);
on the lossless anaglyph the same copy costs 2-3 points of bad-3, so it is used only for
files known to be stored so (`image_io.chroma_halved`, `hints.FrameHint.chroma_halved`). The
stage then restores its views from the stored image (`hints.FrameHint.stored_image`) with
those disparities (the copy's own views as a prior were worse there: 24.66 / 25.54 dB
against 24.75 / 26.45; the solve on the stored image gave 24.50 / 26.12).
"""

import cv2
import numpy as np


def colour_resolution_copy(image: np.ndarray) -> np.ndarray:
  """uint8 [H, W, 3] `image` area-reduced to half size and enlarged back (bilinear): the
  detail a half-resolution colour stores, at full size."""
  height, width = image.shape[:2]
  if min(height, width) < 4:
    return image
  small = cv2.resize(image, (max(1, width // 2), max(1, height // 2)),
                     interpolation=cv2.INTER_AREA)
  return cv2.resize(small, (width, height), interpolation=cv2.INTER_LINEAR)

