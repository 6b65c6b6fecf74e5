"""The mixing weight a of a double image I = a L + (1 - a) R, from its echoes.

An edge of the left view at x shows twice in I: at x with weight a (the left view's copy)
and at x - d_L(x) with weight 1 - a (the right view's, positive disparities). Where both
copies are clear edges of one sign, |g(x)| / (|g(x)| + |g(x - d_L)|) of the horizontal
gradient g of I is a: `echo_histogram` gathers it over such pairs (weights: the smaller
magnitude, so clear echoes count most), `echo_peak` finds their peak beside the spread of
unrelated pairs around 1/2, `estimate_weight` does both. Second-order statistics cannot:
the power spectrum a^2 + (1 - a)^2 + 2 a (1 - a) cos(w d) is the same for a and 1 - a.
"""

from typing import Optional, Tuple

import cv2
import numpy as np
import scipy.optimize

AUTO = 'auto'  # A mixing weight estimated from the image (`estimate_weight`).
# Said where AUTO found too few echo pairs to estimate a from (`resolve_weight`).
NO_ECHO = ('no clear echo to estimate it from (too few isolated echo pairs): 1/2 used; '
           'name the weight (--mixing_weight) if known')
# The ratio histogram's bin centres, and the spreads fitted by `echo_peak` (chosen on
# validation double images: docs/LEARNED_DIPLOPIA.md, "Estimating a").
RATIO_BINS = 0.05 + 0.01 * (np.arange(90) + 0.5)
BACKGROUND_SPREADS = tuple(0.04 + 0.02 * k for k in range(9))  # 0.04 to 0.2.
ECHO_SPREAD = 0.03


def check_weight(weight: float) -> float:
  """`weight` as a float in (0, 1), or ValueError naming it."""
  if not 0.0 < float(weight) < 1.0:
    raise ValueError(f'The mixing weight a of I = a L + (1 - a) R must lie in (0, 1), got '
                     f'{weight!r}.')
  return float(weight)


def _lagged(values: np.ndarray, lag: np.ndarray):
  """values[y, x + lag[y, x]] (clipped) and whether x + lag lies inside the row."""
  width = values.shape[1]
  column = np.arange(width)[None, :] + lag
  inside = (column >= 0) & (column < width)
  return np.take_along_axis(values, np.clip(column, 0, width - 1), axis=1), inside


def echo_histogram(mixture01: np.ndarray, d_left: np.ndarray, consistent: np.ndarray,
                   quantile: float = 0.9, isolation: float = 0.25, min_lag: int = 5,
                   min_pairs: int = 30) -> Optional[np.ndarray]:
  """The echo ratios' histogram over RATIO_BINS (module docstring), or None where fewer
  than `min_pairs` pairs show (no clear echo: fine, dense texture).

  Pairs: consistent left pixels x with d = round(d_L(x)) >= `min_lag` (nearer copies'
  gradients overlap), |g(x)| + |g(x - d)| at least the `quantile` of |g|, one sign, and
  isolated: |g(x + d)| and |g(x - 2 d)| (where a third copy of an unrelated edge would show)
  below `isolation` times the weaker copy; each counts |g(x)| / (|g(x)| + |g(x - d)|),
  weighted by the weaker copy.

  Args:
    mixture01: float [H, W, 3] (or [H, W]) in [0, 1].
    d_left: float [H, W], pixels, positive: left pixel x matches right pixel x - d_L.
    consistent: bool [H, W], left pixels whose disparity passed the left-right check.
    quantile, isolation, min_lag, min_pairs: the pairs' selection (above).
  """
  gray = np.asarray(mixture01, np.float32)
  gray = gray.mean(axis=-1) if gray.ndim == 3 else gray
  grad = cv2.Sobel(cv2.GaussianBlur(gray, (0, 0), 0.7), cv2.CV_32F, 1, 0, ksize=3)
  lag = np.rint(np.nan_to_num(d_left)).astype(np.int64)
  echo, inside = _lagged(grad, -lag)
  after, inside_after = _lagged(grad, lag)
  before, inside_before = _lagged(grad, -2 * lag)
  here, there = np.abs(grad), np.abs(echo)
  weaker = np.minimum(here, there)
  chosen = (consistent & inside & inside_after & inside_before & (lag >= min_lag) &
            (here + there >= np.quantile(here, quantile)) & (grad * echo > 0) &
            (np.abs(after) < isolation * weaker) & (np.abs(before) < isolation * weaker))
  if np.count_nonzero(chosen) < min_pairs:
    return None
  ratio = here[chosen] / (here[chosen] + there[chosen])
  return np.histogram(ratio, bins=RATIO_BINS.size, range=(0.05, 0.95),
                      weights=weaker[chosen])[0]


def estimate_weight(mixture01: np.ndarray, d_left: np.ndarray, consistent: np.ndarray,
                    fallback: Optional[float] = 0.5) -> Optional[float]:
  """The left view's weight a of a double image, in [0.05, 0.95]: `echo_peak` of its
  `echo_histogram` (arguments as there), or `fallback` where it shows no clear echo."""
  counts = echo_histogram(mixture01, d_left, consistent)
  return fallback if counts is None else echo_peak(counts)


def echo_peak(counts: np.ndarray) -> float:
  """The echo ratio a of a histogram over RATIO_BINS: the centre of the peak N(a,
  ECHO_SPREAD) that, beside unrelated pairs' spread around 1/2 (N(1/2, s), s one of
  BACKGROUND_SPREADS), fits the normalised histogram best in least squares with
  non-negative weights. The mode alone was pulled towards 1/2 by those pairs where true
  echoes are few (small images)."""
  target = counts / max(float(counts.sum()), 1e-12)
  echoes = np.exp(-0.5 * ((RATIO_BINS[None, :] - RATIO_BINS[:, None]) / ECHO_SPREAD) ** 2)
  best, found = np.inf, 0.5
  for spread in BACKGROUND_SPREADS:
    background = np.exp(-0.5 * ((RATIO_BINS - 0.5) / spread) ** 2)
    for centre, echo in zip(RATIO_BINS, echoes):
      residual = scipy.optimize.nnls(np.stack([background, echo], axis=1), target)[1]
      if residual < best:
        best, found = residual, float(centre)
  return found


def resolve_weight(weight, mixture01: np.ndarray, d_left: np.ndarray,
                   consistent: np.ndarray) -> Tuple[float, Optional[str]]:
  """(The weight a to separate with, a note or None): None -> 1/2 (`--mixture=diplopia`
  exactly), AUTO -> `estimate_weight` (noted NO_ECHO where it found too few pairs and fell
  back to 1/2), a number in (0, 1) -> itself (ValueError otherwise)."""
  if weight is None:
    return 0.5, None
  if weight != AUTO:
    return check_weight(weight), None
  found = estimate_weight(mixture01, d_left, consistent, fallback=None)
  return (0.5, NO_ECHO) if found is None else (found, None)
