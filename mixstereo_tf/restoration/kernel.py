"""The numba kernel of `views`: over-relaxed alternations of both views, row by row.

Per pixel and view, the normal equations of `views`' least-squares problem
(w_obs |A_own v + A_other v_other - m|^2 + w_match c |v - v_other(x + offset)|^2
+ w_prior |v - prior|^2) are solved and the view relaxed towards the solution; channels
the mixture copies are set to it. Values are float32 in [0, 1]; offsets in pixels, signed.
"""

import numba
import numpy as np


@numba.njit(error_model='numpy')
def _linear_taps(width, x, offset):
  """(x0, x1, f): a row of `width` pixels sampled linearly at clamp(x + offset, 0,
  width - 1) is (1 - f) row[x0] + f row[x1] (`sample_horizontal` without OpenCV's
  1/32-px rounding of the position)."""
  last = width - 1
  position = min(max(np.float32(x) + offset, np.float32(0.0)), np.float32(last))
  x0 = min(int(position), last)
  return x0, min(x0 + 1, last), position - np.float32(x0)


@numba.njit(error_model='numpy')
def _observed(value):
  """A mixture channel clipped to 0 or 255 is no observation (Dubois encodings)."""
  return np.float32(0.5 / 255) < value < np.float32(254.5 / 255)


@numba.njit(error_model='numpy')
def _observed_pattern(mixture, y, x):
  """Bit c set where mixture channel c is an observation (`_observed`): 0..7."""
  return ((1 if _observed(mixture[y, x, 0]) else 0) |
          (2 if _observed(mixture[y, x, 1]) else 0) |
          (4 if _observed(mixture[y, x, 2]) else 0))


@numba.njit(error_model='numpy')
def clipped_inverses(own, observation_weight, prior_weight, match_weight):
  """Dubois encodings: float32 [2, 8, 3, 3], [k, pattern] the inverse of w_obs sum_c
  [bit c of pattern] A_own[c]^T A_own[c] + (w_prior + k w_match) I (cofactors, float64):
  every normal matrix a pixel can have, by whether it is matched (k) and which of its
  mixture channels are observations (`_observed_pattern`), so no pixel inverts one."""
  out = np.empty((2, 8, 3, 3), np.float32)
  gram, cofactor = np.empty((3, 3), np.float64), np.empty((3, 3), np.float64)
  for k in range(2):
    for pattern in range(8):
      gram[:] = 0.0
      for c in range(3):
        if not pattern >> c & 1:
          continue
        for i in range(3):
          for j in range(3):
            gram[i, j] += observation_weight * own[c, i] * own[c, j]
      for i in range(3):
        gram[i, i] += prior_weight + match_weight * k
      for i in range(3):
        for j in range(3):
          a, b = (i + 1) % 3, (i + 2) % 3
          c, d = (j + 1) % 3, (j + 2) % 3
          cofactor[i, j] = gram[a, c] * gram[b, d] - gram[a, d] * gram[b, c]
      determinant = gram[0, 0] * cofactor[0, 0] + gram[0, 1] * cofactor[0, 1] + (
          gram[0, 2] * cofactor[0, 2])
      for i in range(3):
        for j in range(3):
          out[k, pattern, i, j] = cofactor[j, i] / determinant
  return out


@numba.njit(error_model='numpy')
def _update_view(y, view, other_view, mixture, offset, consistent, prior, other, own,
                 inverses, copied, weights, clipped):
  """One over-relaxed step of row y of one view, in place: the per-pixel normal equations'
  solution of w_obs A_own^T (m - A_other v_other) + w_match [consistent] v_other(x +
  offset) + w_prior prior; channels the mixture copies (copied[i] >= 0) set to it.
  weights = (w_obs, w_match, w_prior, relaxation); inverses[k]: the normal matrix's
  inverse for unmatched (k = 0) and matched (1) pixels; clipped (Dubois encodings, where
  clipped mixture channels are no observations: `clipped_inverses`, else empty):
  clipped[k, pattern] instead. Per-pixel values live in scalars (registers), not in small
  arrays."""
  observation_weight, match_weight, prior_weight, omega = weights
  clip = clipped.shape[0] > 0
  one = np.float32(1.0)
  # The matrices in scalars: loads from arrays the loop writes to could alias.
  p00, p01, p02 = other[0, 0], other[0, 1], other[0, 2]
  p10, p11, p12 = other[1, 0], other[1, 1], other[1, 2]
  p20, p21, p22 = other[2, 0], other[2, 1], other[2, 2]
  q00, q01, q02 = own[0, 0], own[0, 1], own[0, 2]
  q10, q11, q12 = own[1, 0], own[1, 1], own[1, 2]
  q20, q21, q22 = own[2, 0], own[2, 1], own[2, 2]
  for x in range(view.shape[1]):
    v0, v1, v2 = other_view[y, x, 0], other_view[y, x, 1], other_view[y, x, 2]
    e0 = mixture[y, x, 0] - (p00 * v0 + p01 * v1 + p02 * v2)
    e1 = mixture[y, x, 1] - (p10 * v0 + p11 * v1 + p12 * v2)
    e2 = mixture[y, x, 2] - (p20 * v0 + p21 * v1 + p22 * v2)
    matched = consistent[y, x]
    k = 1 if matched else 0
    pattern = 7
    if clip:
      pattern = _observed_pattern(mixture, y, x)
      e0 = e0 if pattern & 1 else np.float32(0.0)
      e1 = e1 if pattern & 2 else np.float32(0.0)
      e2 = e2 if pattern & 4 else np.float32(0.0)
    x0, x1, f = _linear_taps(view.shape[1], x, offset[y, x])
    h0 = observation_weight * (q00 * e0 + q10 * e1 + q20 * e2) + prior_weight * prior[y, x, 0]
    h1 = observation_weight * (q01 * e0 + q11 * e1 + q21 * e2) + prior_weight * prior[y, x, 1]
    h2 = observation_weight * (q02 * e0 + q12 * e1 + q22 * e2) + prior_weight * prior[y, x, 2]
    if matched:
      h0 += match_weight * ((one - f) * other_view[y, x0, 0] + f * other_view[y, x1, 0])
      h1 += match_weight * ((one - f) * other_view[y, x0, 1] + f * other_view[y, x1, 1])
      h2 += match_weight * ((one - f) * other_view[y, x0, 2] + f * other_view[y, x1, 2])
    for i in range(3):
      if copied[i] >= 0:
        view[y, x, i] = mixture[y, x, copied[i]]
      else:
        if clip:
          solved = (clipped[k, pattern, i, 0] * h0 + clipped[k, pattern, i, 1] * h1 +
                    clipped[k, pattern, i, 2] * h2)
        else:  # Indexed, not through a view: numba counts the references of views.
          solved = inverses[k, i, 0] * h0 + inverses[k, i, 1] * h1 + inverses[k, i, 2] * h2
        view[y, x, i] += omega * (solved - view[y, x, i])


@numba.njit(error_model='numpy')
def _clip_row(y, view):
  """Row y of `view` clipped to [0, 1], in place."""
  for x in range(view.shape[1]):
    for c in range(3):
      view[y, x, c] = min(max(view[y, x, c], np.float32(0.0)), np.float32(1.0))


@numba.njit(nogil=True, cache=True, error_model='numpy')
def solve_rows(y0, y1, iterations, mixture, offsets, consistent, priors, matrices,
                inverses, copied, weights, clipped, left, right):
  """`iterations` alternations of both views over rows [y0, y1), in place. Index 0 of
  each pair is the left view's, 1 the right's; offsets = (-d_L, d_R), where each view's
  pixel finds the other view; matrices = (A_L, A_R); clipped: each view's
  `clipped_inverses` (Dubois encodings) or empty [0, 8, 3, 3] arrays; finished rows are
  clipped to [0, 1]. Rows are independent (the warps are horizontal), so row blocks run in parallel
  and each stays in cache."""
  for y in range(y0, y1):
    for _ in range(iterations):
      _update_view(y, left, right, mixture, offsets[0], consistent[0], priors[0],
                   matrices[1], matrices[0], inverses[0], copied[0], weights, clipped[0])
      _update_view(y, right, left, mixture, offsets[1], consistent[1], priors[1],
                   matrices[0], matrices[1], inverses[1], copied[1], weights, clipped[1])
    _clip_row(y, left)  # The result is clipped to [0, 1].
    _clip_row(y, right)


@numba.njit(error_model='numpy')
def _decoupled_view(y, view, mixture, offset, consistent, prior, copied, other_copied,
                    inverses, weights, iterations, first_other):
  """Row y of one view after `iterations` steps, in closed form (`solve_decoupled_rows`).
  A lost channel i sees only the prior and the other view's channel i, which that view
  copies from the mixture, so each step relaxes it towards one fixed target
  t = inverse_ii (w_prior prior_i + w_match [consistent] O_i(x + offset)), and n steps
  from s give t + (1 - omega)^n (s - t). `first_other` (the left view: its first step
  reads the right view's start, not yet copied) is that start: step one then relaxes
  towards the target of those values instead."""
  _, match_weight, prior_weight, omega = weights
  rest = np.float32(1.0) - omega
  one = np.float32(1.0)
  steps = iterations - 1 if first_other is not None else iterations
  decay = rest ** np.float32(steps)
  for x in range(view.shape[1]):
    k = 1 if consistent[y, x] else 0
    x0, x1, f = _linear_taps(view.shape[1], x, offset[y, x])
    for i in range(3):
      if copied[i] >= 0:
        value = mixture[y, x, copied[i]]
      else:
        value = view[y, x, i]
        pull = prior_weight * prior[y, x, i]
        if first_other is not None:
          start = pull
          if k == 1:
            start += match_weight * ((one - f) * first_other[y, x0, i] +
                                     f * first_other[y, x1, i])
          value += omega * (inverses[k, i, i] * start - value)
        if k == 1:
          channel = other_copied[i]
          pull += match_weight * ((one - f) * mixture[y, x0, channel] +
                                  f * mixture[y, x1, channel])
        target = inverses[k, i, i] * pull
        value = target + decay * (value - target)
      view[y, x, i] = min(max(value, np.float32(0.0)), one)


@numba.njit(nogil=True, cache=True, error_model='numpy')
def solve_decoupled_rows(y0, y1, iterations, mixture, offsets, consistent, priors,
                         inverses, copied, weights, left, right):
  """`solve_rows` for the channel anaglyphs whose lost channels are decoupled: every
  channel a view does not copy is unobserved by the mixture and copied by the other
  view (colour, green-magenta, amber-blue), so its alternations have a closed form
  (`_decoupled_view`); the same result up to float rounding, in one pass over the rows
  instead of 2 x `iterations`. Arguments as `solve_rows` (no matrices, no clipping)."""
  if iterations < 1:
    for y in range(y0, y1):
      _clip_row(y, left)
      _clip_row(y, right)
    return
  for y in range(y0, y1):
    _decoupled_view(y, left, mixture, offsets[0], consistent[0], priors[0], copied[0],
                    copied[1], inverses[0], weights, iterations, right)
    _decoupled_view(y, right, mixture, offsets[1], consistent[1], priors[1], copied[1],
                    copied[0], inverses[1], weights, iterations, None)
