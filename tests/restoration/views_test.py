"""Known-answer tests of the restoration of both views from a mixture and disparities."""

import cv2
import numpy as np
import pytest

from mixstereo_tf.core import mixtures
from mixstereo_tf.restoration import views

# A 1 % pull towards the prior (w_prior / w_match) and no colour-line pass (tested on its
# own below), to see how exact the views are when the match is perfect; the default pulls
# 10 % and adds the pass, which real matches need (`experiments/restoration_weight.py`).
SLIGHT_PULL = views.RestoreConfig(prior_weight=0.01, colour_line_weight=0.0,
                                  borrowed_detail_sigma=0.0)


def _pair(shift=3, height=24, width=40, seed=0):
  """A textured pair with constant disparity `shift` ([0, 1] floats) and its masks."""
  rng = np.random.default_rng(seed)
  base = rng.uniform(0.1, 0.9, (height, width + shift, 1))
  texture = np.clip(base * [1.0, 0.8, 0.6] + rng.uniform(-0.1, 0.1, (height, width + shift, 3)),
                    0, 1).astype(np.float32)
  left, right = texture[:, :width], texture[:, shift:]  # Left x is right x - shift.
  d = np.full((height, width), float(shift), np.float32)
  inside = np.broadcast_to(np.arange(width)[None, :] >= shift, (height, width))  # Match in image.
  return left, right, d, inside


def _mix(name, left, right):
  spec = mixtures.get_mixture(name)
  mixed = left @ np.asarray(spec.left_matrix).T + right @ np.asarray(spec.right_matrix).T
  return np.clip(mixed, 0, 1).astype(np.float32)


def test_sample_horizontal_shifts_and_replicates_edges():
  image = np.arange(5, dtype=np.float32)[None, :].repeat(2, 0)
  np.testing.assert_array_equal(views.sample_horizontal(image, np.full((2, 5), 1.5)),
                                [[1.5, 2.5, 3.5, 4, 4]] * 2)
  np.testing.assert_array_equal(views.sample_horizontal(image, np.full((2, 5), -2.0)),
                                [[0, 0, 0, 1, 2]] * 2)


def test_lr_consistency_flags_disagreement_and_the_border():
  d = np.full((1, 8), 2.0, np.float32)
  other = d.copy()
  other[0, 4] = 6.0  # The left pixel 6 matches right 4, which disagrees.
  ok_left, ok_right = views.lr_consistency(d, other)
  np.testing.assert_array_equal(ok_left[0], [0, 0, 1, 1, 1, 1, 0, 1])
  assert not ok_right[0, 6] and not ok_right[0, 7]  # x + 2 leaves the image.


@pytest.mark.parametrize('name', ['anaglyph', 'green_magenta', 'amber_blue'])
def test_channel_anaglyphs_are_recovered_exactly_where_both_views_see(name):
  left, right, d, inside = _pair()
  out = views.restore_views(_mix(name, left, right), name, d, d, config=SLIGHT_PULL)
  assert out['consistent_left'][inside].all()
  # Copied channels exactly; warped ones up to the prior's 1 % pull.
  np.testing.assert_allclose(out['left'][inside], left[inside], atol=5e-3)
  seen_right = np.arange(d.shape[1])[None, :] + d < d.shape[1] - 1
  np.testing.assert_allclose(out['right'][np.broadcast_to(seen_right, d.shape)],
                             right[np.broadcast_to(seen_right, d.shape)], atol=5e-3)
  for view, truth, copied in (('left', left, mixtures.get_mixture(name).left_channels),
                              ('right', right, mixtures.get_mixture(name).right_channels)):
    for channel in copied:
      np.testing.assert_array_equal(out[view][..., channel], truth[..., channel])


def test_lossy_encodings_keep_their_luminance_and_gray_gives_gray():
  left, right, d, inside = _pair(seed=1)
  luma = np.asarray(mixtures.LUMA, np.float32)
  gray = views.restore_views(_mix('gray', left, right), 'gray', d, d)
  np.testing.assert_allclose(gray['left'][..., 0], gray['left'][..., 2], atol=1e-6)
  np.testing.assert_allclose(gray['left'][inside] @ luma, left[inside] @ luma, atol=3e-3)
  half = views.restore_views(_mix('half_color', left, right), 'half_color', d, d,
                                   config=SLIGHT_PULL)
  # Within 2 levels everywhere (a prior fitted at half resolution can push a near-black
  # pixel's lost channels below 0, and the clip then lifts its luminance), 0.25 on average.
  error = np.abs(half['left'][inside] @ luma - left[inside] @ luma)
  assert error.max() < 8e-3 and error.mean() < 1e-3
  # Colour came from the right view: the left view's colour is recovered, not only its Y.
  assert np.abs(half['left'][inside] - left[inside]).mean() < 0.02


def test_the_network_prior_fills_what_nothing_else_fixes():
  left, right, d, inside = _pair(seed=2)
  prior = np.full_like(left, 0.5)
  out = views.restore_views(_mix('anaglyph', left, right), 'anaglyph', d, d, prior,
                                  prior)
  occluded = ~inside
  np.testing.assert_allclose(out['left'][occluded][:, 0], left[occluded][:, 0], atol=2e-3)
  np.testing.assert_allclose(out['left'][occluded][:, 1:], 0.5, atol=0.02)


def test_a_given_left_right_check_is_the_one_used():
  left, right, d, _ = _pair(seed=4)
  mixture, prior = _mix('anaglyph', left, right), np.full_like(left, 0.5)
  out = views.restore_views(mixture, 'anaglyph', d, d, prior, prior)
  checked = out['consistent_left'], out['consistent_right']
  again = views.restore_views(mixture, 'anaglyph', d, d, prior, prior,
                                    consistent=checked)
  np.testing.assert_array_equal(again['left'], out['left'])
  np.testing.assert_array_equal(again['right'], out['right'])
  # Nothing matched: the lost channels come from the prior alone.
  nothing = tuple(np.zeros_like(c) for c in checked)
  alone = views.restore_views(mixture, 'anaglyph', d, d, prior, prior,
                                    consistent=nothing)
  assert not alone['consistent_left'].any()
  np.testing.assert_allclose(alone['left'][..., 1:], 0.5, atol=0.02)


def _reference_solve(mixture, spec, d_left, d_right, consistent, priors, config):
  """The module docstring's alternation, transcribed with NumPy solves per pixel."""
  left, right = (p.copy() for p in priors)
  matrices = np.asarray(spec.left_matrix), np.asarray(spec.right_matrix)
  for _ in range(config.iterations):
    for index in (0, 1):
      own, other = matrices[index], matrices[1 - index]
      view, other_view = (left, right) if index == 0 else (right, left)
      offset = -d_left if index == 0 else d_right
      c = consistent[index][..., None].astype(np.float64)
      # Dubois: clipped mixture channels are no observations.
      observed = ((mixture > 0.5 / 255) & (mixture < 254.5 / 255) if spec.clip
                  else np.ones(mixture.shape, bool)).astype(np.float64)
      rhs = (config.observation_weight * (observed * (mixture - other_view @ other.T)) @ own
             + config.match_weight * c * views.sample_horizontal(other_view, offset)
             + config.prior_weight * priors[index])
      gram = config.observation_weight * np.einsum('yxc,ci,cj->yxij', observed, own, own) + (
          config.prior_weight + config.match_weight * c[..., None]) * np.eye(3)
      solved = np.linalg.solve(gram, rhs[..., None])[..., 0]
      view += config.relaxation * (solved - view)
      for view_channel, mixture_channel in (spec.left_channels if index == 0
                                            else spec.right_channels).items():
        view[..., view_channel] = mixture[..., mixture_channel]
  return np.clip(left, 0, 1), np.clip(right, 0, 1)


@pytest.mark.parametrize('name', ['anaglyph', 'half_color', 'gray', 'dubois'])
@pytest.mark.parametrize('threads', [1, 3])
def test_the_fused_solve_equals_the_equations_per_pixel(name, threads):
  left, right, d, _ = _pair(shift=4, height=13)
  spec = mixtures.get_mixture(name)
  mixture = _mix(name, left, right)
  d_left = d + np.linspace(0, 2, d.size, dtype=np.float32).reshape(d.shape).round()
  consistent = views.lr_consistency(d_left, d_left, 1.0)
  rng = np.random.default_rng(2)
  priors = tuple(rng.uniform(size=left.shape).astype(np.float32) for _ in range(2))
  config = views.RestoreConfig(iterations=3, threads=threads)
  fused = views._solve(mixture, spec, d_left, d_left, consistent, priors, config,
                             priors)
  expected = _reference_solve(mixture, spec, d_left, d_left, consistent, priors, config)
  for got, want in zip(fused, expected):
    np.testing.assert_allclose(got, want, atol=1e-3)  # float32 against float64: 1/4 level.


@pytest.mark.parametrize('name', ['anaglyph', 'green_magenta', 'amber_blue'])
@pytest.mark.parametrize('iterations', [0, 1, 4, 10])
def test_the_closed_form_equals_the_alternations_of_decoupled_encodings(
    name, iterations, monkeypatch):
  spec = mixtures.get_mixture(name)
  assert views.decoupled(spec)
  left, right, d, _ = _pair(shift=4, height=9)
  rng = np.random.default_rng(3)
  d_left, d_right = ((d + rng.uniform(-3, 3, d.shape)).astype(np.float32)  # Some clamped.
                     for _ in range(2))
  consistent = tuple(rng.uniform(size=d.shape) < 0.7 for _ in range(2))
  priors = tuple(rng.uniform(size=left.shape).astype(np.float32) for _ in range(2))
  # Starts unlike the priors and outside [0, 1]: the left view's first step reads the
  # right view's start, before its copied channels are set.
  starts = tuple(rng.uniform(-0.5, 1.5, size=left.shape).astype(np.float32)
                 for _ in range(2))
  mixture = _mix(name, left, right)
  config = views.RestoreConfig(iterations=iterations, threads=1)
  arguments = (mixture, spec, d_left, d_right, consistent, priors, config, starts)
  closed = views._solve(*arguments)
  monkeypatch.setattr(views, 'decoupled', lambda spec: False)  # The alternations.
  iterated = views._solve(*arguments)
  for got, want in zip(closed, iterated):
    assert np.ptp(want) > 0.5
    np.testing.assert_allclose(got, want, atol=2e-6)


def test_mixed_channels_are_not_decoupled():
  for name in ('gray', 'half_color', 'dubois', 'dubois_ffmpeg', 'green_magenta_half'):
    assert not views.decoupled(mixtures.get_mixture(name)), name


def test_only_anaglyphs_are_restored():
  left, right, d, _ = _pair()
  with pytest.raises(ValueError, match='anaglyph encoding'):
    views.restore_views(_mix('diplopia', left, right), 'diplopia', d, d)


def _colour_line_pair(tile, shift=3, height=48, width=96):
  """A pair whose colours lie on one line per `tile`-px tile (G and B proportional to R,
  the slopes drawn per tile) with constant disparity `shift`."""
  rng = np.random.default_rng(5)
  red = rng.uniform(0.1, 0.9, (height, width + shift)).astype(np.float32)
  slope = np.kron(rng.uniform(0.3, 1.0, (height // tile + 1, (width + shift) // tile + 1, 2)),
                  np.ones((tile, tile, 1)))[:height, :width + shift]
  texture = np.concatenate([red[..., None], slope * red[..., None]], -1).astype(np.float32)
  d = np.full((height, width), float(shift), np.float32)
  return texture[:, :width], texture[:, shift:], d


def test_the_colour_line_pass_repairs_colours_a_wrong_disparity_warped_in():
  left, right, d = _colour_line_pair(tile=24)
  mixture = _mix('anaglyph', left, right)
  # 2 px off in a 3-px band every 16 px, taken as matched in both views.
  band = np.broadcast_to(np.arange(d.shape[1]) % 16 < 3, d.shape) & (
      np.arange(d.shape[1]) >= 8)
  wrong = np.where(band, d + 2.0, d).astype(np.float32)
  matched = (np.ones(d.shape, bool),) * 2
  errors = {}
  for weight in (0.0, 1.0, 4.0):
    out = views.restore_views(mixture, 'anaglyph', wrong, wrong, consistent=matched,
                              config=views.RestoreConfig(colour_line_weight=weight,
                                                             borrowed_detail_sigma=0.0))
    # The channels the mixture copies stay exact.
    np.testing.assert_array_equal(out['left'][..., 0], left[..., 0])
    np.testing.assert_array_equal(out['right'][..., 1:], right[..., 1:])
    errors[weight] = np.abs(out['left'][band][:, 1:] - left[band][:, 1:]).mean()
  # In the band the warped colours are off by about the texture's contrast; the fit,
  # from windows mostly outside it, knows the colour line. At w_line = w_match the solve
  # lands about halfway between the warp and the fit, at 4 w_match near the fit.
  assert errors[0.0] > 0.1
  assert errors[1.0] < 0.7 * errors[0.0] and errors[4.0] < 0.45 * errors[0.0]


def test_the_colour_line_pass_keeps_a_right_match_and_skips_network_priors_unless_asked():
  left, right, d = _colour_line_pair(tile=128)  # One colour line: the fit is exact.
  mixture = _mix('anaglyph', left, right)
  inner = (slice(None), slice(8, -8))
  with_pass = views.restore_views(mixture, 'anaglyph', d, d,
                                  config=views.RestoreConfig(colour_line_weight=1.0))
  assert np.abs(with_pass['left'][inner] - left[inner]).mean() < 0.01
  prior = np.full_like(left, 0.5)
  outs = [views.restore_views(mixture, 'anaglyph', d, d, prior, prior,
                              config=views.RestoreConfig(colour_line_weight=weight,
                                                             borrowed_detail_sigma=0.0))
          for weight in (0.0, 1.0)]
  np.testing.assert_array_equal(outs[0]['left'], outs[1]['left'])
  # Asked for (the refiner's restoration), the pass also runs over a network's priors.
  asked = views.restore_views(mixture, 'anaglyph', d, d, prior, prior, colour_line=True)
  assert not np.array_equal(asked['left'], outs[0]['left'])
  error = lambda out: np.abs(out['left'][inner] - left[inner]).mean()
  assert error(asked) < error(outs[0]) + 0.01


def test_borrowed_detail_of_noisy_cameras_is_scaled_where_the_colour_line_pass_may_run():
  """Two cameras seeing one texture, each with its own noise per channel: the default
  restoration scales the borrowed channels' finest band (`borrowed_detail`) and comes
  nearer each camera's views than with it off; the mixture's own channels stay exact, and
  a network's priors (the paper's path) skip it."""
  rng = np.random.default_rng(5)
  shift, height, width = 3, 48, 96
  detail = cv2.GaussianBlur(rng.normal(0, 1, (height, width + shift)).astype(np.float32),
                            (0, 0), 2.0)  # Most power at coarse scales, as a photograph's.
  texture = 0.5 + 0.7 * detail[..., None] - [0.0, 0.05, 0.1]
  d = np.full((height, width), float(shift), np.float32)
  columns = np.broadcast_to(np.arange(width)[None, :], (height, width))
  seen = (columns >= shift, columns + shift < width)  # Left, right pixels the other sees.
  noisy = [np.clip(view + rng.normal(0, 0.05, view.shape), 0, 1).astype(np.float32)
           for view in (texture[:, :width], texture[:, shift:])]
  mixture = _mix('anaglyph', *noisy)
  # Without the colour-line pass, whose exact colour lines here would already take the
  # borrowed channels' detail from the view's own channel.
  on = views.RestoreConfig(colour_line_weight=0.0)
  off = views.RestoreConfig(colour_line_weight=0.0, borrowed_detail_sigma=0.0)
  outs = [views.restore_views(mixture, 'anaglyph', d, d, config=config)
          for config in (on, off)]
  for key, truth, mask in zip(('left', 'right'), noisy, seen):
    error = lambda out: np.mean((out[key][mask] - truth[mask]) ** 2)
    assert error(outs[0]) < 0.95 * error(outs[1])
  np.testing.assert_array_equal(outs[0]['left'][..., 0], mixture[..., 0])
  np.testing.assert_array_equal(outs[0]['right'][..., 1:], mixture[..., 1:])
  prior = np.full_like(noisy[0], 0.5)
  given = [views.restore_views(mixture, 'anaglyph', d, d, prior, prior, config=config)
           for config in (on, off)]
  np.testing.assert_array_equal(given[0]['left'], given[1]['left'])


def test_the_dubois_inverses_are_those_of_every_observation_pattern():
  """`kernel.clipped_inverses`: per matched flag k and pattern of observed channels, the
  inverse of w_obs sum_c [observed c] A[c]^T A[c] + (w_prior + k w_match) I, computed once
  instead of per pixel and iteration."""
  from mixstereo_tf.restoration import kernel  # pylint: disable=g-import-not-at-top
  own = np.asarray(mixtures.get_mixture('dubois').left_matrix, np.float32)
  table = kernel.clipped_inverses(own, 30.0, 0.1, 1.0)
  for k in (0, 1):
    for pattern in range(8):
      observed = np.array([pattern >> c & 1 for c in range(3)], np.float64)
      gram = 30.0 * np.einsum('c,ci,cj->ij', observed, own, own) + (0.1 + k) * np.eye(3)
      np.testing.assert_allclose(table[k, pattern], np.linalg.inv(gram), rtol=1e-5,
                                 atol=1e-6)
