"""Both views of an anaglyph from its mixture and disparities (paper 4.2, any encoding).

Every anaglyph encoding is linear (`mixtures.MixtureSpec`): on [0, 1] values
m(x) = A_L L(x) + A_R R(x). With the disparities, a scene point seen at the left pixel x is
seen at the right pixel x - d_L(x), so where the left-right check passes each view also
equals the other one warped. Each view V is the per-pixel least-squares solution of

    w_obs |A_V V + A_O O(x) - m(x)|^2 + w_match c(x) |V - O(x - d)|^2 + w_prior |V - P(x)|^2

(O the other view's current estimate, c the consistency mask, P a prior), alternated
between the views with over-relaxation (weights, iterations and relaxation chosen on the
`sample` training scenes with true disparities, over all encodings), channels the mixture
copies set to the mixture's exactly after each step. So the other view's channels are warped in
wherever they match, and what neither fixes comes from the prior: for the classical method a local linear colour transfer from the
view's own mixture channels, fitted where the views match (standing in for Joulin & Kang's
occlusion handling, which the paper adopts); for the model, the separation network's views.
Encodings that transmit no colour (`MixtureSpec.transmits_colour`: the gray ones) give
gray views, their luminance. Clipped channels of
the Dubois encodings (0 or 255) are not used as observations.

Images are float32 [H, W, 3] in [0, 1]; disparities float32 [H, W] in pixels, signed (the
left pixel x matches the right pixel x - d_L, the right pixel x matches the left x + d_R).
NumPy and OpenCV only: this runs on every video frame.
"""

import dataclasses
from typing import Dict, Optional, Tuple

import cv2
import numba
import numpy as np

from mixstereo_tf import mixtures


@dataclasses.dataclass(frozen=True)
class RestoreConfig:
  """Weights and sizes of the restoration.

  Attributes:
    observation_weight: w_obs, the weight of the mixture equation.
    match_weight: w_match, the pull towards the other view warped, where consistent.
    prior_weight: w_prior, the pull towards the prior.
    iterations: alternations between the two views per solve.
    relaxation: over-relaxation factor of each alternation (1 = plain Gauss-Seidel).
    lr_threshold: largest accepted |d_L(x) - d_R(x - d_L(x))|, pixels.
    transfer_radius: window radius of the colour transfer, pixels.
  """
  observation_weight: float = 30.0
  match_weight: float = 1.0
  prior_weight: float = 0.01
  iterations: int = 10
  relaxation: float = 1.5
  lr_threshold: float = 1.0
  transfer_radius: int = 7


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


def _box(image: np.ndarray, radius: int) -> np.ndarray:
  size = 2 * radius + 1
  return cv2.boxFilter(image, -1, (size, size), normalize=False,
                       borderType=cv2.BORDER_CONSTANT)


def local_linear_transfer(guide: np.ndarray, target: np.ndarray, train: np.ndarray,
                          radius: int = 7, eps: float = 1e-3,
                          prior_count: float = 10.0) -> np.ndarray:
  """Predicts `target` from `guide` with a guided-filter-style local linear model.

  In every (2r + 1)^2 window, target = a . guide + b is fitted by ridge least squares on
  the `train` pixels (He et al. 2013); every window's moments are blended with the
  image-wide ones as if `prior_count` extra pixels had them (windows with few training
  pixels lean on the global fit); coefficients are averaged over the windows covering a
  pixel and applied everywhere.

  Args:
    guide: float [H, W, K], K = 1 or 2, [0, 1].
    target: float [H, W, M]; read only where `train`.
    train: bool [H, W].
    radius, eps, prior_count: window radius (pixels), ridge, global-moment weight.

  Returns:
    float32 [H, W, M] in [0, 1]; with no training pixel, the guide's mean per pixel.
  """
  guide, target = np.asarray(guide, np.float32), np.asarray(target, np.float32)
  k, m = guide.shape[-1], target.shape[-1]
  if k not in (1, 2):
    raise ValueError(f'local_linear_transfer takes 1 or 2 guide channels, got {k}.')
  if not train.any():
    return np.repeat(guide.mean(-1, keepdims=True), m, axis=-1)
  weight = train.astype(np.float32)
  count, total = _box(weight, radius), float(weight.sum())

  def moment(feature):
    weighted = feature * weight
    image_mean = float(weighted.sum(dtype=np.float64) / total)
    return (_box(weighted, radius) + prior_count * image_mean) / (count + prior_count)

  g = [moment(guide[..., i]) for i in range(k)]
  t = [moment(target[..., j]) for j in range(m)]
  var = [[moment(guide[..., i] * guide[..., j]) - g[i] * g[j] + (eps if i == j else 0.0)
          for j in range(k)] for i in range(k)]
  cov = [[moment(guide[..., i] * target[..., j]) - g[i] * t[j] for j in range(m)]
         for i in range(k)]
  if k == 1:
    coeff = [[cov[0][j] / var[0][0] for j in range(m)]]
  else:
    det = var[0][0] * var[1][1] - var[0][1] * var[0][1]
    coeff = [[(var[1][1] * cov[0][j] - var[0][1] * cov[1][j]) / det for j in range(m)],
             [(var[0][0] * cov[1][j] - var[0][1] * cov[0][j]) / det for j in range(m)]]
  windows = _box(np.ones(weight.shape, np.float32), radius)
  out = np.empty(target.shape[:2] + (m,), np.float32)
  for j in range(m):
    offset = t[j] - sum(g[i] * coeff[i][j] for i in range(k))
    out[..., j] = _box(offset, radius) / windows + sum(
        guide[..., i] * (_box(coeff[i][j], radius) / windows) for i in range(k))
  return np.clip(out, 0.0, 1.0)


@numba.njit(nogil=True, cache=True, error_model='numpy')
def _solve_unclipped(mixture, other_view, warped, consistent, prior, other, own_weighted,
                     inverses, match_weight, prior_weight, out):
  """out = (the per-pixel normal equations' inverse) (w_obs A_own^T (I - A_other v_other)
  + w_match [consistent] warped + w_prior prior), fused over [H, W] (unclipped encodings)."""
  h, w = consistent.shape
  residual = np.empty(3, np.float32)
  rhs = np.empty(3, np.float32)
  for y in range(h):
    for x in range(w):
      for c in range(3):
        residual[c] = mixture[y, x, c] - (other[c, 0] * other_view[y, x, 0] +
                                          other[c, 1] * other_view[y, x, 1] +
                                          other[c, 2] * other_view[y, x, 2])
      matched = consistent[y, x]
      for i in range(3):
        rhs[i] = (own_weighted[0, i] * residual[0] + own_weighted[1, i] * residual[1] +
                  own_weighted[2, i] * residual[2] + prior_weight * prior[y, x, i])
        if matched:
          rhs[i] += match_weight * warped[y, x, i]
      inverse = inverses[1] if matched else inverses[0]
      for i in range(3):
        out[y, x, i] = inverse[i, 0] * rhs[0] + inverse[i, 1] * rhs[1] + inverse[i, 2] * rhs[2]


class _ViewSolver:
  """The per-pixel normal equations of one view (module docstring)."""

  def __init__(self, own: np.ndarray, other: np.ndarray, clip: bool, config: RestoreConfig):
    # float32 matrices: the per-pixel products stay in float32.
    own, other = np.asarray(own, np.float32), np.asarray(other, np.float32)
    self.own, self.other, self.clip, self.config = own, other, clip, config
    gram = config.observation_weight * own.T @ own
    # Inverses for unmatched / matched pixels (channels never clipped).
    pulls = [config.prior_weight + c * config.match_weight for c in (0, 1)]
    self.inverse = np.stack([np.linalg.inv(gram + pull * np.eye(3))
                             for pull in pulls]).astype(np.float32)

  def __call__(self, mixture, other_view, warped, consistent, prior):
    config = self.config
    if not self.clip:
      out = np.empty(mixture.shape, np.float32)
      _solve_unclipped(*(np.ascontiguousarray(a, np.float32)
                         for a in (mixture, other_view, warped)),
                       np.ascontiguousarray(consistent, np.bool_),
                       np.ascontiguousarray(prior, np.float32), self.other,
                       config.observation_weight * self.own, self.inverse,
                       np.float32(config.match_weight), np.float32(config.prior_weight), out)
      return out
    residual = mixture - other_view @ self.other.T  # Per pixel: mixture - A_other v.
    observed = ((mixture > 0.5 / 255) & (mixture < 254.5 / 255)).astype(np.float32)
    c = consistent[..., None].astype(np.float32)
    rhs = (config.observation_weight * ((observed * residual) @ self.own)  # A_own^T r.
           + config.match_weight * c * warped + config.prior_weight * prior)
    gram = config.observation_weight * sum(
        observed[..., k, None, None] * np.outer(self.own[k], self.own[k]) for k in range(3))
    pull = config.prior_weight + config.match_weight * c
    return np.linalg.solve(gram + pull[..., None] * np.eye(3), rhs[..., None])[..., 0]


def _copy_channels(view: np.ndarray, mixture: np.ndarray, copied) -> np.ndarray:
  """The channels the mixture copies are the view's, exactly (the solve leaves 1 / w_obs)."""
  for view_channel, mixture_channel in copied.items():
    view[..., view_channel] = mixture[..., mixture_channel]
  return view


def _solve(mixture, spec, d_left, d_right, consistent, priors, config, start):
  solvers = (_ViewSolver(np.asarray(spec.left_matrix), np.asarray(spec.right_matrix),
                         spec.clip, config),
             _ViewSolver(np.asarray(spec.right_matrix), np.asarray(spec.left_matrix),
                         spec.clip, config))
  left, right = start
  omega = config.relaxation
  for _ in range(config.iterations):
    solved = solvers[0](mixture, right, sample_horizontal(right, -d_left), consistent[0],
                        priors[0])
    left = _copy_channels(left + omega * (solved - left), mixture, spec.left_channels)
    solved = solvers[1](mixture, left, sample_horizontal(left, d_right), consistent[1],
                        priors[1])
    right = _copy_channels(right + omega * (solved - right), mixture, spec.right_channels)
  return np.clip(left, 0, 1).astype(np.float32), np.clip(right, 0, 1).astype(np.float32)


def restore_views(mixture: np.ndarray, mixture_name: str, d_left: np.ndarray,
                  d_right: np.ndarray, fallback_left: Optional[np.ndarray] = None,
                  fallback_right: Optional[np.ndarray] = None,
                  config: RestoreConfig = RestoreConfig()) -> Dict[str, np.ndarray]:
  """Restores both views of an anaglyph (module docstring).

  Args:
    mixture: float32 [H, W, 3] in [0, 1].
    mixture_name: an anaglyph of `mixtures.ANAGLYPH_NAMES`.
    d_left, d_right: float [H, W] disparities, pixels, signed.
    fallback_left, fallback_right: [H, W, 3] in [0, 1], the prior where the views do not
      match (the separation network's views); None: the classical colour transfer.
    config: weights.

  Returns:
    'left', 'right': float32 [H, W, 3] in [0, 1]; 'consistent_left', 'consistent_right':
    bool [H, W], the left-right check.
  """
  spec = mixtures.get_mixture(mixture_name)
  if not spec.is_anaglyph:
    raise ValueError(f'restore_views needs an anaglyph encoding, got {mixture_name!r}.')
  mixture = np.asarray(mixture, np.float32)
  d_left, d_right = np.asarray(d_left, np.float32), np.asarray(d_right, np.float32)
  consistent = lr_consistency(d_left, d_right, config.lr_threshold)
  if fallback_left is not None and fallback_right is not None:
    priors = (np.asarray(fallback_left, np.float32), np.asarray(fallback_right, np.float32))
    left, right = _solve(mixture, spec, d_left, d_right, consistent, priors, config, priors)
  else:
    # First pass with a gray prior (the mean of each view's own mixture channels); then
    # the colour transfer from those channels, fitted where the views match, as the prior.
    gray = tuple(np.repeat(mixture[..., list(eye)].mean(-1, keepdims=True), 3, axis=-1)
                 for eye in spec.eye_channels)
    first = _solve(mixture, spec, d_left, d_right, consistent, gray, config, gray)
    priors = tuple(local_linear_transfer(mixture[..., list(eye)], view, ok,
                                         config.transfer_radius)
                   for eye, view, ok in zip(spec.eye_channels, first, consistent))
    left, right = _solve(mixture, spec, d_left, d_right, consistent, priors, config, first)
  if not spec.transmits_colour:  # Gray encodings: only brightness exists to restore.
    left, right = (np.repeat(view @ np.asarray(mixtures.LUMA, np.float32)[:, None], 3, -1)
                   for view in (left, right))
  return {'left': left, 'right': right, 'consistent_left': consistent[0],
          'consistent_right': consistent[1]}
