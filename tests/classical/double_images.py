"""A drawn double-image scene the double-image tests share: known edges, a known shift."""

import numpy as np

H, W, D = 24, 160, 7


def steps_pair(seed=0):
  """A left view of vertical steps 20-40 px apart (distinct levels per 8-row band), the
  right view = left shifted by D (R(x) = L(x + D)), float [H, W, 3] in [0, 1]."""
  rng = np.random.default_rng(seed)
  wide = np.zeros((H, W + D, 3))
  for band in range(0, H, 8):
    x = 0
    while x < W + D:
      step = int(rng.integers(20, 41))
      wide[band:band + 8, x:x + step] = rng.uniform(0.1, 0.9, 3)
      x += step
  return wide[:, :W], wide[:, D:]
