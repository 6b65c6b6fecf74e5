"""What is decided before a frame is unmixed (`FrameHint`): its video shot's decisions,
and how the matcher runs.

Made by `video.temporal.VideoState` (and, pinned to one SGM strip, by the refiner's
training examples), read by the unmixing steps and the families' classical stages; one
object under one name from the video loop down to the matcher's configuration.
"""

import dataclasses
from typing import Callable, Dict, Optional, Tuple, Union

import numpy as np


@dataclasses.dataclass(frozen=True)
class FrameHint:
  """What is decided before a frame is unmixed (None: decide now, or the default).

  Attributes:
    mixture: the shot's encoding.
    may_be: a larger encoding the shot may still turn out to be (its detection's
      'also_fits': the colours seen so far fit both): this frame is detected again and
      read as `may_be` where detection gives it (`steps.run`; `VideoState` sets it on
      every `settle_every`-th frame of an unsettled shot); None: read as `mixture`.
    detection: the detection info of the shot's first frame ({'detected', 'confidence'} and
      'also_fits', 'eye_order_score' when detection gave them).
    disparity_range: the shot's (min, max) signed pixels.
    swap_eyes: whether the shot's eyes are swapped (`unmixing.eye_order`).
    prior: the previous frame's left disparity, float32 [H, W] (NaN: no prior there).
    prior_window: (radius, spread) of the search around the prior (`TemporalConfig`).
    full_search_cells: for a shot's first frame, the matcher's coarse-to-fine threshold
      (`TemporalConfig.first_frame_cells`); None: the matcher's own.
    matcher_strips: the anaglyph matcher's SGM strips (`MatcherConfig.strips`), for its
      range estimation and its matching; None: its own (they follow the core count, and
      the aggregation differs near strip borders); 1: the same result on every machine.
    fallback_mixture: 'auto' only: the encoding a frame in which detection finds no anaglyph
      is read as (`mixture_choice.resolve_mixture`): the video's last shot's, or the first frame's
      with one (black frames, fades, titles); None: such a frame fails.
    mixing_weight: double images: the left view's weight a of I = a L + (1 - a) R; None:
      1/2 (`--mixture=diplopia` exactly); 'auto': estimated from the frame; a number in
      (0, 1): that weight (`classical.diplopia_weight.resolve_weight`).
    unread: an output the caller does not read ('disparity_right': a video's frames,
      which write the views and the left disparity): a stage may return its first stage's
      value there instead of refining it (`refiner_stage.refiner_unmix`); None: every output.
    base_disparities: a stage whose views do not depend on its refined disparities (a
      double image's refiner) returns its first stage's disparities instead of refining
      them (`refiner_stage.refiner_unmix`): a video's frames, where the refinement costs
      most of the refiner's time and on real pans gains only on KITTI's (docs/DESIGN.md).
    on_disparity: called once with {'disparity_left', 'disparity_right'} (and
      'consistent_left' where the stage checks them) as soon as the frame's first stage
      has matched them, before its views are restored or refined (the anaglyph matcher,
      `classical.anaglyph.unmix_anaglyph`; the double images' self-matching,
      `classical.diplopia.unmix_diplopia`; a refiner passes it to its base stage): the
      video loop takes them as the next frame's prior and starts that frame
      (`video.frame_pipeline`). None: nobody is told early.
    chroma_halved: the image was stored with its colour at half the width (4:2:0 or 4:2:2
      JPEG, lossy WebP, most video): its finest detail is the stored luminance, the same in
      every channel, which matches at disparity 0; an anaglyph is then matched without it
      (`unmixing.chroma`).
    stored_image: uint8 [H, W, 3], the image as stored, where the stage is given its
      colour-resolution copy to match (`steps.run` sets it for chroma_halved anaglyphs),
      or uint16, a 16-bit image matched at 8 bits: the views are restored from it, at its
      depth (`views_image`); None: from the image matched.
    descreen: a printed image's halftone screen (`classical.halftone.resolve`): 'auto'
      (found from the frame), 'off' or its period in pixels (a video shot's, found on its
      first frame); None: the unmixer's own setting.
    rectify: a tilted anaglyph's or double image's turn (`unmixing.tilt.level`): 'auto',
      'off' or the shot's (angle degrees, offset pixels); None: the unmixer's own setting.
  """
  mixture: Optional[str] = None
  may_be: Optional[str] = None
  detection: Optional[Dict[str, object]] = None
  disparity_range: Optional[Tuple[int, int]] = None
  swap_eyes: Optional[bool] = None
  prior: Optional[np.ndarray] = None
  prior_window: Optional[Tuple[int, int]] = None
  full_search_cells: Optional[int] = None
  matcher_strips: Optional[int] = None
  fallback_mixture: Optional[str] = None
  mixing_weight: Union[None, float, str] = None
  unread: Optional[str] = None
  base_disparities: bool = False
  on_disparity: Optional[Callable[[Dict[str, np.ndarray]], None]] = None
  chroma_halved: bool = False
  stored_image: Optional[np.ndarray] = None
  descreen: Union[None, str, float] = None
  rectify: Union[None, str, Tuple[float, float]] = None


def views_image(image: np.ndarray, hint: Optional[FrameHint]) -> np.ndarray:
  """The image a stage restores its views from: the hint's stored_image, else `image`."""
  return image if hint is None or hint.stored_image is None else hint.stored_image


def stored(chroma_halved: bool) -> Dict[str, FrameHint]:
  """The keywords an unmixer is called with for an image stored as `chroma_halved` says:
  {'hint': FrameHint(chroma_halved=True)}, or {} (the image as it is)."""
  return {'hint': FrameHint(chroma_halved=True)} if chroma_halved else {}
