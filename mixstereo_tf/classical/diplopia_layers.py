"""The two layers of a double image I = a L + (1 - a) R given its disparities, and the
mixing weight a from the image's echoes.

With the right pixel x matching the left pixel x + d_R(x) (docs/DESIGN.md), R(x) =
L(x + d_R(x)) wherever the right pixel is visible in the left view, so

    I(x) = a L(x) + (1 - a) L(x + d_R(x)),

one linear equation per pixel in the unknown left view (a = 1/2: `--mixture=diplopia`).
`separate_layers`: L on the columns [0, W + E) (E covers the largest d_R, content the left
view never shows inside the image) minimises
    sum_x (a L(x) + (1 - a) L(x + d_R(x)) - I(x))^2 + smoothness * |grad L|^2
      + fidelity * |L - I|^2   (I edge-extended to the extra columns)
(sub-pixel shifts by linear interpolation; horizontal and vertical first differences),
solved by Jacobi-preconditioned conjugate gradients for all channels at once, the normal
matrix applied without being built (`layers_kernel`, row blocks in threads); then R = (I -
a L) / (1 - a), what the mixture leaves of L (`onto_mixture`; L sampled at x + d_R with
`LayerConfig.right_from_mixture` off, wrong where R shows what L hides). The 2-tap
filter a + (1 - a) e^{i w d} is zero only for a = 1/2 (at w = pi (2k + 1) / d): there
those frequencies are unobservable and the prior sets them.

`estimate_weight`: an edge of the left view at x shows twice in I: at x with weight a (the
left view's copy) and at x - d_L(x) with weight 1 - a (the right view's, positive
disparities). Where both copies are clear edges of one sign, |g(x)| / (|g(x)| +
|g(x - d_L)|) of the horizontal gradient g of I is a; the peak of its histogram over such
pairs (weights: the smaller magnitude, so clear echoes count most), told apart from the
spread of unrelated pairs around 1/2, estimates it. Second-order statistics cannot: the
power spectrum a^2 + (1 - a)^2 + 2 a (1 - a) cos(w d) is the same for a and 1 - a.
"""

import dataclasses
import math
from typing import Dict, Optional, Tuple

import cv2
import numpy as np
import scipy.optimize

from mixstereo_tf.classical import layers_kernel
from mixstereo_tf.classical import parallel_sgm
from mixstereo_tf.core import workers


@dataclasses.dataclass(frozen=True)
class LayerConfig:
  """Prior weights and solver settings of `separate_layers`.

  Attributes:
    smoothness: weight of the squared-gradient prior on the left layer ([0, 1] units).
    fidelity: weight of a prior pulling the left layer towards the mixture itself, which
      fills the unobservable frequencies with the mixture's and limits the damage of
      wrong shifts.
    cg_iterations: conjugate-gradient iteration cap.
    cg_tolerance: relative residual at which CG stops.
    right_from_mixture: the right layer is what the mixture leaves of the left one,
      (I - a L) / (1 - a) (`onto_mixture`, the whole residual on the right), not the left
      layer sampled at x + d_R, which is wrong where the right view shows what the left
      one hides. True since 2026-11-29, chosen on validation double images (right view
      +1.28 dB at a = 1/2, +0.24 to +3.24 at a = 0.7 / 0.3; the left one unchanged).
  cg_tolerance 3e-3 (1e-4 before) was chosen on validation double images
  (`experiments/results/diplopia_validation.md`): views +0.03 / +0.03 dB with the SGM
  penalties of then (8 / 64), +0.02 / +0.01 with today's (stopping early keeps the layer
  nearer the mixture, as more fidelity does; 1e-2: 0.00 / -0.06, 3e-2: -0.3 / -0.4), and
  4 CG steps instead of 12 on a 720p frame (0.12 s instead of 0.27). fidelity 0.1 gave
  the classical views +0.12 / 0.00 dB there (+0.16 / +0.03 with 8 / 64) and +0.1 to +0.4
  dB on the evaluation scenes, but the shipped refiners, trained on layers made with
  0.05, then lost up to 0.14 dB (Motorcycle): it waits for a retraining of the refiners.
  """
  smoothness: float = 0.01
  fidelity: float = 0.05
  cg_iterations: int = 300
  cg_tolerance: float = 3e-3
  right_from_mixture: bool = True

  def __post_init__(self):
    if not self.smoothness > 0:
      raise ValueError(f'smoothness must be positive, got {self.smoothness!r}.')


def check_weight(weight: float) -> float:
  """`weight` as a float in (0, 1), or ValueError naming it."""
  if not 0.0 < float(weight) < 1.0:
    raise ValueError(f'The mixing weight a of I = a L + (1 - a) R must lie in (0, 1), got '
                     f'{weight!r}.')
  return float(weight)


def _taps(d_right: np.ndarray, wide: int):
  """(x0 int64, frac float64) [H, W]: right pixel x reads the left layer at x0 + frac =
  clip(x + d_R, 0, wide - 1.001) (`layers_kernel`'s data operator)."""
  position = np.clip(np.arange(d_right.shape[1])[None, :] + d_right.astype(np.float64), 0,
                     wide - 1.001)
  x0 = np.floor(position).astype(np.int64)
  return x0, position - x0


def _conjugate_gradient(taps, weight: float, config: LayerConfig, rhs: np.ndarray,
                        solution: np.ndarray, blocks, threads: int) -> np.ndarray:
  """Jacobi-preconditioned CG for A u = rhs ([H, E, C] float64; A of `layers_kernel`,
  every channel with its own step sizes), from `solution` (updated in place and returned),
  until each channel's residual is below config.cg_tolerance |rhs| or
  config.cg_iterations steps; the kernels run on the row `blocks` in `threads` threads
  (`parallel_sgm.run_blocks`)."""
  run = lambda kernel, *arguments, partial=0: parallel_sgm.run_blocks(
      kernel, blocks, threads, *arguments, partial=partial)
  channels = rhs.shape[2]
  operator = (*taps, weight, config.smoothness, config.fidelity)
  inverse_diagonal = np.empty(rhs.shape[:2])
  run(layers_kernel.diagonal_rows, *operator, inverse_diagonal)
  np.divide(1.0, inverse_diagonal, out=inverse_diagonal)
  product, residual, direction = (np.empty_like(rhs) for _ in range(3))
  run(layers_kernel.normal_rows, solution, *operator, product, partial=channels)
  sums = run(layers_kernel.start_rows, rhs, product, inverse_diagonal, residual, direction,
             partial=3 * channels)
  rz, norms = sums[:channels], np.sqrt(sums[channels:2 * channels])
  target = config.cg_tolerance * np.sqrt(sums[2 * channels:])
  preconditioned = np.empty_like(rhs)
  for _ in range(config.cg_iterations):
    if np.all(norms <= target):
      break
    curvature = run(layers_kernel.normal_rows, direction, *operator, product,
                    partial=channels)
    alpha = rz / np.maximum(curvature, 1e-30)
    sums = run(layers_kernel.step_rows, alpha, solution, residual, direction, product,
               inverse_diagonal, preconditioned, partial=2 * channels)
    rz_new, norms = sums[:channels], np.sqrt(sums[channels:])
    run(layers_kernel.direction_rows, rz_new / np.maximum(rz, 1e-30), preconditioned,
        direction)
    rz = rz_new
  return solution


def separate_layers(mixture01: np.ndarray, d_right: np.ndarray,
                    config: LayerConfig = LayerConfig(),
                    weight: float = 0.5) -> Dict[str, np.ndarray]:
  """Left and right layers of I = a L + (1 - a) R given the right disparity.

  Args:
    mixture01: float [H, W, 3] in [0, 1].
    d_right: float [H, W], pixels, positive: right pixel x shows left pixel x + d_R.
    config: prior weights and solver settings.
    weight: a, the left view's share of every pixel, in (0, 1).

  Returns:
    'left', 'right': float32 [H, W, 3] in [0, 1]; 'right_warped': the left layer sampled
    at x + d_R (the right layer without `right_from_mixture`; the shipped refiners'
    input).
  """
  weight = check_weight(weight)
  h, w, channels = mixture01.shape
  extra = int(np.ceil(max(float(d_right.max()), 0.0))) + 2
  x0, frac = _taps(d_right, w + extra)
  # The mixture itself, edge-extended: CG's start and the target of the fidelity prior.
  start = np.empty((h, w + extra, channels))
  start[:, :w], start[:, w:] = mixture01, np.asarray(mixture01)[:, -1:]
  rhs = np.empty_like(start)
  threads = workers.usable_cpus(0)
  blocks = workers.row_blocks(h, 4 * threads)
  run = lambda kernel, *arguments: parallel_sgm.run_blocks(kernel, blocks, threads,
                                                          *arguments)
  run(layers_kernel.transpose_rows, np.ascontiguousarray(mixture01), x0, frac, weight, rhs)
  rhs += config.fidelity * start
  wide = _conjugate_gradient((x0, frac), weight, config, rhs, start, blocks, threads)
  left, right = (np.empty((h, w, channels), np.float32) for _ in range(2))
  run(layers_kernel.views_rows, wide, x0, frac, left, right)
  if not config.right_from_mixture:
    return {'left': left, 'right': right, 'right_warped': right}
  return dict(zip(('left', 'right'), onto_mixture(mixture01, left, right, weight, math.inf)),
              right_warped=right)


def onto_mixture(mixture01: np.ndarray, left: np.ndarray, right: np.ndarray, weight: float,
                 right_share: float) -> Tuple[np.ndarray, np.ndarray]:
  """Views that satisfy I = a L + (1 - a) R, nearest to (`left`, `right`).

  The residual e = I - a L - (1 - a) R goes to the views as L + a e / n and
  R + (1 - a) k e / n with n = a^2 + (1 - a)^2 k, k = `right_share` (the least-squares
  change with the right view's changes costing 1 / k as much as the left's: k = 1 is the
  orthogonal projection, which brings the pair nearer to any true pair of this mixture,
  both views together; k = inf leaves the left view and makes the right one
  (I - a L) / (1 - a)); then clipped to [0, 1].

  Args:
    mixture01, left, right: float [H, W, 3] in [0, 1].
    weight: a, in (0, 1).
    right_share: k > 0 (math.inf allowed).

  Returns:
    (left, right) float32 [H, W, 3] in [0, 1].
  """
  weight = check_weight(weight)
  if not right_share > 0:
    raise ValueError(f'right_share must be positive, got {right_share!r}.')
  residual = (np.asarray(mixture01, np.float32) - np.float32(weight) * left
              - np.float32(1 - weight) * right)
  if math.isinf(right_share):
    to_left, to_right = 0.0, 1.0 / (1.0 - weight)
  else:
    norm = weight ** 2 + (1.0 - weight) ** 2 * right_share
    to_left, to_right = weight / norm, (1.0 - weight) * right_share / norm
  return tuple(np.clip(view + np.float32(share) * residual, 0.0, 1.0).astype(np.float32)
               for view, share in ((left, to_left), (right, to_right)))


def _lagged(values: np.ndarray, lag: np.ndarray):
  """values[y, x + lag[y, x]] (clipped) and whether x + lag lies inside the row."""
  width = values.shape[1]
  column = np.arange(width)[None, :] + lag
  inside = (column >= 0) & (column < width)
  return np.take_along_axis(values, np.clip(column, 0, width - 1), axis=1), inside


def estimate_weight(mixture01: np.ndarray, d_left: np.ndarray, consistent: np.ndarray,
                    quantile: float = 0.9, isolation: float = 0.25, min_lag: int = 5,
                    min_pairs: int = 30, fallback: Optional[float] = 0.5) -> Optional[float]:
  """The left view's weight a of a double image (module docstring).

  Pairs: consistent left pixels x with d = round(d_L(x)) >= `min_lag` (nearer copies'
  gradients overlap), |g(x)| + |g(x - d)| at least the `quantile` of |g|, one sign, and
  isolated: |g(x + d)| and |g(x - 2 d)| (where a third copy of an unrelated edge would show)
  below `isolation` times the weaker copy. a is the centre of the peak that true echoes
  make in the histogram of |g(x)| / (|g(x)| + |g(x - d)|) (0.01 bins over [0.05, 0.95]
  weighted by the weaker copy) beside the spread of unrelated edge pairs around 1/2
  (`echo_peak`).

  Args:
    mixture01: float [H, W, 3] (or [H, W]) in [0, 1].
    d_left: float [H, W], pixels, positive: left pixel x matches right pixel x - d_L.
    consistent: bool [H, W], left pixels whose disparity passed the left-right check.
    quantile, isolation, min_lag: the pairs' selection (above).
    min_pairs: with fewer pairs the image shows no clear echo: `fallback` is returned.

  Returns:
    a in [0.05, 0.95], or `fallback`.
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
    return fallback
  ratio = here[chosen] / (here[chosen] + there[chosen])
  counts, _ = np.histogram(ratio, bins=RATIO_BINS.size, range=(0.05, 0.95),
                           weights=weaker[chosen])
  return echo_peak(counts)


# The ratio histogram's bin centres, and the spreads fitted by `echo_peak` (chosen on
# validation double images: docs/LEARNED_DIPLOPIA.md, "Estimating a").
RATIO_BINS = 0.05 + 0.01 * (np.arange(90) + 0.5)
BACKGROUND_SPREADS = tuple(0.04 + 0.02 * k for k in range(9))  # 0.04 to 0.2.
ECHO_SPREAD = 0.03


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


AUTO = 'auto'  # A mixing weight estimated from the image (`estimate_weight`).
# Said where AUTO found too few echo pairs to estimate a from (`resolve_weight`).
NO_ECHO = ('no clear echo to estimate it from (too few isolated echo pairs): 1/2 used; '
           'name the weight (--mixing_weight) if known')


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
