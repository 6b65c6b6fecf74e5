"""Cost volumes from per-pixel descriptors (any extractor: the learned matching features of
`models/matching_features.py`), for the SGM of stored volumes (`parallel_sgm`).

cost[y, x, i] = clip(round((1 - <left[y, x], right[y, x - d_i]>) * scale), 0, 255), uint8,
d_i = min_disparity + i (left-referenced, signed pixels: the left pixel x matches the
right pixel x - d); for unit descriptors the dot product is the cosine, so the cost lies in
[0, 2 * scale]. Where x - d_i falls outside the image the cost is `outside`. Rows are
shared among threads (the kernel releases the GIL). `blend` mixes such a volume with
another (the census matcher's) in place, one pass instead of NumPy's five.
"""

import numba
import numpy as np

from mixstereo_tf.classical import census_costs
from mixstereo_tf.core import workers


@numba.njit(fastmath=True, **census_costs.JIT)
def _rows(left, right, y0, y1, min_disparity, scale, outside, out):
  """out[y] for y in [y0, y1) (module docstring); left, right float32 [H, W, C]."""
  _, w, c = left.shape
  depth = out.shape[2]
  for y in range(y0, y1):
    for x in range(w):
      for i in range(depth):
        xr = x - (min_disparity + i)
        if xr < 0 or xr >= w:
          out[y, x, i] = outside
          continue
        dot = np.float32(0.0)
        for k in range(c):
          dot += left[y, x, k] * right[y, xr, k]
        v = (np.float32(1.0) - dot) * scale + np.float32(0.5)
        out[y, x, i] = np.uint8(min(max(v, np.float32(0.0)), np.float32(255.0)))


def cosine_costs(left: np.ndarray, right: np.ndarray, min_disparity: int,
                 num_disparities: int, scale: float, outside: int = 255,
                 threads: int = 1) -> np.ndarray:
  """The module docstring's uint8 cost volume.

  Args:
    left, right: float [H, W, C] descriptors of the two views (unit vectors).
    min_disparity: d_0, signed pixels; num_disparities: D.
    scale: cost units per unit of (1 - dot).
    outside: the cost of a match outside the right image, 0..255.
    threads: worker threads (row blocks).

  Returns:
    uint8 [H, W, D].
  """
  left = np.ascontiguousarray(left, np.float32)
  right = np.ascontiguousarray(right, np.float32)
  if left.ndim != 3 or left.shape != right.shape:
    raise ValueError(f'left and right descriptors must be [H, W, C] of one shape, got '
                     f'{left.shape} and {right.shape}.')
  if num_disparities <= 0 or not 0 <= outside <= 255:
    raise ValueError(f'need num_disparities > 0 and outside in [0, 255], got '
                     f'{num_disparities} and {outside}.')
  h = left.shape[0]
  out = np.empty((h, left.shape[1], num_disparities), np.uint8)
  workers.run_tasks(lambda t: _rows(left, right, t[0], t[1], int(min_disparity),
                                    np.float32(scale), np.uint8(outside), out),
                    workers.row_blocks(h, max(1, threads)), max(1, threads))
  return out


@numba.njit(**census_costs.JIT)
def _blend_rows(other, volume, y0, y1, weight):
  """volume[y] = rint(weight * other[y] + (1 - weight) * volume[y]) for y in [y0, y1), in
  `blend`'s arithmetic."""
  own = np.float32(weight)
  rest = 1.0 - weight
  _, w, depth = volume.shape
  for y in range(y0, y1):
    for x in range(w):
      for i in range(depth):
        mixed = np.float64(own * np.float32(other[y, x, i])) + rest * np.float64(volume[y, x, i])
        volume[y, x, i] = np.uint8(np.rint(mixed))


def blend(other: np.ndarray, volume: np.ndarray, weight: float, threads: int = 1) -> np.ndarray:
  """`volume` (uint8 [H, W, D], C-contiguous) overwritten with
  rint(weight * other + (1 - weight) * volume), bit for bit NumPy's
  `np.rint(weight * other.astype(np.float32) + (1 - weight) * volume).astype(np.uint8)`
  (the first product in float32, the rest in float64); returns it.

  Raises:
    ValueError: volumes of different shapes or types, or a weight outside [0, 1].
  """
  if (other.shape != volume.shape or other.dtype != np.uint8 or volume.dtype != np.uint8
      or not volume.flags.c_contiguous or not 0.0 <= weight <= 1.0):
    raise ValueError(f'blend needs two uint8 volumes of one shape (the second C-contiguous) '
                     f'and a weight in [0, 1]; got {other.dtype}{other.shape}, '
                     f'{volume.dtype}{volume.shape} and {weight}.')
  workers.run_tasks(lambda t: _blend_rows(other, volume, t[0], t[1], float(weight)),
                    workers.row_blocks(volume.shape[0], max(1, threads)),
                    max(1, threads))
  return volume
