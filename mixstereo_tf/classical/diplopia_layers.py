"""The two layers of a double image I = a L + (1 - a) R given its disparities
(the weight a: `diplopia_weight`).

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
"""

import dataclasses
import math
from typing import Dict, Tuple

import numpy as np

from mixstereo_tf.classical import diplopia_weight
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
  weight = diplopia_weight.check_weight(weight)
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
  weight = diplopia_weight.check_weight(weight)
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
