"""Both views of an anaglyph from its mixture and disparities (paper 4.2, any encoding).

Every anaglyph encoding is linear (`mixtures.MixtureSpec`): on [0, 1] values
m(x) = A_L L(x) + A_R R(x). With the disparities, a scene point seen at the left pixel x is
seen at the right pixel x - d_L(x), so where the left-right check passes each view also
equals the other one warped. Each view V is the per-pixel least-squares solution of

    w_obs |A_V V + A_O O(x) - m(x)|^2 + w_match c(x) |V - O(x - d)|^2 + w_prior |V - P(x)|^2

(O the other view's current estimate, c the consistency mask, P a prior), alternated
between the views with over-relaxation (iterations and relaxation chosen on the `sample`
training scenes with true disparities, over all encodings; the prior's weight on validation
examples with the classical disparities, `RestoreConfig`), channels the mixture
copies set to the mixture's exactly after each step (`kernel`). So the other
view's channels are warped in wherever they match, and what neither fixes comes from the
prior: for the classical method a local linear colour transfer from the view's own
mixture channels, fitted where the views match (`colour_transfer`; standing in for Joulin
& Kang's occlusion handling, which the paper adopts); for the model, the separation
network's views. Without a network's priors (or when asked: the refiner's), a last
solve (the colour-line pass) takes as its prior the colour transfer refitted on the
restored views: colours a wrong but consistent disparity warped in are pulled towards
what each view's own channels explain locally; where the mixture does not observe the
borrowed channels at all (`decoupled`), their finest detail is then scaled by how much of
it the camera's channels share (`borrowed_detail`: the other camera's noise is no part of
this view). Encodings that transmit no colour (`MixtureSpec.transmits_colour`: the gray
ones) give gray views, their luminance.
Clipped channels of the Dubois encodings (0 or 255) are not used as observations.

Images are float32 [H, W, 3] in [0, 1]; disparities float32 [H, W] in pixels, signed (the
left pixel x matches the right pixel x - d_L, the right pixel x matches the left x + d_R).
NumPy, OpenCV and numba only: this runs on every video frame.
"""

import dataclasses
from typing import Dict, Optional, Tuple

import cv2
import numpy as np

from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.restoration import borrowed_detail
from mixstereo_tf.restoration import colour_transfer
from mixstereo_tf.restoration import kernel
from mixstereo_tf.core import workers


@dataclasses.dataclass(frozen=True)
class RestoreConfig:
  """Weights and sizes of the restoration.

  Attributes:
    observation_weight: w_obs, the weight of the mixture equation.
    match_weight: w_match, the pull towards the other view warped, where consistent.
    prior_weight: w_prior, the pull towards the prior (chosen on validation examples,
      `experiments/restoration_weight.py`: the matched view's errors, which the encodings
      that infer a channel amplify, are larger on real and degraded inputs than on clean
      renders; 0.01 before).
    iterations: alternations between the two views per solve.
    relaxation: over-relaxation factor of each alternation (1 = plain Gauss-Seidel).
    lr_threshold: largest accepted |d_L(x) - d_R(x - d_L(x))|, pixels.
    transfer_radius: window radius of the colour transfer, pixels.
    transfer_subsample: the first solve and the colour transfer's fits run on copies
      reduced this many times (`colour_transfer.apply_reduced_fit`; 1: full size, exact).
    colour_line_weight: w_line, the prior weight of a last solve whose prior is the colour
      transfer refitted on the restored views (the colour-line pass, `_colour_line_pass`);
      0: no such pass (the restoration before it). By default only without fallback
      priors (`restore_views`' colour_line).
      2 (not the paper's): best mean over every encoding on validation examples,
      procedural and photo warps (`experiments/results/colour_line_weight.md`; smallest
      largest regret too until its 2026-11-30 rerun, 1 since: 0.22 against 0.25 dB).
    colour_line_iterations: alternations of that last solve (it starts from the restored
      views; for channel encodings the lost channels are decoupled, and 4 over-relaxed
      steps leave about 1/16 of the change undone).
    borrowed_detail_sigma: where the colour-line pass may run, on the encodings whose borrowed
      channels the mixture does not observe (`decoupled`), their detail below a Gaussian
      of this many pixels is scaled by the share the camera's channels have in common
      (`borrowed_detail`); 0: kept as warped. 0.7 (not the paper's): best mean of 0.7, 1
      and 1.4 on validation photo warps, clean, degraded apart and as JPEG
      (`experiments/results/borrowed_detail.md`).
    threads: threads of the solve (row blocks); 0 = every CPU this process may use.
  """
  observation_weight: float = 30.0
  match_weight: float = 1.0
  prior_weight: float = 0.1
  iterations: int = 10
  relaxation: float = 1.5
  lr_threshold: float = 1.0
  transfer_radius: int = 7
  transfer_subsample: int = 2
  colour_line_weight: float = 2.0
  colour_line_iterations: int = 4
  borrowed_detail_sigma: float = 0.7
  threads: int = 0


def sample_horizontal(image: np.ndarray, offset: np.ndarray) -> np.ndarray:
  """`image` [H, W] or [H, W, C] sampled at clamp(x + offset, 0, W - 1), linearly."""
  height, width = offset.shape
  map_x = np.clip(np.arange(width, dtype=np.float32)[None, :] + offset, 0, width - 1)
  map_y = np.broadcast_to(np.arange(height, dtype=np.float32)[:, None], (height, width))
  out = cv2.remap(np.ascontiguousarray(image, np.float32), map_x.astype(np.float32),
                  np.ascontiguousarray(map_y), cv2.INTER_LINEAR,
                  borderMode=cv2.BORDER_REPLICATE)
  return out.reshape(image.shape)


def lr_consistency(d_left: np.ndarray, d_right: np.ndarray,
                   threshold: float = 1.0) -> Tuple[np.ndarray, np.ndarray]:
  """(consistent_left, consistent_right) bool [H, W]: the match lies inside the image and
  the other map, linearly interpolated there, agrees within `threshold` pixels."""
  columns = np.arange(d_left.shape[1], dtype=np.float32)[None, :]
  last = d_left.shape[1] - 1
  right_at_left = sample_horizontal(d_right, -d_left)
  left_at_right = sample_horizontal(d_left, d_right)
  ok_left = ((np.abs(d_left - right_at_left) <= threshold) & (columns - d_left >= 0) &
             (columns - d_left <= last))
  ok_right = ((np.abs(d_right - left_at_right) <= threshold) & (columns + d_right >= 0) &
              (columns + d_right <= last))
  return ok_left, ok_right


def _solve(mixture, spec, d_left, d_right, consistent, priors, config, start):
  """`config.iterations` over-relaxed alternations between the views from `start`
  (`kernel.solve_rows` on row blocks, in threads: the kernel releases the
  GIL; `kernel.solve_decoupled_rows` where `decoupled`); returns both views clipped to
  [0, 1]."""
  offsets = (-d_left, d_right)
  matrices = (np.asarray(spec.left_matrix, np.float32),
              np.asarray(spec.right_matrix, np.float32))
  weights = tuple(np.float32(w) for w in (config.observation_weight, config.match_weight,
                                           config.prior_weight, config.relaxation))
  observation, match, prior = weights[:3]
  every = tuple(kernel.clipped_inverses(own, observation, prior, match) for own in matrices)
  # Unmatched / matched pixels' inverses with every channel observed (pattern 7).
  inverses = tuple(np.ascontiguousarray(each[:, 7]) for each in every)
  copied = tuple(np.array([channels.get(i, -1) for i in range(3)], np.int64)
                 for channels in (spec.left_channels, spec.right_channels))
  left, right = (np.array(view, np.float32, order='C') for view in start)
  contiguous = lambda arrays, dtype: tuple(np.ascontiguousarray(a, dtype) for a in arrays)
  inputs = (config.iterations, np.ascontiguousarray(mixture, np.float32),
            contiguous(offsets, np.float32), contiguous(consistent, np.bool_),
            contiguous(priors, np.float32))
  if decoupled(spec):  # The same alternations in closed form.
    solve = kernel.solve_decoupled_rows
    arguments = inputs + (inverses, copied, weights, left, right)
  else:
    solve = kernel.solve_rows
    clipped = every if spec.clip else (np.empty((0, 8, 3, 3), np.float32),) * 2
    arguments = inputs + (matrices, inverses, copied, weights, clipped, left, right)
  height, threads = mixture.shape[0], workers.usable_cpus(config.threads)
  workers.run_tasks(lambda block: solve(*block, *arguments),
                    workers.row_blocks(height, 4 * threads), threads)
  return left, right


def decoupled(spec: mixtures.MixtureSpec) -> bool:
  """True when every channel a view does not copy is unobserved by the mixture and
  copied by the other view (the colour, green-magenta and amber-blue anaglyphs): each
  lost channel then relaxes towards a fixed target, and `kernel.solve_decoupled_rows`
  gives `kernel.solve_rows`' result in one pass."""
  if spec.clip:
    return False
  for matrix, own, other in ((spec.left_matrix, spec.left_channels, spec.right_channels),
                             (spec.right_matrix, spec.right_channels, spec.left_channels)):
    lost = [c for c in range(3) if c not in own]
    if any(np.any(np.asarray(matrix)[:, c]) or c not in other for c in lost):
      return False
  return True


def _gray_priors(mixture, spec):
  """Each view's prior before any colour is known: the mean of its own mixture channels."""
  return tuple(np.repeat(mixture[..., list(eye)].mean(-1, keepdims=True), 3, axis=-1)
               for eye in spec.eye_channels)


def _per_view(config, fn, *arguments) -> Tuple[np.ndarray, np.ndarray]:
  """(fn(left's arguments), fn(right's)): in two threads when config allows (OpenCV and
  large NumPy operations release the GIL)."""
  threads = min(2, workers.usable_cpus(config.threads))
  return tuple(workers.run_tasks(lambda args: fn(*args), list(zip(*arguments)), threads))


def _classical_solve(mixture, spec, d_left, d_right, consistent, config):
  """Both views without a network (encodings that transmit no colour: one solve with
  the gray priors): a first solve with the gray priors, the colour transfer from each
  view's mixture channels fitted where the views match, and a second solve with the
  transfer as the prior. With `config.transfer_subsample` s > 1 the first
  solve runs on copies reduced s times (area-reduced mixture, nearest-sampled disparities
  scaled by 1 / s, their own left-right check), whose result is all the reduced transfer
  fit reads, and the second solve starts from the transfer."""
  if not spec.transmits_colour:  # No colour to transfer: one solve, gray priors.
    gray = _gray_priors(mixture, spec)
    return _solve(mixture, spec, d_left, d_right, consistent, gray, config, gray)
  if config.transfer_subsample == 1:
    gray = _gray_priors(mixture, spec)
    first = _solve(mixture, spec, d_left, d_right, consistent, gray, config, gray)
    priors = _per_view(config, lambda eye, view, ok: colour_transfer.local_linear_transfer(
        mixture[..., list(eye)], view, ok, config.transfer_radius),
                       spec.eye_channels, first, consistent)
    return _solve(mixture, spec, d_left, d_right, consistent, priors, config, first)
  size = colour_transfer.reduced_size(*d_left.shape, config.transfer_subsample)
  scale = size[0] / d_left.shape[1]
  small_mixture = cv2.resize(mixture, size, interpolation=cv2.INTER_AREA)
  small_d = [cv2.resize(d, size, interpolation=cv2.INTER_NEAREST) * np.float32(scale)
             for d in (d_left, d_right)]
  small_consistent = lr_consistency(*small_d, config.lr_threshold * scale)
  gray = _gray_priors(small_mixture, spec)
  first = _solve(small_mixture, spec, *small_d, small_consistent, gray, config, gray)
  radius = max(1, round(config.transfer_radius / config.transfer_subsample))
  priors = _per_view(config, lambda eye, view, ok: colour_transfer.apply_reduced_fit(
      mixture[..., list(eye)], small_mixture[..., list(eye)], view, ok, radius),
                     spec.eye_channels, first, small_consistent)
  return _solve(mixture, spec, d_left, d_right, consistent, priors, config, priors)


def _colour_line_pass(mixture, spec, d_left, d_right, consistent, restored, config):
  """The colour-line pass: each restored view's colours refitted as a local linear
  function of its own mixture channels (`colour_transfer.local_linear_transfer`, fitted
  where the views match, radius `config.transfer_radius`, reduced
  `config.transfer_subsample` times), then one more solve from `restored` with that fit
  as the prior at weight `config.colour_line_weight`. Where a view's channels were warped
  from the other eye by a wrong disparity, their edges disagree with the edges of the
  channels the view kept; the fit keeps only what a local colour line explains."""
  priors = _per_view(config, lambda eye, view, ok: colour_transfer.local_linear_transfer(
      mixture[..., list(eye)], view, ok, config.transfer_radius,
      subsample=config.transfer_subsample), spec.eye_channels, restored, consistent)
  line = dataclasses.replace(config, prior_weight=config.colour_line_weight,
                             iterations=config.colour_line_iterations)
  return _solve(mixture, spec, d_left, d_right, consistent, priors, line, restored)


def restore_views(mixture: np.ndarray, mixture_name: str, d_left: np.ndarray,
                  d_right: np.ndarray, fallback_left: Optional[np.ndarray] = None,
                  fallback_right: Optional[np.ndarray] = None,
                  config: RestoreConfig = RestoreConfig(),
                  consistent: Optional[Tuple[np.ndarray, np.ndarray]] = None,
                  colour_line: Optional[bool] = None) -> Dict[str, np.ndarray]:
  """Restores both views of an anaglyph (module docstring).

  Args:
    mixture: float32 [H, W, 3] in [0, 1].
    mixture_name: an anaglyph of `mixtures.ANAGLYPH_NAMES`.
    d_left, d_right: float [H, W] disparities, pixels, signed.
    fallback_left, fallback_right: [H, W, 3] in [0, 1], the prior where the views do not
      match (the separation network's views); None: the classical colour transfer.
    config: weights.
    consistent: (left, right) bool [H, W], `lr_consistency` of these disparities at
      config.lr_threshold when already computed (an earlier restoration's); None: computed.
    colour_line: run the colour-line pass (at config.colour_line_weight) and the borrowed
      detail's scaling; None: only without fallback priors (a network's views skip both:
      the paper's path).

  Returns:
    'left', 'right': float32 [H, W, 3] in [0, 1]; 'consistent_left', 'consistent_right':
    bool [H, W], the left-right check.
  """
  spec = mixtures.get_mixture(mixture_name)
  if not spec.is_anaglyph:
    raise ValueError(f'restore_views needs an anaglyph encoding, got {mixture_name!r}.')
  mixture = np.asarray(mixture, np.float32)
  d_left, d_right = np.asarray(d_left, np.float32), np.asarray(d_right, np.float32)
  if consistent is None:
    consistent = lr_consistency(d_left, d_right, config.lr_threshold)
  given = fallback_left is not None and fallback_right is not None
  if given:
    priors = (np.asarray(fallback_left, np.float32), np.asarray(fallback_right, np.float32))
    left, right = _solve(mixture, spec, d_left, d_right, consistent, priors, config, priors)
  else:
    left, right = _classical_solve(mixture, spec, d_left, d_right, consistent, config)
  if colour_line is None:
    colour_line = not given
  if colour_line and config.colour_line_weight > 0 and spec.transmits_colour:
    left, right = _colour_line_pass(mixture, spec, d_left, d_right, consistent,
                                    (left, right), config)
  if colour_line and decoupled(spec):
    left, right, _ = borrowed_detail.scale_borrowed(mixture, spec, left, right,
                                                    config.borrowed_detail_sigma)
  if not spec.transmits_colour:  # Gray encodings: only brightness exists to restore.
    left, right = (np.repeat(view @ np.asarray(mixtures.LUMA, np.float32)[:, None], 3, -1)
                   for view in (left, right))
  return {'left': left, 'right': right, 'consistent_left': consistent[0],
          'consistent_right': consistent[1]}


def at_depth(restored: Dict[str, np.ndarray], dtype) -> Dict[str, np.ndarray]:
  """`restore_views`' 'left' and 'right' ([0, 1]) as `dtype`: uint8, or uint16 for views
  restored from a 16-bit image (`image_range.unit_to`)."""
  return {key: image_range.unit_to(restored[key], dtype) for key in ('left', 'right')}
