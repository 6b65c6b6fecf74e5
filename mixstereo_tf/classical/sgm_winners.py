"""Winner search of an SGM row: the left disparities (least aggregated cost, a parabola
through its neighbours) and the right ones along the volume's diagonal, as `sgm._winner`
and `sgm.select_disparities` compute them, for the numba kernels of `census_sgm` (a row's
windows laid out back to back, pixel x's from offsets[x] on).
"""

import numba
import numpy as np

from mixstereo_tf.classical import census_costs

_NONE = np.int64(2 ** 63 - 1)  # No candidate yet (right winners).
_INNER = census_costs.INNER


@numba.njit(**_INNER)
def _refined(base, lower, best, upper):
  """base + the parabola offset through three costs, in float32 as `sgm._winner`."""
  lower, best, upper = np.float32(lower), np.float32(best), np.float32(upper)
  curvature = lower - np.float32(2.0) * best + upper
  offset = np.float32(0.0)
  if curvature > 0:
    offset = min(np.float32(0.5), max(np.float32(-0.5),
                                      np.float32(0.5) * (lower - upper) / curvature))
  return np.float32(np.float64(base) + np.float64(offset))


@numba.njit(**_INNER)
def winners(s, offsets, lo, nds, y, dl, dr, best):
  """Left winners of the row's aggregated costs and right winners along the diagonal.

  s: int32 flat costs (>= 0), pixel x at offsets[x] + [0, nds[y, x]); best: int64 [W]
  scratch. Right pixels no left pixel reaches get NaN. Both searches take the least
  (cost << 32 | index) key, which keeps the first of equal costs as a running minimum
  would, in branch-free loops over unsigned indices: numba wraps negative signed indices,
  and that branch kept LLVM from vectorising them (0.100 -> 0.034 s for the winners of a
  1280 x 720 x 60 volume on one core).
  """
  w = dl.shape[1]
  for x in range(w):
    base, nd = offsets[x], nds[y, x]
    least = _NONE
    for i in range(nd):
      key = (np.int64(s[np.uint64(base + i)]) << 32) | i
      least = key if key < least else least
    bi = np.int64(least & 0xFFFFFFFF) if nd > 0 else 0
    if 0 < bi < nd - 1:
      dl[y, x] = _refined(lo[y, x] + bi, s[base + bi - 1], s[base + bi], s[base + bi + 1])
    else:
      dl[y, x] = lo[y, x] + bi
  # Right winners: per right pixel the least (cost, left column) key.
  best[:] = _NONE
  for x in range(w):
    base = offsets[x]
    xr0 = x - lo[y, x]  # Right pixel of window position 0; position i -> xr0 - i.
    first, stop = max(0, xr0 - w + 1), min(nds[y, x], xr0 + 1)
    low_right = xr0 - stop + 1  # Right pixels [low_right, xr0 - first], ascending.
    for k in range(stop - first):
      xr = np.uint64(low_right + k)
      key = (np.int64(s[np.uint64(base + stop - 1 - k)]) << 32) | x
      kept = best[xr]
      best[xr] = key if key < kept else kept
  for xr in range(w):
    if best[xr] == _NONE:
      dr[y, xr] = np.nan
      continue
    cost, d = np.int32(best[xr] >> 32), np.int32(best[xr] & 0xFFFFFFFF) - xr
    dr[y, xr] = d
    xa, xb = xr + d - 1, xr + d + 1  # Diagonal neighbours: left x -+ 1 at d -+ 1.
    if 0 <= xa and xb < w:
      ia, ib = d - 1 - lo[y, xa], d + 1 - lo[y, xb]
      if 0 <= ia < nds[y, xa] and 0 <= ib < nds[y, xb]:
        dr[y, xr] = _refined(d, s[offsets[xa] + ia], cost, s[offsets[xb] + ib])
