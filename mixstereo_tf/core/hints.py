"""What a video shot has decided before one of its frames is unmixed (`FrameHint`).

Made by `video.temporal.VideoState`, read by the unmixing steps and the classical matcher;
one object under one name from the video loop down to the matcher.
"""

import dataclasses
from typing import Dict, Optional, Tuple

import numpy as np


@dataclasses.dataclass(frozen=True)
class FrameHint:
  """What a shot has decided before one of its frames is unmixed (None: decide now).

  Attributes:
    mixture: the shot's encoding.
    detection: the detection info of the shot's first frame ({'detected', 'confidence'} and
      'also_fits' when detection gave one).
    disparity_range: the shot's (min, max) signed pixels.
    prior: the previous frame's left disparity, float32 [H, W] (NaN: no prior there).
    prior_window: (radius, spread) of the search around the prior (`TemporalConfig`).
    full_search_cells: for a shot's first frame, the matcher's coarse-to-fine threshold
      (`TemporalConfig.first_frame_cells`); None: the matcher's own.
  """
  mixture: Optional[str] = None
  detection: Optional[Dict[str, object]] = None
  disparity_range: Optional[Tuple[int, int]] = None
  prior: Optional[np.ndarray] = None
  prior_window: Optional[Tuple[int, int]] = None
  full_search_cells: Optional[int] = None
