"""Which eye an anaglyph's filters carry, and unmixing with the eyes swapped.

    found = detect(image, 'anaglyph')   # found.swapped, found.score (z; < 0: looks swapped)

A swapped anaglyph (cyan-red glasses, a mirrored scan) is M = f(I_R, I_L): unmixed as it is,
its views come out exchanged with (mostly negative) disparities of the right view. Mirrored,
flip(M) = f(flip(I_R), flip(I_L)) is an ordinary anaglyph of the pair (flip(I_R), flip(I_L)),
whose left disparity is the mirrored right one and vice versa. So a swapped image is unmixed
mirrored (`mirror`, `mirror_hint`) and mapped back (`unmirror`): views exchanged and
mirrored back, the left view's disparity = the mirrored run's right disparity, mirrored (left
x matches right x - d, positive for near; every predictor returns both disparities).

Detection, from the image alone. A view's pixels that the other view cannot see form bands
beside depth edges. Matched as if the eyes were in order, a band of the left-eye channels
lies where the disparity rises by about its width going right, between two surfaces,
whichever eye is which: the disparities (and their sign: window-aligned images have both)
do not say which surface hides it. Its texture does: a band is the hidden part of the far
surface, so its texture continues that surface and breaks at the near one's silhouette; in
order the far surface is the band's left neighbour, swapped its right one. On a copy at most
EyeOrderConfig.width px wide the eye channels are matched (census-SGM over the estimated
range); a band is a left-right inconsistent run of a row between consistent pixels (regions
of at least min_area) whose disparity rises by its width (within width_tolerance); its vote
is the colour step across its right end minus the step across its left end (mirrored for
the right-eye channels' bands): positive for the eyes in order. The score is the votes' sum
over their standard error, votes summed per cell first (neighbouring rows of one band
agree); below -threshold the eyes are swapped. Only anaglyph encodings are detected.
"""

import dataclasses
from typing import Dict, Optional, Tuple

import cv2
import numpy as np

from mixstereo_tf.classical import anaglyph
from mixstereo_tf.classical import matcher
from mixstereo_tf.classical import sgm
from mixstereo_tf.core import hints
from mixstereo_tf.core import image_range
from mixstereo_tf.core import planning_copies

AUTO = 'auto'
# PredictorConfig.swap_eyes: the eyes as given (left eye in the red / first filter's
# channels), swapped, or detected per image (a video: per shot).
SWAP_EYES = (False, True, AUTO)


@dataclasses.dataclass(frozen=True)
class EyeOrderConfig:
  """Parameters of `detect` (module docstring): the threshold just above the lowest score of
  an original of 16 procedural training scenes (128 anaglyphs: -1.89), the others by a sweep
  (experiments/results/eye_order.md).

  Attributes:
    width: the analysed copy's width at most, pixels.
    min_area: consistent regions smaller than this many pixels count as inconsistent.
    edge_pixels: a colour step compares the means of this many pixels on each side.
    min_jump: a band's disparity rise at least, pixels ...
    width_tolerance: ... within this many pixels of its width.
    cell: votes are summed per cell x cell pixels before the standard error.
    threshold: scores below -threshold mean swapped eyes.
  """
  width: int = 640
  min_area: int = 100
  edge_pixels: int = 2
  min_jump: float = 3.0
  width_tolerance: float = 4.0
  cell: int = 8
  threshold: float = 2.0


@dataclasses.dataclass(frozen=True)
class EyeOrder:
  """What `detect` found: `swapped`, `score` (the z of the votes: positive for the eyes as
  given, below -threshold swapped) and the number of `bands` that voted."""
  swapped: bool
  score: float
  bands: int


def _eyes(image: np.ndarray, name: str, width: int) -> Tuple[np.ndarray, np.ndarray]:
  """(left-eye, right-eye) channels on 0..255, float32 [h, w, k], at most `width` wide a
  frame (`planning_copies`)."""
  left, right = anaglyph.eye_images(image_range.u8_to_unit(image), name)
  left, right = (planning_copies.area_copy(x, width) for x in (left, right))
  fix = lambda x: np.ascontiguousarray(x[..., None] if x.ndim == 2 else x, np.float32)
  return fix(left), fix(right)


def _large(consistent: np.ndarray, min_area: int) -> np.ndarray:
  """`consistent` without its 4-connected regions smaller than min_area pixels."""
  count, labels, stats, _ = cv2.connectedComponentsWithStats(
      consistent.astype(np.uint8), connectivity=4)
  keep = stats[:, cv2.CC_STAT_AREA] >= min_area
  keep[0] = False  # The inconsistent background.
  return keep[labels] if count > 1 else np.zeros_like(consistent, bool)


def runs(valid: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
  """(rows, first, last) columns of the runs of False in bool [H, W] `valid` that have a
  True pixel on both sides in their row."""
  width = valid.shape[1]
  steps = np.diff(valid.astype(np.int8), axis=1)
  start_y, start_x = np.nonzero(steps == -1)
  end_y, end_x = np.nonzero(steps == 1)
  if end_y.size == 0:
    return end_y, end_x, end_x
  index = np.searchsorted(end_y * width + end_x, start_y * width + start_x)
  closed = index < end_y.size
  index = np.minimum(index, end_y.size - 1)
  closed &= end_y[index] == start_y  # The next end in the same row.
  return start_y[closed], start_x[closed] + 1, end_x[index][closed]


def band_votes(view: np.ndarray, disparity: np.ndarray, consistent: np.ndarray, sign: int,
               config: EyeOrderConfig) -> Tuple[np.ndarray, np.ndarray]:
  """(votes, cells) of one view's bands (module docstring); sign +1 for the left-eye view
  and its disparity_left, -1 for the right-eye view and its disparity_right."""
  height, width = disparity.shape
  y, first, last = runs(_large(consistent, config.min_area))
  jump = sign * (disparity[y, last + 1] - disparity[y, first - 1])
  size = last - first + 1
  k = config.edge_pixels
  keep = ((jump >= config.min_jump) & (np.abs(size - jump) <= config.width_tolerance) &
          (first >= k) & (last + 1 + k <= width))
  y, first, last, size = y[keep], first[keep], last[keep], size[keep]
  sums = np.concatenate([np.zeros((height, 1, view.shape[2])),
                         np.cumsum(view, axis=1, dtype=np.float64)], axis=1)
  mean = lambda x0, x1: (sums[y, x1] - sums[y, x0]) / (x1 - x0)[:, None]
  inside = np.minimum(k, size)
  step_left = np.abs(mean(first - k, first) - mean(first, first + inside)).sum(axis=1)
  step_right = np.abs(mean(last + 1, last + 1 + k) - mean(last + 1 - inside, last + 1)).sum(1)
  cells = (y // config.cell) * width + first // config.cell
  return sign * (step_right - step_left), cells


def z_score(votes: np.ndarray, cells: np.ndarray) -> float:
  """Sum of the votes over its standard error, votes summed per cell first; 0 without."""
  if votes.size == 0:
    return 0.0
  _, index = np.unique(cells, return_inverse=True)
  per_cell = np.bincount(index, votes)
  spread = float(np.sqrt((per_cell ** 2).sum()))
  return float(per_cell.sum() / spread) if spread > 0 else 0.0


def detect(image: np.ndarray, name: str, config: EyeOrderConfig = EyeOrderConfig(),
           chroma_halved: bool = False) -> EyeOrder:
  """Whether uint8 anaglyph `image` [H, W, 3] of encoding `name` has its eyes swapped.
  `chroma_halved` (a 4:2:0 JPEG, `hints.FrameHint.chroma_halved`): analysed at most at
  half its width, the colour's resolution, where the colour steps across a band's ends
  are the eyes' own and not the luminance's, which mixes both."""
  frame = planning_copies.frame_width(image.shape)
  width = min(config.width, -(-frame // 2)) if chroma_halved else config.width
  left, right = _eyes(image, name, width)
  low, high = matcher.estimate_range(left, right)
  matched = matcher.match(left, right, low - 2, high + 2, matcher.MatcherConfig(strips=1))
  votes, cells = zip(
      band_votes(left, matched['disparity_left'], matched['consistent_left'], 1, config),
      band_votes(right, matched['disparity_right'], matched['consistent_right'], -1, config))
  offset = left.shape[0] * left.shape[1]  # The right view's cells after the left's.
  votes, cells = np.concatenate(votes), np.concatenate([cells[0], cells[1] + offset])
  score = z_score(votes, cells)
  return EyeOrder(score < -config.threshold, score, int(votes.size))


def _flip(array: np.ndarray) -> np.ndarray:
  return np.ascontiguousarray(array[:, ::-1])


def mirror(image: np.ndarray) -> np.ndarray:
  """The image mirrored left-right: a swapped anaglyph becomes an ordinary one."""
  return _flip(image)


def right_from_left(disparity_left: np.ndarray) -> np.ndarray:
  """The right view's disparity forward-warped from the left's, float32 [H, W]: right pixel
  round(x - d) takes d, the largest (nearest) where several land; NaN where none does (and
  where the left was NaN)."""
  height, width = disparity_left.shape
  rows, columns = np.mgrid[:height, :width]
  finite = np.isfinite(disparity_left)
  target = np.rint(columns - np.where(finite, disparity_left, 0)).astype(np.int64)
  inside = finite & (target >= 0) & (target < width)
  out = np.full(height * width, -np.inf)
  np.maximum.at(out, rows[inside] * width + target[inside], disparity_left[inside])
  out = out.reshape(height, width)
  return np.where(np.isfinite(out), out, np.nan).astype(np.float32)


# An output of one eye -> the same output of the other (`unmirror` maps them so).
_OTHER_EYE = {'left': 'right', 'right': 'left', 'disparity_left': 'disparity_right',
              'disparity_right': 'disparity_left'}


def mirror_hint(hint: hints.FrameHint) -> hints.FrameHint:
  """A frame hint for the mirrored image: its prior (the previous frame's left disparity)
  becomes the mirrored problem's left disparity, the mirrored right one; an unread output
  of one eye becomes the other eye's; `on_disparity` is told the disparities mapped back
  (`unmirror`)."""
  if hint.unread in _OTHER_EYE:
    hint = dataclasses.replace(hint, unread=_OTHER_EYE[hint.unread])
  if hint.on_disparity is not None:
    told = hint.on_disparity
    hint = dataclasses.replace(hint, on_disparity=lambda found: told(unmirror(found)))
  if hint.prior is None:
    return hint
  return dataclasses.replace(hint, prior=_flip(right_from_left(hint.prior)))


def unmirror(outputs: Dict[str, object],
             lr_threshold: float = matcher.MatcherConfig().lr_threshold) -> Dict[str, object]:
  """Outputs of the mirrored image mapped back (module docstring); 'consistent_left', when
  given, becomes the left-right check (lr_threshold px) of the mapped disparities. The
  views may be absent (`hints.FrameHint.on_disparity`'s disparities)."""
  mapped = dict(outputs)
  if 'left' in outputs:
    mapped['left'], mapped['right'] = _flip(outputs['right']), _flip(outputs['left'])
  mapped['disparity_left'] = _flip(outputs['disparity_right'])
  mapped['disparity_right'] = _flip(outputs['disparity_left'])
  if 'consistent_left' in outputs:
    mapped['consistent_left'] = sgm.lr_check(mapped['disparity_left'],
                                             mapped['disparity_right'], lr_threshold)[0]
  return mapped


def decide(image: np.ndarray, name: str, asked, detectable: bool,
           shot: Optional[bool] = None, chroma_halved: bool = False
           ) -> Tuple[bool, Dict[str, object]]:
  """(swapped, info) for one image of encoding `name`: a video shot's decision (`shot`),
  else `asked` (SWAP_EYES; AUTO detects, on `detectable` encodings only: others keep the
  order given; `chroma_halved` as `detect`'s). info: 'eye_order' ('as_given' or
  'swapped') and, when detected, 'eye_order_score' (`EyeOrder.score`)."""
  info = {}
  if shot is not None:
    swapped = shot
  elif asked == AUTO and detectable:
    found = detect(image, name, chroma_halved=chroma_halved)
    swapped, info['eye_order_score'] = found.swapped, round(found.score, 2)
  else:
    swapped = asked not in (False, AUTO)
  info['eye_order'] = 'swapped' if swapped else 'as_given'
  return swapped, info
