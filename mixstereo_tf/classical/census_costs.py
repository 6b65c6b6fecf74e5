"""Census codes and matching costs for the numba SGM (`census_sgm`), row by row.

`census_rows` computes the census codes of a block of rows (as `sgm.census_transform`);
`cost_row` the mean Hamming cost of one row against its per-pixel disparity windows, which
`census_sgm` aggregates without storing a cost volume.
"""

import numba
import numpy as np
from numba.core import types
from numba.extending import intrinsic

# Helpers run once per pixel and path and only index arrays (never allocate or slice), so
# they are compiled without numba's reference counting (`_nrt=False`): with it, each call
# paid ~50 ns of atomic counts on its array arguments, more than the recursion on narrow
# windows (1280x720, 16 disparities: 463 -> 254 ms). The entry points allocate, release
# the GIL and are cached on disk. error_model: no ZeroDivisionError checks in the loops.
INNER = {'error_model': 'numpy', '_nrt': False}
JIT = dict(error_model='numpy', nogil=True, cache=True)



@intrinsic
def _popcount(typingctx, value):  # pylint: disable=unused-argument
  """Bits set in a uint64 (LLVM's ctpop: one instruction where the CPU has it)."""
  def codegen(context, builder, signature, args):  # pylint: disable=unused-argument
    return builder.ctpop(args[0])
  return types.uint64(types.uint64), codegen


@numba.njit(**JIT)
def census_rows(padded, height, width, out):
  """Census codes of a reflect-padded float32 block, as `sgm.census_transform`.

  out[y, x] (uint64 [rows, W]) gets bit k set where the k-th neighbour of padded[y + ry,
  x + rx] in its height x width window (row-major, centre skipped) is darker.
  """
  rows, w = out.shape
  ry, rx = height // 2, width // 2
  code = np.empty(w, np.uint64)
  for y in range(rows):
    code[:] = 0
    centre = padded[y + ry, rx:rx + w]
    for dy in range(height):
      for dx in range(width):
        if dy == ry and dx == rx:
          continue
        row = padded[y + dy, dx:dx + w]
        for x in range(w):
          code[x] = (code[x] << np.uint64(1)) | np.uint64(row[x] < centre[x])
    out[y] = code


@numba.njit(**INNER)
def cost_row(cl, cr, lo, nds, y, oob, rev, acc, out, starts):
  """out[starts[x] + i] (uint8, flat: pixel x's window from starts[x] on) = mean Hamming
  cost of left (y, x) against right (y, x - lo - i). The right codes are reversed (rev[b,
  k] = cr[b, y, W-1-k]) so the loop over i reads consecutive words and vectorises
  (indexed by unsigned ints: numba wraps negative signed indices, a branch that kept LLVM
  from vectorising; 720p x 96 lags of one row block: 0.12 -> 0.06 s); 1x1, 1x2 and 2x1
  channel pairs (plain and colour anaglyphs) have their own loops."""
  kl, _, w = cl.shape
  kr = cr.shape[0]
  pairs = kl * kr
  half = np.uint32(pairs // 2)
  one = np.uint32(1)
  for b in range(kr):
    for k in range(w):
      rev[b, k] = cr[b, y, w - 1 - k]
  for x in range(w):
    d0, nd = lo[y, x], nds[y, x]
    ia = min(nd, max(0, x - d0 - w + 1))  # i < ia: the match is right of the image.
    ib = max(ia, min(nd, x - d0 + 1))  # i >= ib: the match is left of the image.
    k0 = w - 1 - x + d0  # Window position i reads rev[., k0 + i].
    o = np.uint64(starts[x])  # Unsigned, as k below.
    for i in range(ia):
      out[o + i] = oob
    for i in range(ib, nd):
      out[o + i] = oob
    ca = cl[0, y, x]
    if pairs == 1:
      for i in range(ia, ib):
        k = np.uint64(k0 + i)
        out[o + i] = np.uint8(_popcount(ca ^ rev[0, k]))
    elif kl == 1 and kr == 2:
      for i in range(ia, ib):
        k = np.uint64(k0 + i)
        out[o + i] = np.uint8((np.uint32(_popcount(ca ^ rev[0, k])) +
                              np.uint32(_popcount(ca ^ rev[1, k])) + one) >> one)
    elif kl == 2 and kr == 1:
      cb = cl[1, y, x]
      for i in range(ia, ib):
        k = np.uint64(k0 + i)
        out[o + i] = np.uint8((np.uint32(_popcount(ca ^ rev[0, k])) +
                              np.uint32(_popcount(cb ^ rev[0, k])) + one) >> one)
    else:
      for i in range(ia, ib):
        acc[i] = 0
      for a in range(kl):
        ca = cl[a, y, x]
        for b in range(kr):
          for i in range(ia, ib):
            acc[i] += np.uint32(_popcount(ca ^ rev[b, np.uint64(k0 + i)]))
      for i in range(ia, ib):
        out[o + i] = np.uint8((acc[i] + half) // np.uint32(pairs))


@numba.njit(**JIT)
def volume_rows(cl, cr, low, y0, y1, oob, out):
  """Rows [y0, y1) of a stored census cost volume: out[y, x, i] (uint8 [H, W, D]) = the
  `cost_row` cost of left (y, x) against right (y, x - low - i)."""
  h, w, nd = out.shape
  lo = np.full((h, w), low, np.int32)
  nds = np.full((h, w), nd, np.int32)
  rev = np.empty((cr.shape[0], w), np.uint64)
  acc = np.zeros(nd, np.uint32)
  starts = np.arange(w) * nd
  for y in range(y0, y1):
    cost_row(cl, cr, lo, nds, y, oob, rev, acc, out[y].reshape(w * nd), starts)
