"""Signed disparity ranges and how a network with D levels is fitted around one.

Published anaglyphs are window-aligned: disparities are signed (negative = behind the
screen) and at photo resolution span 100-300 px, while the stereo network regresses
d in [0, D - 1] (D = `ModelConfig.max_disparity`). `plan` chooses, for a range [lo, hi] in
pixels of the input image:
  * a shift s = max(0, -lo): the channels of the right eye are moved s pixels to the left
    (the right view sampled at x + s), so every disparity becomes d + s >= 0; this needs
    mixture channels that carry the right view alone or mostly (anaglyphs), not an average
    of both (diplopia: its range must be non-negative);
  * a scale k >= 1: the (shifted) image is reduced k times, so the range (hi + s) / k fits
    the network's levels with a margin, and the image its pixel budget;
and `to_network` / `from_network` apply and undo them. Disparities in pixels; the left
pixel x matches the right pixel x - d_L, the right pixel x matches the left x + d_R.
"""

import dataclasses
import math
from typing import Dict, Optional, Sequence, Tuple, Union

import cv2
import numpy as np

Range = Tuple[int, int]
# The range a method covers as it is (a network: [0, D - 1], its input neither shifted nor
# scaled), the one the paper's benchmark protocols use.
NETWORK = 'network'


def parse(text: str) -> Union[None, str, Range]:
  """'auto' -> None; 'network' -> NETWORK; 'MIN,MAX' -> (MIN, MAX) integers, MIN < MAX:
  fractional bounds widen to the whole pixels around them (0.5,10.5 -> 0,11).

  Raises:
    ValueError: anything else, naming the text.
  """
  if text.strip().lower() == 'auto':
    return None
  if text.strip().lower() == NETWORK:
    return NETWORK
  parts = text.split(',')
  try:
    low, high = (float(p) for p in parts)
    low, high = math.floor(low), math.ceil(high)
  except (ValueError, OverflowError):
    raise ValueError("disparity range must be 'auto', 'network' or MIN,MAX in pixels (e.g. "
                     f'-40,120), got {text!r}.') from None
  if low >= high:
    raise ValueError(f'disparity range needs MIN < MAX, got {text!r}.')
  return low, high


@dataclasses.dataclass(frozen=True)
class Plan:
  """How an image is fed to a network: shift s of the right-eye channels, scale k."""
  shift: int
  scale: float


def plan(disparity_range: Range, levels: int, height: int, width: int,
         max_pixels: Optional[int] = None, can_shift: bool = True,
         margin: float = 0.1) -> Plan:
  """The shift and scale that fit `disparity_range` into the network's [0, levels - 1].

  A range that needs reducing is fitted into [0, (1 - margin)(levels - 1)]; one that fits
  after the shift is kept at full size (scale 1).

  Args:
    disparity_range: (lo, hi) pixels of the input image.
    levels: the network's disparity levels D.
    height, width: the input image's size.
    max_pixels: largest network input (pixels), or None.
    can_shift: False for mixtures whose channels all mix both views (diplopia).
    margin: fraction of the levels kept free above the range.

  Raises:
    ValueError: a negative range for a mixture that cannot shift.
  """
  low, high = disparity_range
  if low < 0 and not can_shift:
    raise ValueError(f'The disparity range {low},{high} has negative disparities, which '
                     'this mixture cannot represent (each channel holds both views).')
  shift = max(0, -low)
  scale = 1.0
  if high + shift > levels - 1:  # A range that already fits is left at full size.
    scale = (high + shift) / ((1.0 - margin) * (levels - 1))
  if max_pixels:
    scale = max(scale, math.sqrt(height * width / max_pixels))
  return Plan(shift=shift, scale=scale)


def _shift_columns(image: np.ndarray, offset: int) -> np.ndarray:
  """image sampled at x + offset along the rows, edge replication."""
  if offset == 0:
    return image
  columns = np.clip(np.arange(image.shape[1]) + offset, 0, image.shape[1] - 1)
  return image[:, columns]


def _resize(image: np.ndarray, size: Tuple[int, int], interpolation) -> np.ndarray:
  out = cv2.resize(image, size, interpolation=interpolation)
  return out.reshape(size[::-1] + image.shape[2:])


def to_network(mixture: np.ndarray, right_eye: Sequence[int], p: Plan) -> np.ndarray:
  """The network input: right-eye channels shifted by p.shift, the image reduced by p.scale.

  Args:
    mixture: uint8 [H, W, 3].
    right_eye: the mixture channels of the right view.
    p: the plan.
  """
  image = mixture.copy()
  if p.shift:
    channels = list(right_eye)
    image[..., channels] = _shift_columns(mixture[..., channels], p.shift)
  if p.scale > 1.0:
    height, width = mixture.shape[:2]
    size = (max(1, round(width / p.scale)), max(1, round(height / p.scale)))
    image = _resize(image, size, cv2.INTER_AREA)
  return image


def from_network(outputs: dict, p: Plan, height: int, width: int) -> dict:
  """Undoes `to_network` on the network's outputs.

  Args:
    outputs: 'left', 'right' (uint8 views) and 'disparity_left', 'disparity_right' (float
      pixels of the network input), at the network's size.
    p: the plan used.
    height, width: the input image's size.

  Returns:
    The same keys at the input size: disparities scaled by the width ratio and shifted back
    (d_L = d'_L - s; d_R(x) = d'_R(x - s) - s), the right view moved back by s.
  """
  size = (width, height)
  ratio = width / outputs['disparity_left'].shape[1]
  out = {key: _resize(np.asarray(outputs[key], np.float32), size, cv2.INTER_LINEAR) * ratio
         for key in ('disparity_left', 'disparity_right')}
  for key in ('left', 'right'):
    out[key] = _resize(outputs[key], size, cv2.INTER_LINEAR)
  out['disparity_left'] = out['disparity_left'] - p.shift
  out['disparity_right'] = _shift_columns(out['disparity_right'], -p.shift) - p.shift
  out['right'] = _shift_columns(out['right'], -p.shift)
  return out


# A given range is warned about when at least this share of the disparities sits at one of
# its limits: the scene reaches past it.
LIMIT_SHARE = 0.1


def at_limits(disparity: np.ndarray, search: Range) -> Dict[str, float]:
  """{'low' / 'high': share of the finite disparities [H, W] (pixels) within 0.5 px of that
  limit of `search`} for the limits at least LIMIT_SHARE of them reach."""
  finite = disparity[np.isfinite(disparity)]
  if not finite.size:
    return {}
  shares = {'low': float(np.mean(finite <= search[0] + 0.5)),
            'high': float(np.mean(finite >= search[1] - 0.5))}
  return {side: share for side, share in shares.items() if share >= LIMIT_SHARE}
