"""The numba kernel of `diplopia_costs.self_matching_volume`: ZNCC of an image against itself
shifted, every lag, row block by row block.

For lag d, the cost of pixel (y, x) is (1 - zncc) * scale with

    zncc = box(h(.) h(. - d))(y, x) / sqrt(box(h^2)(y, x) box(h^2)(y, x - d) + 1e-6),

box the (2r + 1)^2 mean with OpenCV's default border (reflect-101: row -1 is row 1) over
the product taken as zero at columns x < d (what OpenCV's box filter of that zero-padded
product gives; tests/classical/zncc_kernel_test.py transcribes it so); columns x < d get
the cost `scale`. Rows are independent given their window, so row blocks run in Python
threads (the kernel releases the GIL) and stay in cache. Within a block the window's
vertical sums roll from row to row (one row in, one out: 2 products per pixel and lag
instead of 2r + 1), in float64 so that the rolling adds no drift; all lags are carried
side by side, the innermost loop over the lags (independent sums, and out's last axis
written in order). Reads at x - d use unsigned indices: numba wraps negative signed
indices, and that branch kept LLVM from vectorising the lag loops (0.145 -> 0.074 s on
one core for a 720p frame and 60 lags). Values float32; lags and radii in pixels.
"""

import numba
import numpy as np


@numba.njit(error_model='numpy')
def _reflect(index, size):
  """OpenCV's BORDER_REFLECT_101 index of `index` in [0, size)."""
  if size == 1:
    return 0
  while index < 0 or index >= size:
    index = -index if index < 0 else 2 * size - 2 - index
  return index


@numba.njit(nogil=True, cache=True, error_model='numpy')
def zncc_rows(y0, y1, high, energy, first_lag, count, radius, scale, out, penalty, sums):
  """Costs of rows [y0, y1) for the lags d_i = first_lag + i, i < count, into out[y, x, i].

  Every lag's window sums are kept side by side ([W, D] vertical sums, [D] horizontal
  running sums), so the innermost loop runs over the lags. Each lag's sums take the same
  steps in the same order as one lag at a time would.

  Args:
    y0, y1: the row block.
    high: float32 [H, W], the high-passed image.
    energy: float32 [H, W], box(high^2) (OpenCV's boxFilter, normalised).
    first_lag, count: the lags, first_lag >= 1.
    radius: window radius r.
    scale: cost units per unit of (1 - zncc).
    out, penalty: float32 [H, W, D] and None: the costs (`scale` at columns x < d_i);
      uint8 [H, W, D] and float32 [D]: the costs as `quantize_rows` quantises them with
      that per-lag penalty; None and None: only the sums (a pass that stores nothing).
    sums: float64 [D], each lag's cost summed over the block's columns x >= d_i
      (accumulated: the caller's per-lag means).
  """
  height, width = high.shape
  size = 2 * radius + 1
  norm = 1.0 / (size * size)
  column = np.zeros((width, count), np.float64)
  total = np.empty(count, np.float64)
  # The columns entering and leaving the horizontal window after column x (reflect-101).
  enter, leave = np.empty(width, np.int64), np.empty(width, np.int64)
  for x in range(width):
    enter[x], leave[x] = _reflect(x + radius + 1, width), _reflect(x - radius, width)
  every = min(first_lag + count - 1, width)  # From this column on every lag is inside.
  # Vertical sums of the zero-padded products over the first row's window, then rolled
  # down the block: the next window drops row reflect(y - r) and adds reflect(y + r + 1)
  # (as multisets of rows, reflect-101 included).
  for dy in range(-radius, radius + 1):
    _add_products(column, high, _reflect(y0 + dy, height), first_lag, 1.0)
  for y in range(y0, y1):
    # Horizontal window sums (reflect-101 at both ends), normalised.
    total[:] = 0.0
    for dx in range(-radius, radius + 1):
      start = _reflect(dx, width)
      for i in range(count):
        total[i] += column[start, i]
    for x in range(width):
      entering, leaving, here = enter[x], leave[x], energy[y, x]
      # Lags i < inside have d_i <= x (all of them from column `every` on: no branch).
      inside = count if x >= every else max(0, min(count, x - first_lag + 1))
      for i in range(inside):
        back = np.uint64(x - first_lag - i)  # >= 0 here; unsigned: see the module docstring.
        denominator = np.sqrt(here * energy[y, back] + np.float32(1e-6))
        cost = np.float32((1.0 - total[i] * norm / denominator) * scale)
        _store(out, penalty, y, x, i, cost)
        sums[i] += cost
        total[i] += column[entering, i] - column[leaving, i]
      for i in range(inside, count):
        _store(out, penalty, y, x, i, np.float32(scale))
        total[i] += column[entering, i] - column[leaving, i]
    if y + 1 < y1:
      _add_products(column, high, _reflect(y - radius, height), first_lag, -1.0)
      _add_products(column, high, _reflect(y + radius + 1, height), first_lag, 1.0)


@numba.njit(nogil=True, cache=True, error_model='numpy')
def _store(out, penalty, y, x, i, cost):
  """out[y, x, i] = cost (penalty None), or its `quantize_rows` value (penalty [D]); nothing
  when out is None. numba prunes the None branches when it compiles each combination."""
  if out is not None:
    if penalty is None:
      out[y, x, i] = cost
    else:
      out[y, x, i] = _quantized(cost, penalty[i])


@numba.njit(nogil=True, cache=True, error_model='numpy')
def _quantized(cost, penalty):
  """clip(rint(cost + penalty), 0, 255) as uint8 (float32 arithmetic)."""
  value = np.rint(cost + penalty)
  return np.uint8(min(max(value, np.float32(0.0)), np.float32(255.0)))


@numba.njit(nogil=True, cache=True, error_model='numpy')
def _add_products(column, high, row, first_lag, sign):
  """column[x, i] += sign * high[row, x] * high[row, x - d_i] for x >= d_i = first_lag + i
  (float64 sums)."""
  count = column.shape[1]
  for x in range(high.shape[1]):
    value = np.float64(high[row, x])
    for i in range(min(count, x - first_lag + 1)):
      column[x, i] += sign * (value * np.float64(high[row, np.uint64(x - first_lag - i)]))


@numba.njit(nogil=True, cache=True, error_model='numpy')
def quantize_rows(y0, y1, costs, penalty, out):
  """out[y, x, i] = clip(rint(costs[y, x, i] + penalty[i]), 0, 255) for rows [y0, y1)
  (uint8 [H, W, D] from float32 [H, W, D] and float32 [D])."""
  for y in range(y0, y1):
    for x in range(costs.shape[1]):
      for i in range(costs.shape[2]):
        out[y, x, i] = _quantized(costs[y, x, i], penalty[i])


@numba.njit(nogil=True, cache=True, error_model='numpy')
def prior_rows(y0, y1, lo, widths, first_lag, weight, cap, volume):
  """volume[y, x, i] += min(weight * (distance of the lag first_lag + i to the window
  lo[y, x] + [0, widths[y, x])), cap), saturating at 255, for rows [y0, y1) (a temporal
  prior's penalty; uint8 [H, W, D] volume, int32 [H, W] windows, weight and cap in cost
  units per pixel and cost units)."""
  for y in range(y0, y1):
    for x in range(volume.shape[1]):
      low = np.int32(lo[y, x] - first_lag)  # The window in lag indices.
      high = np.int32(low + widths[y, x] - 1)
      for i in range(volume.shape[2]):
        distance = max(low - i, np.int32(0), i - high)
        added = min(np.int32(weight) * distance, np.int32(cap))
        volume[y, x, i] = np.uint8(min(np.int32(volume[y, x, i]) + added, np.int32(255)))
