"""An image without its uniform margins: what encoding detection (`detection`) looks at.

Letterbox or pillarbox bars, a white frame, and the gray surroundings of a screenshot
(a page, a viewer) hold no colour of either eye; their neutral colour fits every colour
set, so a colour anaglyph inside them read as half-colour.
"""

from typing import Tuple

import numpy as np

# A margin row or column is uniform when no channel varies along it by more than this share
# of full scale (JPEG noise on a flat bar stays within it).
MARGIN_TOLERANCE = 0.05
# Within the margins, the rows and columns at the edges with fewer than COLOUR_SHARE of
# their pixels coloured (channels spread by more than MARGIN_TOLERANCE of full scale) are
# left out too: gray surroundings with text (a screenshot of a page or a viewer).
COLOUR_SHARE = 0.05


def content_box(image: np.ndarray) -> Tuple[int, int, int, int]:
  """(top, bottom, left, right) of `image` [H, W, 3] without its uniform margins: the rows
  and columns at its edges along which no channel varies by more than MARGIN_TOLERANCE of
  full scale (letterbox or pillarbox bars, a white frame). Their neutral colour fits every
  colour set, so a colour anaglyph inside them read as half-colour. The whole image when
  fewer than 16 rows or columns would remain. Then the gray surroundings (`COLOUR_SHARE`):
  a colour anaglyph in a screenshot of a page read as half-colour."""
  values = np.asarray(image, np.float32)
  scale = 1.0 if values.max(initial=0.0) <= 1.0 else 255.0

  tolerance = MARGIN_TOLERANCE * scale
  top, bottom = _span(np.ptp(values, axis=1).max(axis=-1) > tolerance)
  values = values[top:bottom]  # Columns within the rows kept: bars and a frame together.
  left, right = _span(np.ptp(values, axis=0).max(axis=-1) > tolerance)
  coloured = np.ptp(values[:, left:right], axis=-1) > tolerance
  rows = _span(coloured.mean(axis=1) > COLOUR_SHARE)
  columns = _span(coloured[rows[0]:rows[1]].mean(axis=0) > COLOUR_SHARE)
  return top + rows[0], top + rows[1], left + columns[0], left + columns[1]


def _span(kept: np.ndarray) -> Tuple[int, int]:
  """[first, last + 1) of the lines `kept` (bool) marks; all of them where fewer than 16
  would remain (a flat image, a gray anaglyph of flat areas)."""
  index = kept.nonzero()[0]
  if index.size == 0 or index[-1] + 1 - index[0] < 16:
    return 0, kept.size
  return int(index[0]), int(index[-1]) + 1
