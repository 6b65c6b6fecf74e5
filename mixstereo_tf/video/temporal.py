"""Temporal consistency for videos: scene cuts and per-shot decisions.

A video is a sequence of shots. Within a shot the encoding and the disparity range do not
change and consecutive disparities are close, so `VideoState` keeps, per shot:
  * the encoding and the eye order, resolved (detected for 'auto') once at the shot's first
    frame; where its colours fit a larger encoding as well (detection's 'also_fits', e.g.
    half-colour or colour anaglyph), every `settle_every`-th frame is detected again until
    one shows colours only the larger explains, and the shot is read as that from there on;
  * the disparity range, estimated once at the shot's first frame;
  * a double image's mixing weight (`--mixing_weight=auto`: estimated at its first frame);
  * the previous frame's left disparity (its first stage's, before any refiner:
    `hints.FrameHint.on_disparity`, `video.frame_pipeline`), handed to the solver as a
    prior (the classical matcher searches around it, `matcher.match(..., prior)`; a double
    image's self-matching penalises lags away from it, `diplopia_costs.add_prior`), except where
    that frame's match failed the left-right check (NaN: those pixels search the valid
    prior's range nearby, or the whole range where none is near), and moved with the
    camera where the two frames differ by a translation (`video.motion`).
Everything is reset at a scene cut. A cut is found between consecutive frames when the
distance of their colour histograms exceeds `TemporalConfig.cut_threshold`
(`histogram_distance`): per channel, 16-bin histograms of a copy at most 160 px wide,
half the L1 distance of the normalised histograms (0: same colours, 1: disjoint), averaged
over the channels. Histograms ignore where colours are, so camera motion within a shot
barely moves them while a change of scene does. Between scenes of similar colours
(distance above `soft_cut_threshold`) the frames' gray thumbnails decide: a cut leaves
them uncorrelated (`is_cut`).

    state = VideoState(TemporalConfig())
    for image in frames:
      hint = state.begin(image)             # FrameHint: None fields at a shot's start
      outputs = unmixer(image, hint=hint)   # uses hint.mixture, .disparity_range, .prior
      state.end(outputs)                    # records what the shot decided
                                            # (frame_pipeline: the disparities reported)
"""

import dataclasses
from typing import Dict, List, Optional, Sequence, Tuple

import cv2
import numpy as np

from mixstereo_tf.classical import halftone
from mixstereo_tf.core import hints
from mixstereo_tf.core import image_range
from mixstereo_tf.unmixing import tilt
from mixstereo_tf.video import motion as motion_lib

# What a shot keeps of its deciding frame's detection info (`hints.FrameHint.detection`).
_DETECTION_KEYS = ('detected', 'confidence', 'also_fits', 'eye_order_score')


def _detection_of(info: Dict[str, object]) -> Dict[str, object]:
  """The `_DETECTION_KEYS` of a frame's info that it has."""
  return {key: info[key] for key in _DETECTION_KEYS if key in info}


@dataclasses.dataclass(frozen=True)
class TemporalConfig:
  """Temporal consistency of video unmixing.

  Attributes:
    enabled: off: every frame is unmixed alone (encoding, range and disparity per frame).
    cut_threshold: histogram distance (0..1, `histogram_distance`) above which two
      consecutive frames belong to different shots.
    soft_cut_threshold, cut_correlation: above this histogram distance two consecutive
      frames also belong to different shots where their gray thumbnails
      (`thumbnail_width` px wide) correlate below cut_correlation (`is_cut`). A user's
      clip cut between two scenes at distance 0.28 (correlation 0.09; inside its shots
      0.996), as did 2 of 26 consecutive training photographs (0.27, 0.28; 0.05, 0.07).
      Pans across those photographs by 5 / 10 / 20% of the width a frame stay below 0.06
      / 0.09 / 0.19 in distance (their correlation falls to -0.3): 0.15 splits only the
      20% ones, where a new shot costs one frame's prior (docs/DESIGN.md, video).
    bins: histogram bins per colour channel.
    analysis_width: frames are area-reduced to at most this width before the histograms.
    use_prior: hand the previous frame's left disparity to the solver.
    prior_radius, prior_spread: the classical matcher's window around the prior (pixels
      added to the prior's [min, max] over (2 * spread + 1)^2 pixels); narrower than a
      still image's coarse-to-fine windows (`MatcherConfig.prior_radius` / `prior_spread`)
      so that the prior holds the disparity steady.
    first_frame_cells: a shot's first frame searches coarse-to-fine (`matcher.match`)
      when a full search would pass this many cells (H * W * D): the frames after it
      refine its disparities through the prior. On the 1280x720 benchmark clip (~120 px
      range) a full search of the first frame took 1.7 s, four later frames' time, and was
      less accurate than coarse-to-fine (docs/DESIGN.md).
    settle_every: a shot whose encoding also fits a larger one (`hints.FrameHint.may_be`)
      is detected again on every settle_every-th frame (a detection costs about half a
      720p frame's unmixing, and such frames are waited for whole); 1: every frame.
    motion: the prior follows the camera's frame-to-frame translation (`video.motion`).
  """
  enabled: bool = True
  cut_threshold: float = 0.3
  soft_cut_threshold: float = 0.15
  cut_correlation: float = 0.5
  thumbnail_width: int = 32
  bins: int = 16
  analysis_width: int = 160
  use_prior: bool = True
  prior_radius: int = 1
  prior_spread: int = 2
  first_frame_cells: int = 20_000_000
  settle_every: int = 4
  motion: motion_lib.MotionConfig = motion_lib.MotionConfig()

  def __post_init__(self):
    if not 0.0 < self.soft_cut_threshold <= self.cut_threshold < 1.0:
      raise ValueError(f'TemporalConfig needs 0 < soft_cut_threshold <= cut_threshold < 1, '
                       f'got {self.soft_cut_threshold} and {self.cut_threshold}.')
    if self.prior_radius < 0 or self.prior_spread < 0:
      raise ValueError(f'TemporalConfig.prior_radius and prior_spread must be >= 0, got '
                       f'{self.prior_radius} and {self.prior_spread}.')
    if self.bins < 2 or self.analysis_width < 8:
      raise ValueError(f'TemporalConfig needs bins >= 2 and analysis_width >= 8, got '
                       f'{self.bins} and {self.analysis_width}.')
    if self.first_frame_cells < 1 or self.settle_every < 1:
      raise ValueError(f'TemporalConfig.first_frame_cells and settle_every must be >= 1, '
                       f'got {self.first_frame_cells} and {self.settle_every}.')


def colour_histograms(image: np.ndarray, config: TemporalConfig = TemporalConfig()
                      ) -> np.ndarray:
  """Normalised per-channel histograms, float64 [3, bins], of a uint8 [H, W, 3] frame
  area-reduced to at most `config.analysis_width` px wide."""
  image = np.asarray(image)
  if image.dtype != np.uint8 or image.ndim != 3 or image.shape[2] != 3:
    raise ValueError(f'Expected a uint8 [H, W, 3] frame, got {image.dtype} {image.shape}.')
  height, width = image.shape[:2]
  if width > config.analysis_width:
    size = (config.analysis_width, max(1, round(height * config.analysis_width / width)))
    image = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
  pixels = image.reshape(-1, 3).astype(np.int64) * config.bins // 256
  counts = np.stack([np.bincount(pixels[:, c], minlength=config.bins) for c in range(3)])
  return counts / float(pixels.shape[0])


def histogram_distance(a: np.ndarray, b: np.ndarray) -> float:
  """Half the L1 distance of two [3, bins] normalised histograms, averaged over channels:
  0 for the same colour distribution, 1 for disjoint ones."""
  return float(0.5 * np.abs(a - b).sum(axis=1).mean())


def signature(image: np.ndarray, config: TemporalConfig = TemporalConfig()
              ) -> Tuple[np.ndarray, np.ndarray]:
  """What a frame is compared with the next by (`is_cut`): its `colour_histograms` and its
  gray thumbnail, float64 [h, config.thumbnail_width] (area-reduced)."""
  histograms = colour_histograms(image, config)
  height, width = image.shape[:2]
  size = (config.thumbnail_width, max(1, round(height * config.thumbnail_width / width)))
  gray = cv2.cvtColor(np.ascontiguousarray(image), cv2.COLOR_RGB2GRAY)
  return histograms, cv2.resize(gray, size, interpolation=cv2.INTER_AREA).astype(np.float64)


def is_cut(previous: Tuple[np.ndarray, np.ndarray], current: Tuple[np.ndarray, np.ndarray],
           config: TemporalConfig = TemporalConfig()) -> bool:
  """Whether two consecutive frames' `signature`s belong to different shots: their
  histogram distance above config.cut_threshold, or above soft_cut_threshold with their
  thumbnails' correlation (zero-mean, normalised; 0 for a flat one) below
  cut_correlation."""
  distance = histogram_distance(previous[0], current[0])
  if distance > config.cut_threshold:
    return True
  if distance <= config.soft_cut_threshold:
    return False
  a, b = (t - t.mean() for t in (previous[1], current[1]))
  norm = np.sqrt((a * a).sum() * (b * b).sum())
  return (float((a * b).sum() / norm) if norm > 0 else 0.0) < config.cut_correlation


def find_cuts(frames: Sequence[np.ndarray], config: TemporalConfig = TemporalConfig()
              ) -> List[int]:
  """Indices of the frames that start a new shot (frame 0 excluded, `is_cut`)."""
  cuts, previous = [], None
  for index, frame in enumerate(frames):
    current = signature(frame, config)
    if previous is not None and is_cut(previous, current, config):
      cuts.append(index)
    previous = current
  return cuts


class VideoState:
  """The running per-shot state of one video (see the module docstring).

  Attributes:
    config: the TemporalConfig.
    frames: frames begun so far.
    shot_starts: the indices of the frames that started a shot (0 first).
    cuts: the indices of the frames where `is_cut` found a scene cut.
    fallback_mixture: the encoding a frame with no anaglyph detected is read as
      (`hints.FrameHint.fallback_mixture`): the one given (a video's first frame found
      with an anaglyph), then each shot's as it is found; None: such frames fail.
  """

  def __init__(self, config: TemporalConfig = TemporalConfig(),
               fallback_mixture: Optional[str] = None):
    self.config, self.fallback_mixture = config, fallback_mixture
    self.frames = 0
    self.shot_starts: List[int] = []
    self.cuts: List[int] = []
    self._signature = None
    self._shot: Dict[str, object] = {}
    self._prior: Optional[np.ndarray] = None
    self._motion_copy: Optional[np.ndarray] = None

  def begin(self, image: np.ndarray, cut: bool = False) -> hints.FrameHint:
    """The hint for the next frame; `cut=True` starts a new shot whatever the histograms
    say (e.g. at a resumable segment's start). With `config.enabled` off: an empty hint
    (every frame decided alone), and no histograms are computed."""
    if not self.config.enabled:
      self.shot_starts.append(self.frames)
      self.frames += 1
      return hints.FrameHint(fallback_mixture=self.fallback_mixture)
    current = signature(image_range.eight_bits(image), self.config)  # uint16: 10-bit video.
    found = self._signature is not None and is_cut(self._signature, current, self.config)
    if found:
      self.cuts.append(self.frames)
    starts = cut or found or self._signature is None
    if starts:
      self.shot_starts.append(self.frames)
      self._shot, self._prior = {}, None
    settling = (self.frames - self.shot_starts[-1]) % self.config.settle_every == 0
    self._signature = current
    self.frames += 1
    prior = self._moved_prior(image) if self.config.use_prior else None
    return hints.FrameHint(mixture=self._shot.get('mixture'),
                     may_be=self._shot.get('may_be') if settling else None,
                     detection=self._shot.get('detection'),
                     disparity_range=self._shot.get('disparity_range'),
                     swap_eyes=self._shot.get('swap_eyes'), prior=prior,
                     prior_window=(self.config.prior_radius, self.config.prior_spread),
                     full_search_cells=self.config.first_frame_cells if starts else None,
                     mixing_weight=self._shot.get('mixing_weight'),
                     descreen=self._shot.get('descreen'), rectify=self._shot.get('rectify'),
                     fallback_mixture=self.fallback_mixture)

  def _moved_prior(self, image: np.ndarray) -> Optional[np.ndarray]:
    """The previous frame's disparity as this frame's prior (None: none, or another
    shape), moved with the camera where `config.motion` finds a translation."""
    prior, moves = self._prior, self.config.motion
    if prior is not None and prior.shape != image.shape[:2]:
      prior = None
    if not moves.enabled:
      return prior
    previous, self._motion_copy = self._motion_copy, motion_lib.motion_copy(image, moves.width)
    if prior is None or previous is None or previous.shape != self._motion_copy.shape:
      return prior
    shift = motion_lib.global_shift(previous, self._motion_copy, image.shape[1], moves)
    return prior if not shift or shift == (0, 0) else motion_lib.shift_map(prior, *shift)

  def started_shot(self) -> bool:
    """Whether the frame begun last started a shot (a scene cut, the first frame or
    `begin(cut=True)`); never with `config.enabled` off, where every frame is alone."""
    return (self.config.enabled and bool(self.shot_starts)
            and self.shot_starts[-1] == self.frames - 1)

  def end(self, outputs: Dict[str, object]) -> None:
    """Records the unmixed frame: its 'info' (mixture, detection, eye order, disparity range,
    mixing weight, halftone screen, tilt) when it is the shot's first frame that decided
    its encoding (not one read as the video's, 'undecided': black or dark frames of a
    fade), or when its mixture is the larger encoding the shot may still be
    (`hints.FrameHint.may_be`: the shot settles on it); and its
    'disparity_left' as the next frame's prior, NaN where its 'consistent_left' (when
    given) says the match failed the left-right check: there the next frame searches the
    valid prior's range nearby (or everything), so a wrong disparity is not inherited."""
    info = outputs.get('info', {})
    if info.get('detected') and info.get('mixture'):
      self.fallback_mixture = info['mixture']  # The latest encoding found in the video.
    if not self.config.enabled:
      return
    if not self._shot and 'mixture' in info and not info.get('undecided'):
      search = info.get('disparity_range')
      self._shot = {'mixture': info['mixture'], 'may_be': info.get('also_fits'),
                    'detection': _detection_of(info),
                    'disparity_range': tuple(int(d) for d in search) if search else None,
                    'swap_eyes': info['eye_order'] == 'swapped' if 'eye_order' in info else None,
                    'mixing_weight': info.get('mixing_weight'),
                    'descreen': info.get('screen_period', halftone.OFF),
                    'rectify': tuple(info['tilt']) if 'tilt' in info else tilt.OFF}
    elif self._shot.get('may_be') and info.get('mixture') == self._shot['may_be']:
      self._shot.update(mixture=info['mixture'], may_be=None,  # Settled by this frame.
                        detection=_detection_of(info))
    disparity = outputs.get('disparity_left')
    if disparity is None or not np.isfinite(disparity).all():
      self._prior = None
      return
    self._prior = np.array(disparity, np.float32)
    consistent = outputs.get('consistent_left')
    if consistent is not None:
      self._prior[~np.asarray(consistent, bool)] = np.nan
