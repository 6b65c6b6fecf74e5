"""Known-answer tests of the SGM kernels' winner search (`sgm_winners.winners`)."""

import numpy as np
import pytest

from mixstereo_tf.classical import sgm_winners


def _parabola(base, lower, best, upper):
  """base + the parabola offset through three costs (float32, as `sgm._winner`)."""
  lower, best, upper = np.float32(lower), np.float32(best), np.float32(upper)
  curvature = lower - np.float32(2) * best + upper
  offset = np.float32(0)
  if curvature > 0:
    offset = np.clip(np.float32(0.5) * (lower - upper) / curvature, -0.5, 0.5)
  return np.float32(np.float64(base) + np.float64(offset))


def _reference(s, offsets, lo, nds, y, w):
  """Plain loops: per left pixel the first least cost, per right pixel the least (cost,
  left column) over the left pixels whose windows reach it; refined by parabolas."""
  left, best = np.zeros(w, np.float32), {}
  for x in range(w):
    costs = s[offsets[x]:offsets[x] + nds[y, x]]
    i = int(np.argmin(costs))
    left[x] = (_parabola(lo[y, x] + i, *costs[i - 1:i + 2]) if 0 < i < len(costs) - 1
               else lo[y, x] + i)
    for i, cost in enumerate(costs):
      xr = x - (lo[y, x] + i)
      if 0 <= xr < w and (xr not in best or (cost, x) < best[xr]):
        best[xr] = (cost, x)
  right = np.full(w, np.nan, np.float32)
  for xr, (cost, x) in best.items():
    d = x - xr
    right[xr] = d
    xa, xb = x - 1, x + 1  # The diagonal: left x -+ 1 at d -+ 1.
    if xa >= 0 and xb < w:
      ia, ib = d - 1 - lo[y, xa], d + 1 - lo[y, xb]
      if 0 <= ia < nds[y, xa] and 0 <= ib < nds[y, xb]:
        right[xr] = _parabola(d, s[offsets[xa] + ia], cost, s[offsets[xb] + ib])
  return left, right


@pytest.mark.parametrize('seed', range(4))
def test_winners_equal_plain_loops_with_per_pixel_windows_and_ties(seed):
  rng = np.random.default_rng(seed)
  h, w = 3, 40
  lo = rng.integers(-12, 12, (h, w)).astype(np.int32)
  nds = rng.integers(1, 12, (h, w)).astype(np.int32)
  lo[0], nds[0] = 5, 1  # Row 0 reaches no right pixel past w - 6.
  dl = np.zeros((h, w), np.float32)
  dr = np.zeros((h, w), np.float32)
  for y in range(h):
    offsets = np.concatenate([[0], np.cumsum(nds[y])]).astype(np.int64)
    s = rng.integers(0, 6, offsets[-1]).astype(np.int32)  # Many ties.
    sgm_winners.winners(s, offsets, lo, nds, y, dl, dr, np.zeros(w, np.int64))
    left, right = _reference(s, offsets, lo, nds, y, w)
    np.testing.assert_array_equal(dl[y], left)
    np.testing.assert_array_equal(dr[y], right)
  assert np.isnan(dr).any() and not np.isnan(dr).all()  # Unreached right pixels too.
