"""Census transform + semi-global matching in vectorised NumPy, for the classical baselines.

Conventions (docs/DESIGN.md): disparities are float32 pixels, positive; the left pixel x
matches the right pixel x - d_L, the right pixel x matches the left pixel x + d_R.

Pipeline (Hirschmüller 2008, with Zabih & Woodfill's census cost): census codes of both
images -> Hamming cost volume over d in [min_disparity, max_disparity] -> 4-path SGM
aggregation (left/right/up/down; each path is a loop over one image axis vectorised over
the other axis and all disparities) -> winner-take-all with parabola sub-pixel refinement
for the left disparity, and for the right disparity the minimum along the volume's diagonal
(the right pixel x at disparity d is the left pixel x + d; Hirschmüller's trick, no second
aggregation) -> 3x3 median -> left-right check -> background-favouring scanline fill.
Census compares intensities only with their own neighbourhood, so it tolerates the colour
difference between e.g. the red and green channels of an anaglyph.
"""

import dataclasses
from typing import Tuple

import cv2
import numpy as np


@dataclasses.dataclass(frozen=True)
class SgmConfig:
  """Matching parameters.

  Attributes:
    max_disparity: largest disparity searched, pixels (clipped to width - 1).
    min_disparity: smallest disparity searched, pixels (>= 0).
    census_height, census_width: odd census window size (at most 64 comparisons).
    p1: SGM penalty for a 1 px disparity change between neighbours (census bits).
    p2: SGM penalty for larger jumps (census bits).
    lr_threshold: largest accepted |d_L(x) - d_R(x - d_L(x))|, pixels.
  """
  max_disparity: int = 128
  min_disparity: int = 0
  census_height: int = 7
  census_width: int = 9
  p1: int = 12
  p2: int = 80
  lr_threshold: float = 1.0

  def __post_init__(self):
    if self.census_height % 2 == 0 or self.census_width % 2 == 0:
      raise ValueError(f'census window must be odd, got {self.census_height}x'
                       f'{self.census_width}.')
    if self.census_height * self.census_width - 1 > 64:
      raise ValueError('census window must have at most 65 pixels (64-bit codes), got '
                       f'{self.census_height}x{self.census_width}.')
    if not 0 <= self.min_disparity < self.max_disparity:
      raise ValueError(f'need 0 <= min_disparity < max_disparity, got '
                       f'{self.min_disparity}, {self.max_disparity}.')
    if not 0 < self.p1 <= self.p2:
      raise ValueError(f'need 0 < p1 <= p2, got p1={self.p1}, p2={self.p2}.')


def census_transform(image: np.ndarray, height: int = 7, width: int = 9) -> np.ndarray:
  """Census codes: bit k is 1 where the k-th window neighbour is darker than the centre.

  Args:
    image: float or integer [H, W] intensities.
    height, width: odd window size; borders are reflected.

  Returns:
    uint64 [H, W] codes with height * width - 1 meaningful bits.
  """
  image = np.asarray(image, np.float32)
  ry, rx = height // 2, width // 2
  padded = np.pad(image, ((ry, ry), (rx, rx)), mode='reflect')
  h, w = image.shape
  codes = np.zeros((h, w), np.uint64)
  for dy in range(height):
    for dx in range(width):
      if dy == ry and dx == rx:
        continue
      darker = padded[dy:dy + h, dx:dx + w] < image
      codes = (codes << np.uint64(1)) | darker.astype(np.uint64)
  return codes


def cost_volume(census_left: np.ndarray, census_right: np.ndarray, min_disparity: int,
                max_disparity: int, out_of_image_cost: int) -> np.ndarray:
  """Hamming distances C[y, x, i] between left code (y, x) and right code (y, x - d_i).

  Args:
    census_left, census_right: uint64 [H, W] codes.
    min_disparity, max_disparity: inclusive disparity range, d_i = min_disparity + i.
    out_of_image_cost: cost where x - d_i < 0 (no match inside the right image).

  Returns:
    uint8 [H, W, D], D = max_disparity - min_disparity + 1.
  """
  h, w = census_left.shape
  disparities = range(min_disparity, max_disparity + 1)
  volume = np.full((len(disparities), h, w), out_of_image_cost, np.uint8)
  for i, d in enumerate(disparities):
    if d < w:
      volume[i, :, d:] = np.bitwise_count(census_left[:, d:] ^ census_right[:, :w - d])
  return np.ascontiguousarray(volume.transpose(1, 2, 0))


def _path_step(prev: np.ndarray, cost: np.ndarray, p1: int, p2: int) -> np.ndarray:
  """One SGM recursion L(p) = C(p) + min(L', L'_{d±1} + P1, min L' + P2) - min L'."""
  lowest = prev.min(axis=-1, keepdims=True)
  best = np.minimum(prev, lowest + p2)
  np.minimum(best[:, 1:], prev[:, :-1] + p1, out=best[:, 1:])
  np.minimum(best[:, :-1], prev[:, 1:] + p1, out=best[:, :-1])
  return cost + best - lowest


def aggregate(volume: np.ndarray, p1: int, p2: int) -> np.ndarray:
  """Sum of the 4 SGM path costs (left-to-right, right-to-left, down, up).

  Args:
    volume: uint8 [H, W, D] matching costs (at most 64).
    p1, p2: smoothness penalties in cost units (p2 < 16000 keeps the sum in uint16).

  Returns:
    uint16 [H, W, D] aggregated costs (each path is at most max cost + p2).
  """
  h, w, _ = volume.shape
  cost = volume.astype(np.int16)
  total = np.zeros(volume.shape, np.uint16)
  for order in (range(w), range(w - 1, -1, -1)):
    prev = None
    for x in order:
      prev = cost[:, x] if prev is None else _path_step(prev, cost[:, x], p1, p2)
      total[:, x] += prev.astype(np.uint16)
  for order in (range(h), range(h - 1, -1, -1)):
    prev = None
    for y in order:
      prev = cost[y] if prev is None else _path_step(prev, cost[y], p1, p2)
      total[y] += prev.astype(np.uint16)
  return total


def _winner(volume: np.ndarray, min_disparity: int, invalid: int) -> np.ndarray:
  """argmin over the last axis plus a parabola sub-pixel offset, as disparities."""
  depth = volume.shape[-1]
  index = np.argmin(volume, axis=-1)
  at = lambda i: np.take_along_axis(  # pylint: disable=g-long-lambda
      volume, np.clip(i, 0, depth - 1)[..., None], -1)[..., 0].astype(np.float32)
  best, lower, upper = at(index), at(index - 1), at(index + 1)
  curvature = lower - 2.0 * best + upper
  usable = ((index > 0) & (index < depth - 1) & (curvature > 0) &
            (lower < invalid) & (upper < invalid))
  offset = np.where(usable, 0.5 * (lower - upper) / np.maximum(curvature, 1e-6), 0.0)
  return (min_disparity + index + np.clip(offset, -0.5, 0.5)).astype(np.float32)


def select_disparities(total: np.ndarray,
                       min_disparity: int) -> Tuple[np.ndarray, np.ndarray]:
  """Winner-take-all left and right disparities from one aggregated left volume.

  Args:
    total: uint16 [H, W, D] aggregated costs, left-referenced: total[y, x, i] scores the
      left pixel x against the right pixel x - d_i, d_i = min_disparity + i.
    min_disparity: pixels.

  Returns:
    (disparity_left, disparity_right): float32 [H, W] pixels, parabola sub-pixel refined.
    The right pixel x takes argmin_i total[y, x + d_i, i] (the diagonal of the volume;
    disparities reaching past the right border are never chosen).
  """
  h, w, depth = total.shape
  invalid = np.iinfo(np.uint16).max
  left = _winner(total, min_disparity, invalid)
  diagonal = np.full((h, w, depth), invalid, np.uint16)
  for i in range(depth):
    d = min_disparity + i
    if d < w:
      diagonal[:, :w - d, i] = total[:, d:, i]
  return left, _winner(diagonal, min_disparity, invalid)


def lr_check(disparity_left: np.ndarray, disparity_right: np.ndarray,
             threshold: float) -> Tuple[np.ndarray, np.ndarray]:
  """Left-right consistency on [H, W] maps (pixels); nearest-pixel lookup of the match.

  Returns:
    (consistent_left, consistent_right): bool [H, W]. A left pixel x is consistent when
    its match m = round(x - d_L) is inside the image and |d_L(x) - d_R(m)| <= threshold;
    symmetrically m = round(x + d_R) for the right map. NaN disparities (no estimate, e.g.
    occlusions of a forward-warped map) are inconsistent.
  """
  w = disparity_left.shape[1]
  cols = np.arange(w, dtype=np.float32)[None, :]

  def check(own, other, sign):
    finite = np.isfinite(own)
    match = np.rint(cols + sign * np.where(finite, own, 0.0)).astype(np.int64)
    inside = finite & (match >= 0) & (match < w)
    looked_up = np.take_along_axis(other, np.clip(match, 0, w - 1), axis=1)
    return inside & (np.abs(own - looked_up) <= threshold)

  return check(disparity_left, disparity_right, -1.0), check(disparity_right, disparity_left, 1.0)


def fill_holes(disparity: np.ndarray, valid: np.ndarray) -> np.ndarray:
  """Background-favouring scanline fill: each invalid pixel takes the smaller of the
  nearest valid disparities to its left and right in its row (the only one if just one
  exists; rows without any valid pixel take the image's smallest valid disparity, or 0).

  Args:
    disparity: float [H, W], pixels; valid: bool [H, W].

  Returns:
    float32 [H, W].
  """
  h, w = disparity.shape
  cols = np.broadcast_to(np.arange(w), (h, w))
  left_idx = np.maximum.accumulate(np.where(valid, cols, -1), axis=1)
  right_idx = np.minimum.accumulate(np.where(valid, cols, w)[:, ::-1], axis=1)[:, ::-1]
  from_left = np.where(left_idx >= 0, np.take_along_axis(
      disparity, np.clip(left_idx, 0, w - 1), axis=1), np.inf)
  from_right = np.where(right_idx < w, np.take_along_axis(
      disparity, np.clip(right_idx, 0, w - 1), axis=1), np.inf)
  filled = np.where(valid, disparity, np.minimum(from_left, from_right))
  default = float(disparity[valid].min()) if valid.any() else 0.0
  return np.where(np.isfinite(filled), filled, default).astype(np.float32)


def match(left: np.ndarray, right: np.ndarray, config: SgmConfig) -> dict:
  """Full census-SGM stereo on two images of one size.

  Args:
    left, right: [H, W] or [H, W, K] intensities (K may differ between the two). With
      several channels the cost is the mean Hamming distance over all (left channel,
      right channel) pairs, so e.g. an anaglyph's red left view is matched against both
      the green and the blue right channel.
    config: matching parameters.

  Returns:
    'disparity_left', 'disparity_right': float32 [H, W] pixels, filled everywhere;
    'consistent_left', 'consistent_right': bool [H, W] left-right check before filling.
  """
  left = np.asarray(left, np.float32)
  right = np.asarray(right, np.float32)
  left = left[..., None] if left.ndim == 2 else left
  right = right[..., None] if right.ndim == 2 else right
  if left.ndim != 3 or right.ndim != 3 or left.shape[:2] != right.shape[:2]:
    raise ValueError(f'match needs two [H, W] or [H, W, K] images of one size, got '
                     f'{left.shape} and {right.shape}.')
  max_disparity = min(config.max_disparity, left.shape[1] - 1)
  if max_disparity <= config.min_disparity:
    raise ValueError(f'Image width {left.shape[1]} leaves no disparity range above '
                     f'min_disparity={config.min_disparity}.')
  window = (config.census_height, config.census_width)
  bits = config.census_height * config.census_width - 1
  codes_left = [census_transform(left[..., c], *window) for c in range(left.shape[-1])]
  codes_right = [census_transform(right[..., c], *window) for c in range(right.shape[-1])]
  volume = None
  for code_left in codes_left:
    for code_right in codes_right:
      pair = cost_volume(code_left, code_right, config.min_disparity, max_disparity,
                         out_of_image_cost=bits // 2).astype(np.uint16)
      volume = pair if volume is None else volume + pair
  pairs = len(codes_left) * len(codes_right)
  return match_volume(((volume + pairs // 2) // pairs).astype(np.uint8), config)


def match_volume(volume: np.ndarray, config: SgmConfig) -> dict:
  """SGM, disparity selection and post-processing of a left-referenced cost volume.

  Args:
    volume: uint8 [H, W, D] costs; volume[y, x, i] scores the left pixel x against the
      right pixel x - d_i, d_i = config.min_disparity + i.
    config: penalties and left-right threshold.

  Returns:
    As `match`.
  """
  total = aggregate(volume, config.p1, config.p2)
  del volume
  d_left, d_right = select_disparities(total, config.min_disparity)
  del total
  return postprocess(d_left, d_right, config.lr_threshold)


def postprocess(disparity_left: np.ndarray, disparity_right: np.ndarray,
                lr_threshold: float) -> dict:
  """3x3 median of both maps, left-right check, background-favouring fill.

  Args:
    disparity_left, disparity_right: float32 [H, W] winner-take-all disparities, pixels
      (any sign; a value that cannot pass the check, e.g. far outside the range, marks a
      pixel without a match).
    lr_threshold: pixels, as `lr_check`.

  Returns:
    As `match`.
  """
  d_left = cv2.medianBlur(np.ascontiguousarray(disparity_left, np.float32), 3)
  d_right = cv2.medianBlur(np.ascontiguousarray(disparity_right, np.float32), 3)
  ok_left, ok_right = lr_check(d_left, d_right, lr_threshold)
  return {'disparity_left': fill_holes(d_left, ok_left),
          'disparity_right': fill_holes(d_right, ok_right),
          'consistent_left': ok_left, 'consistent_right': ok_right}
