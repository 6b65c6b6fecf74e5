"""A tilted anaglyph or double image made level before it is unmixed, its outputs turned
back after.

    image, deep, back, info = level(image, deep, name, 'auto')  # `steps.run`, step 1b
    ... outputs = back(outputs)                                 # the input's frame again

The eyes' displacement line comes from `classical.epipolar.estimate`, whose line is tilted
by up to 1.3 degrees on level frames (matching red against green-blue; docs/DESIGN.md,
classical: tilted anaglyphs). So it is only taken when it helps the matcher itself: the
census matcher's left-right consistent share on a copy `width` px a frame (the encoding's
eye channels, over its own estimated range) must rise by at least min_gain once the image
is turned and its right eye moved onto the line. On Motorcycle, SceneFlow and the KITTI
frames (scratch `s27/tilt4.py`) every level frame kept its level (the estimate lost 0.004
to 0.016), and every frame turned by 3 degrees was turned back (+0.07 to +0.15).
The disparities of a turned image run along its eyes' line, in pixels.

A double image's line is its echo's (`classical.echo_tilt`: an angle, no offset, which
both copies would share); the check is its self-matching's consistent share at lags of
at least `DiplopiaConfig.min_lag` (`echo_tilt.consistent_share`), on the box inside the
image that both the input and the turned canvas show (the canvas' replicated corners
match nothing), gaining at least echo_min_gain. Chosen on 16 validation photo warps
(256 x 512 to 540 x 960) at a = 0.3 / 0.5 / 0.7 (scratch `s28/dtilt/t11.py`): of 48
level ones 8 read a turn of 0.3 degrees or more, their gains at most 0.0006 (on the
whole canvas, -0.03 to +0.007); turned by 2 / 1 / 0.5 degrees, 28 of 37 / 18 of 38 /
10 of 31 such reads gain 0.005 or more (the line within 0.5 degrees on most; the rest
stay as they are).
"""

import dataclasses
from typing import Callable, Dict, Optional, Tuple, Union

import numpy as np

from mixstereo_tf.classical import anaglyph
from mixstereo_tf.classical import diplopia_costs
from mixstereo_tf.classical import echo_tilt
from mixstereo_tf.classical import epipolar
from mixstereo_tf.classical import matcher
from mixstereo_tf.core import hints
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.core import planning_copies

AUTO, OFF = 'auto', 'off'  # --rectify: estimated and checked per image (a video per shot).
Setting = Union[str, Tuple[float, float]]  # AUTO, OFF or a shot's (angle, offset).
# Outputs of the right eye, moved with its channels.
RIGHT_KEYS = ('right', 'disparity_right', 'consistent_right')


@dataclasses.dataclass(frozen=True)
class LevelConfig:
  """`level`'s parameters: the line's estimate (an anaglyph's, a double image's echo), the
  copy the matcher checks it on (pixels a frame) and the consistent share it must add
  (module docstring)."""
  line: epipolar.EpipolarConfig = epipolar.EpipolarConfig()
  echo: echo_tilt.EchoConfig = echo_tilt.EchoConfig()
  width: int = 640
  min_gain: float = 0.002
  echo_min_gain: float = 0.005


class _EyesLine:
  """An anaglyph's line: between its eyes' channels (`epipolar.estimate`), its right eye
  moved onto the rows, checked by the census matcher on the whole canvas."""

  @staticmethod
  def estimate(image: np.ndarray, name: str, config: LevelConfig):
    left, right = (np.float32(image[..., list(eye)]).mean(axis=-1)
                   for eye in mixtures.get_mixture(name).eye_channels)
    return epipolar.estimate(left, right, config.line)

  @staticmethod
  def helps(image: np.ndarray, turned: np.ndarray, name: str, config: LevelConfig,
            angle: float) -> bool:
    del angle  # The whole canvas (measured so: module docstring).
    share = lambda x: census_share(x, name, config.width)
    return share(turned) - share(image) >= config.min_gain

  @staticmethod
  def right_channels(name: str) -> Tuple[int, ...]:
    return tuple(mixtures.get_mixture(name).eye_channels[1])


class _EchoLine:
  """A double image's line: its echo's (`echo_tilt`; an angle alone), checked by its
  self-matching on the box both frames show."""

  @staticmethod
  def estimate(image: np.ndarray, name: str, config: LevelConfig):
    del name
    return echo_tilt.estimate(_gray(image), config.echo)

  @staticmethod
  def helps(image: np.ndarray, turned: np.ndarray, name: str, config: LevelConfig,
            angle: float) -> bool:
    del name
    image, turned = _common_box(image, turned, angle)
    share = lambda x: echo_tilt.consistent_share(_gray(x), config.width)
    return share(turned) - share(image) >= config.echo_min_gain

  @staticmethod
  def right_channels(name: str) -> Tuple[int, ...]:
    del name
    return ()  # Both copies share every channel.


def _line(name: str):
  """The line strategy of encoding `name`: anaglyphs' eyes, double images' echo, or None."""
  spec = mixtures.get_mixture(name)
  return _EyesLine if spec.is_anaglyph else _EchoLine if spec.family == 'diplopia' else None


def turnable(name: str) -> bool:
  """Whether encoding `name` is one `level` turns: the anaglyphs and double images."""
  return _line(name) is not None


def census_share(image: np.ndarray, name: str, width: int) -> float:
  """The census matcher's left-right consistent share of uint8 anaglyph `image` of
  encoding `name`, on a copy `width` px a frame, its 8-px border left out."""
  left, right = anaglyph.eye_images(
      image_range.u8_to_unit(planning_copies.area_copy(image, width)), name)
  left, right = (np.float32(x) for x in (left, right))
  low, high = matcher.estimate_range(left, right)
  consistent = matcher.match(left, right, low, high)['consistent_left']
  return float(consistent[8:-8, 8:-8].mean())


def _gray(image: np.ndarray) -> np.ndarray:
  """A double image's float32 intensities, 0-255 (the double-image matcher's)."""
  return np.float32(diplopia_costs.gray_255(image_range.u8_to_unit(image)))


def _estimate(image: np.ndarray, name: str, config: LevelConfig) -> Optional[epipolar.Tilt]:
  """The line's tilt of uint8 `image` (`_line`), None where it is too small to be worth a
  turn (`epipolar.worth_rectifying`)."""
  tilt = _line(name).estimate(image, name, config)
  return tilt if epipolar.worth_rectifying(tilt, config.line) else None


def _common_box(image: np.ndarray, turned: np.ndarray, angle: float):
  """The central boxes of `image` and of its `turned` canvas (turned by `angle` degrees
  about its centre) of the size that lies inside the image in both, 1 px spare a side."""
  height, width = image.shape[:2]
  sine = abs(np.sin(np.radians(angle)))
  rows, columns = max(1, int(height - width * sine) - 2), max(1, int(width - height * sine) - 2)
  box = lambda x: x[(x.shape[0] - rows) // 2:(x.shape[0] - rows) // 2 + rows,
                    (x.shape[1] - columns) // 2:(x.shape[1] - columns) // 2 + columns]
  return np.ascontiguousarray(box(image)), np.ascontiguousarray(box(turned))


def choose(image: np.ndarray, name: str,
           config: LevelConfig = LevelConfig()) -> Optional[epipolar.Tilt]:
  """The tilt to level uint8 `image` of encoding `name` (`turnable`) by, None where it is
  level or none helps."""
  chosen = _chosen(image, name, config)
  return None if chosen is None else chosen[0]


def _chosen(image: np.ndarray, name: str, config: LevelConfig):
  """(tilt, `epipolar.rectify`'s (turned, back, forth) of `image` by it) of `choose`, or
  None where it is level or no turn helps."""
  tilt = _estimate(image, name, config)
  if tilt is None:
    return None
  line = _line(name)
  rectified = epipolar.rectify(image, tilt, line.right_channels(name))
  return (tilt, rectified) if line.helps(image, rectified[0], name, config,
                                         tilt.angle) else None


def _back(outputs: Dict[str, object], back: Callable[..., np.ndarray],
          shape: Tuple[int, int], name: str, originals: Tuple[np.ndarray, ...],
          swapped: bool) -> Dict[str, object]:
  """The outputs of the turned canvas (arrays of its `shape`) in the input's frame, the
  views' channels the encoding copies taken from the input itself (`originals`: the image
  and its 16-bit samples, matched to the views' dtype; `swapped`: eyes exchanged), not
  resampled twice."""
  result = {}
  for key, value in outputs.items():
    if isinstance(value, np.ndarray) and value.shape[:2] == shape:
      turned = back(value.astype(np.float32) if value.dtype == bool else value,
                    right=key in RIGHT_KEYS)
      value = turned > 0.5 if value.dtype == bool else turned
    result[key] = value
  spec = mixtures.get_mixture(name)
  copies = {'left': spec.left_channels, 'right': spec.right_channels}
  if swapped:
    copies = {'left': copies['right'], 'right': copies['left']}
  for key, copied in copies.items():
    source = [x for x in originals if key in result and x is not None and
              x.dtype == result[key].dtype]
    for view_channel, mixture_channel in copied.items() if source else ():
      result[key][..., view_channel] = source[0][..., mixture_channel]
  return result


def level(image: np.ndarray, deep: Optional[np.ndarray], name: str, setting: Setting,
          hint: hints.FrameHint, config: LevelConfig = LevelConfig()):
  """(image, deep, hint, back, info): uint8 `image` of encoding `name` (and its 16-bit
  samples `deep`, or None) turned level under `setting` (AUTO: `choose`; OFF; a shot's
  (angle, offset)) where it is an anaglyph or a double image (`turnable`), the `hint`'s
  prior turned with it and its on_disparity given maps turned back; back(outputs,
  swapped=False) brings a dict of their outputs to the input's frame; info {'tilt':
  [angle degrees, offset pixels]} where turned, else {}."""
  unchanged = image, deep, hint, lambda outputs, swapped=False: outputs, {}
  if setting == OFF or not turnable(name):
    return unchanged
  right = _line(name).right_channels(name)
  if setting == AUTO:
    chosen = _chosen(image, name, config)
    if chosen is None:
      return unchanged
    tilt, (turned, back, forth) = chosen
  else:
    tilt = epipolar.Tilt(float(setting[0]), float(setting[1]), 0)
    turned, back, forth = epipolar.rectify(image, tilt, right)
  originals = (image, deep)
  deep = None if deep is None else epipolar.rectify(deep, tilt, right)[0]
  undo = lambda outputs, swapped=False: _back(outputs, back, turned.shape[:2], name,
                                              originals, swapped)
  told = hint.on_disparity
  hint = dataclasses.replace(
      hint, prior=None if hint.prior is None else forth(hint.prior),
      on_disparity=None if told is None else lambda maps: told(undo(maps)))
  return turned, deep, hint, undo, {'tilt': [round(tilt.angle, 3), round(tilt.offset, 3)]}
