"""Census + 4-path SGM kernels compiled with numba, on per-pixel disparity windows.

The cost and the recursion are those of `sgm.py` (census codes per channel, Hamming cost
averaged over all (left channel, right channel) pairs, `oob` where the match falls outside
the right image, 4 paths with P1 / P2, winner-take-all with a parabola, the right disparity
from the diagonal of the aggregated volume), restructured so that no cost volume is stored:
  pass 1 (rows top to bottom): cost row -> left-to-right, right-to-left and top-down path
    costs -> their sum, kept as uint16 (the only per-cell array: 2 bytes per cell);
  pass 2 (rows bottom to top): the cost row again -> bottom-up path -> S = sum + L_up ->
    the row's left and right winners.

Disparity windows: pixel (y, x) searches d = lo[y, x] + i, i in [0, nds[y, x]). A full
search is one window for all pixels; windows per pixel (coarse-to-fine, a temporal prior)
cost work and memory in proportion to the sum of the widths. The recursion maps a
neighbour's window onto the current one; disparities outside the neighbour's window cost
+inf there. `parallel_sgm` runs `sgm_strip` on horizontal strips in threads (the kernels
release the GIL); the codes and the cost rows come from `census_costs`. A stored cost
volume (diplopia's self-matching) runs the same recursion in `volume_sgm`.

Compiled kernels are cached on disk (`cache=True`: `__pycache__` beside this file, or
numba's user-wide cache directory where that is not writable; NUMBA_CACHE_DIR overrides
both), so only the first process after an install or an edit compiles them.
"""

import numba
import numpy as np

from mixstereo_tf.classical import census_costs
from mixstereo_tf.classical import sgm_winners

_BIG = np.int32(30000)  # Above any path cost; _BIG + P2 still fits the int32 arithmetic.
_INNER = census_costs.INNER
_JIT = census_costs.JIT


@numba.njit(**_INNER)
def _start(cost_all, co, cur_all, do, nd):
  """First pixel of a path: cur[1 + i] = cost[i], i < nd, between _BIG guards at 0 and
  nd + 1, where cost = cost_all[co:], cur = cur_all[do:]; returns min. Rows are flat
  arrays and a pixel's window an offset into them (`_strip`); the views are taken here
  (the caller's views would cost numba reference counting at every call)."""
  cost = cost_all[co:co + nd]
  cur = cur_all[do:do + nd + 2]
  m = _BIG
  cur[0] = _BIG
  for i in range(nd):
    v = np.int32(cost[i])
    cur[i + 1] = v
    m = v if v < m else m
  cur[nd + 1] = _BIG
  return m


@numba.njit(**_INNER)
def _step(prev_all, po, pm, shift, nprev, cost_all, co, cur_all, do, nd, p1, p2, tmp):
  """One SGM recursion L(d) = C(d) + min(L'(d), L'(d +- 1) + P1, min L' + P2) - min L'.

  prev = prev_all[po:], cur = cur_all[do:]: the neighbour's and this pixel's path costs
  as `_start` lays them out (window position i at index 1 + i, _BIG guards around);
  cost = cost_all[co:], this pixel's costs. The neighbour's window starts `shift`
  disparities lower and has nprev positions; a shifted or resized one is first copied
  into `tmp`, aligned with the current window, so the recursion is always the same
  branch-free loop (selects on int32 vectorise, numba's float min does not). Returns
  min L.
  """
  prev = prev_all[po:po + nprev + 2]
  cost = cost_all[co:co + nd]
  cur = cur_all[do:do + nd + 2]
  src = prev
  if shift != 0 or nprev != nd:
    a = min(nd + 2, max(0, 1 - shift))  # tmp[k] = prev[k + shift] for k in [a, b).
    b = max(a, min(nd + 2, nprev + 1 - shift))
    for k in range(a):
      tmp[k] = _BIG
    for k in range(a, b):
      tmp[k] = prev[k + shift]
    for k in range(b, nd + 2):
      tmp[k] = _BIG
    src = tmp
  lim = np.int32(pm + p2)
  m = _BIG
  cur[0] = _BIG
  for i in range(nd):
    same, lower, upper = src[i + 1], src[i], src[i + 2]
    q = np.int32((lower if lower < upper else upper) + p1)
    same = same if same < lim else lim
    v = np.int32(np.int32(cost[i]) + (same if same < q else q) - pm)
    cur[i + 1] = v
    m = v if v < m else m
  cur[nd + 1] = _BIG
  return m


@numba.njit(**_JIT)
def _window_offsets(nds, y0, n, w):
  """(offsets, widest window, most cells of a row) of rows [y0, y0 + n): pixel
  (y0 + k, x) at offsets[k * w + x]."""
  offsets = np.zeros(n * w + 1, np.int64)
  nd, row = 1, 1
  for k in range(n):
    for x in range(w):
      offsets[k * w + x + 1] = offsets[k * w + x] + nds[y0 + k, x]
      nd = max(nd, nds[y0 + k, x])
    row = max(row, offsets[(k + 1) * w] - offsets[k * w])
  return offsets, nd, row


@numba.njit(**_INNER)
def _row_starts(offsets, k, w, cs, gs):
  """Row k's flat layouts: pixel x's costs at cs[x] (its cells before it), its path costs
  with their two guards at gs[x] = cs[x] + 2 x."""
  base = offsets[k * w]
  for x in range(w):
    cs[x] = offsets[k * w + x] - base
    gs[x] = cs[x] + 2 * x


@numba.njit(**_JIT)
def _down_row(crow, lo, nds, y, first, pen1, pen2, hor, vprev, vcur, vpm, t12, tmp, total,
              base, cs, gs, gs_prev):
  """Pass 1 on row y: left-to-right (hor), top-down (vcur), right-to-left (t12: two
  pixels' rows of len(tmp) each) paths; their sum goes to total[base + cs[x] + i]. Row
  layouts cs, gs (this row), gs_prev (vprev's, the row above) as `_row_starts`'."""
  w = lo.shape[1]
  tw = tmp.shape[0]
  pm = _start(crow, cs[0], hor, gs[0], nds[y, 0])
  for x in range(1, w):
    pm = _step(hor, gs[x - 1], pm, lo[y, x] - lo[y, x - 1], nds[y, x - 1], crow, cs[x], hor,
               gs[x], nds[y, x], pen1, pen2, tmp)
  for x in range(w):
    if first:
      vpm[x] = _start(crow, cs[x], vcur, gs[x], nds[y, x])
    else:
      vpm[x] = _step(vprev, gs_prev[x], vpm[x], lo[y, x] - lo[y - 1, x], nds[y - 1, x], crow,
                     cs[x], vcur, gs[x], nds[y, x], pen1, pen2, tmp)
  for x in range(w - 1, -1, -1):
    now = (x & 1) * tw  # This pixel's row of t12; pixel x + 1 used the other one.
    if x == w - 1:
      pm = _start(crow, cs[x], t12, now, nds[y, x])
    else:
      pm = _step(t12, tw - now, pm, lo[y, x] - lo[y, x + 1], nds[y, x + 1], crow, cs[x], t12,
                 now, nds[y, x], pen1, pen2, tmp)
    out, g = np.uint64(base + cs[x]), np.uint64(gs[x] + 1)
    for i in range(nds[y, x]):  # Unsigned indices vectorise (`sgm_winners.winners`).
      k = np.uint64(i)
      total[out + k] = np.uint16(t12[np.uint64(now + 1) + k] + hor[g + k] + vcur[g + k])


@numba.njit(**_JIT)
def _up_row(crow, lo, nds, y, first, pen1, pen2, vprev, vcur, vpm, total, base, srow, cs, gs,
            gs_prev, tmp):
  """Pass 2 on row y: the bottom-up path (vprev laid out by gs_prev, the row below);
  srow[cs[x] + i] = total[base + cs[x] + i] + L_up."""
  w = lo.shape[1]
  for x in range(w):
    if first:
      vpm[x] = _start(crow, cs[x], vcur, gs[x], nds[y, x])
    else:
      vpm[x] = _step(vprev, gs_prev[x], vpm[x], lo[y, x] - lo[y + 1, x], nds[y + 1, x], crow,
                     cs[x], vcur, gs[x], nds[y, x], pen1, pen2, tmp)
    c, g = np.uint64(cs[x]), np.uint64(gs[x] + 1)
    for i in range(nds[y, x]):  # Unsigned indices vectorise (`sgm_winners.winners`).
      k = np.uint64(i)
      srow[c + k] = np.int32(total[np.uint64(base) + c + k]) + vcur[g + k]


@numba.njit(**_JIT)
def sgm_strip(cl, cr, lo, nds, y0, y1, w0, w1, p1, p2, oob, dl, dr):
  """SGM over rows [y0, y1); writes the winners of rows [w0, w1) into dl, dr.

  Args:
    cl, cr: uint64 [K_L, H, W], [K_R, H, W] census codes (C-contiguous).
    lo, nds: int32 [H, W] windows: pixel (y, x) searches lo + [0, nds), nds >= 1.
    y0, y1, w0, w1: rows aggregated and rows written (y0 <= w0 < w1 <= y1).
    p1, p2: SGM penalties; oob: uint8 cost of a match outside the right image.
    dl, dr: float32 [H, W] outputs: the left pixel x matches the right pixel x - dl, the
      right pixel x matches the left pixel x + dr (NaN where no window reaches it).
  """
  _strip(cl, cr, np.empty((0, 0, 0), np.uint8), lo, nds, y0, y1, w0, w1, p1, p2, oob, dl,
         dr)


@numba.njit(**_JIT)
def volume_sgm(volume, min_disparity, p1, p2, dl, dr, rows=None):
  """SGM of a stored cost volume over rows [y0, y1), winners of rows [w0, w1) written
  (`rows` = (y0, y1, w0, w1); None: the whole image, one strip: the winners of
  `sgm.aggregate` and `sgm.select_disparities`, bit for bit).

  Args:
    volume: uint8 [H, W, D] C-contiguous; volume[y, x, i] scores the left pixel x against
      the right pixel x - d_i, d_i = min_disparity + i (diplopia's self-matching costs).
    min_disparity: pixels; p1, p2: SGM penalties.
    dl, dr: float32 [H, W] outputs, as `sgm_strip`'s.
    rows: the strip, as `sgm_strip`'s y0, y1, w0, w1.
  """
  h, w, depth = volume.shape
  y0, y1, w0, w1 = rows or (0, h, 0, h)
  codes = np.empty((0, h, w), np.uint64)
  _strip(codes, codes, volume, np.full((h, w), min_disparity, np.int32),
         np.full((h, w), depth, np.int32), y0, y1, w0, w1, p1, p2, np.uint8(0), dl, dr)


@numba.njit(**_JIT)
def _cost_rows(volume, cl, cr, lo, nds, y, oob, rev, acc, crow, cs):
  """Row y's costs into crow (pixel x's from cs[x] on): the census codes'
  (`census_costs.cost_row`), or the stored volume's row when `volume` has rows (all
  windows its depth wide, so the row is laid out as stored: one copy)."""
  if volume.shape[0] == 0:
    census_costs.cost_row(cl, cr, lo, nds, y, oob, rev, acc, crow, cs)
    return
  cells = volume.shape[1] * volume.shape[2]
  crow[:cells] = volume[y].reshape(cells)


@numba.njit(**_JIT)
def _strip(cl, cr, volume, lo, nds, y0, y1, w0, w1, p1, p2, oob, dl, dr):
  """`sgm_strip` on the costs of the codes cl, cr or, when it has rows, of `volume`. Row
  buffers hold one image row's windows back to back (`_row_starts`), so they scale with
  the row's cells, not with its widest window times the width."""
  _, _, w = cl.shape
  n = y1 - y0
  pen1, pen2 = np.int32(p1), np.int32(p2)
  offsets, nd, row = _window_offsets(nds, y0, n, w)
  total = np.empty(offsets[n * w], np.uint16)
  crow = np.empty(row, np.uint8)
  rev = np.empty((cr.shape[0], w), np.uint64)
  acc = np.zeros(nd, np.uint32)
  hor = np.empty(row + 2 * w, np.int32)
  vprev = np.empty(row + 2 * w, np.int32)
  vcur = np.empty(row + 2 * w, np.int32)
  vpm = np.zeros(w, np.int32)
  t12 = np.empty(2 * (nd + 2), np.int32)
  tmp = np.empty(nd + 2, np.int32)
  cs = np.empty(w, np.int64)
  gs = np.empty(w, np.int64)
  gs_prev = np.empty(w, np.int64)
  for k in range(n):
    _row_starts(offsets, k, w, cs, gs)
    _cost_rows(volume, cl, cr, lo, nds, y0 + k, oob, rev, acc, crow, cs)
    _down_row(crow, lo, nds, y0 + k, k == 0, pen1, pen2, hor, vprev, vcur, vpm, t12, tmp,
              total, offsets[k * w], cs, gs, gs_prev)
    vprev, vcur = vcur, vprev
    gs, gs_prev = gs_prev, gs
  srow = np.empty(row, np.int32)
  best = np.empty(w, np.int64)
  for k in range(n - 1, -1, -1):
    y = y0 + k
    _row_starts(offsets, k, w, cs, gs)
    _cost_rows(volume, cl, cr, lo, nds, y, oob, rev, acc, crow, cs)
    _up_row(crow, lo, nds, y, k == n - 1, pen1, pen2, vprev, vcur, vpm, total, offsets[k * w],
            srow, cs, gs, gs_prev, tmp)
    vprev, vcur = vcur, vprev
    gs, gs_prev = gs_prev, gs
    if w0 <= y < w1:
      sgm_winners.winners(srow, cs, lo, nds, y, dl, dr, best)
