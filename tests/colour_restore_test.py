"""Colour restoration on a synthetic scene with known disparities and occlusions."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf import mixtures
from mixstereo_tf.ops import colour_restore

_H, _W = 16, 32
_D_BG, _D_FG = 2, 6  # Background plane and nearer square, pixels.
_Y0, _Y1, _X0, _X1 = 4, 12, 12, 20  # The square in the left view.


def _scene(seed=0):
  """Renders both views and their true disparities, batch of one.

  Background: texture B seen at left(x) = B[x], right(x) = B[x + _D_BG]. Square: texture F
  at left columns [_X0, _X1) and right columns [_X0 - _D_FG, _X1 - _D_FG).
  """
  rng = np.random.default_rng(seed)
  background = rng.uniform(-1, 1, (_H, _W + _D_BG, 3))
  square = rng.uniform(-1, 1, (_Y1 - _Y0, _X1 - _X0, 3))
  left, right = background[:, :_W].copy(), background[:, _D_BG:].copy()
  left[_Y0:_Y1, _X0:_X1] = square
  right[_Y0:_Y1, _X0 - _D_FG:_X1 - _D_FG] = square
  d_left = np.full((_H, _W, 1), _D_BG, np.float64)
  d_right = d_left.copy()
  d_left[_Y0:_Y1, _X0:_X1] = _D_FG
  d_right[_Y0:_Y1, _X0 - _D_FG:_X1 - _D_FG] = _D_FG
  return [a[np.newaxis].astype(np.float32) for a in (left, right, d_left, d_right)]


def _expected_occlusions():
  """1 where a pixel's match is hidden by the square or outside the image."""
  occ_left = np.zeros((1, _H, _W, 1), np.float32)
  occ_right = occ_left.copy()
  occ_left[:, :, :_D_BG] = 1  # x - _D_BG < 0.
  occ_right[:, :, _W - _D_BG:] = 1  # x + _D_BG > W - 1.
  # Background just left of the square in the left view is behind it in the right view,
  # background just right of the square in the right view is behind it in the left view.
  occ_left[:, _Y0:_Y1, _X0 - (_D_FG - _D_BG):_X0] = 1
  occ_right[:, _Y0:_Y1, _X1 - _D_FG:_X1 - _D_BG] = 1
  return occ_left, occ_right


def test_consistency_check_flags_exactly_the_occlusions():
  _, _, d_left, d_right = _scene()
  consistent_left, consistent_right = colour_restore.lr_consistency_mask(d_left, d_right)
  occ_left, occ_right = _expected_occlusions()
  np.testing.assert_array_equal(consistent_left.numpy(), 1 - occ_left)
  np.testing.assert_array_equal(consistent_right.numpy(), 1 - occ_right)


def test_anaglyph_restoration_with_true_disparity():
  left, right, d_left, d_right = _scene()
  mixture = mixtures.mix('anaglyph', left, right).numpy()
  fallback = np.full_like(left, 0.5)  # Distinct from every true value.
  out = colour_restore.restore_views(mixture, d_left, d_right,
                                     mixtures.get_mixture('anaglyph'), fallback, fallback)
  occ_left, occ_right = _expected_occlusions()
  np.testing.assert_array_equal(out['occluded_left'].numpy(), occ_left)
  np.testing.assert_array_equal(out['occluded_right'].numpy(), occ_right)
  restored_left, restored_right = out['left'].numpy(), out['right'].numpy()
  # Away from occlusions every channel is the true one.
  keep_left, keep_right = occ_left[..., 0] == 0, occ_right[..., 0] == 0
  np.testing.assert_allclose(restored_left[keep_left], left[keep_left], atol=1e-6)
  np.testing.assert_allclose(restored_right[keep_right], right[keep_right], atol=1e-6)
  # In occlusions the observed channels are still exact, the missing ones are the fallback.
  hole_left, hole_right = ~keep_left, ~keep_right
  np.testing.assert_array_equal(restored_left[hole_left][:, 0], left[hole_left][:, 0])
  np.testing.assert_array_equal(restored_left[hole_left][:, 1:], 0.5)
  np.testing.assert_array_equal(restored_right[hole_right][:, 1:], right[hole_right][:, 1:])
  np.testing.assert_array_equal(restored_right[hole_right][:, 0], 0.5)


def test_true_fallback_restores_everything_unbatched():
  left, right, d_left, d_right = _scene(seed=1)
  mixture = mixtures.mix('green_magenta', left, right).numpy()[0]
  out = colour_restore.restore_views(mixture, d_left[0], d_right[0],
                                     mixtures.get_mixture('green_magenta'), left[0], right[0])
  assert out['left'].shape == (_H, _W, 3) and out['occluded_left'].shape == (_H, _W, 1)
  np.testing.assert_allclose(out['left'].numpy(), left[0], atol=1e-6)
  np.testing.assert_allclose(out['right'].numpy(), right[0], atol=1e-6)


def test_half_colour_keeps_the_unobserved_channel_from_the_fallback():
  left, right, d_left, d_right = _scene(seed=2)
  mixture = mixtures.mix('half_color', left, right)
  fallback = np.full_like(left, -0.25)
  out = colour_restore.restore_views(mixture, d_left, d_right,
                                     mixtures.get_mixture('half_color'), fallback, fallback)
  keep_left = out['occluded_left'].numpy()[..., 0] == 0
  # Red is observed in neither view (the mixture has Y(left)); green, blue come from right.
  np.testing.assert_array_equal(out['left'].numpy()[..., 0], -0.25)
  np.testing.assert_array_equal(out['right'].numpy()[..., 0], -0.25)
  np.testing.assert_allclose(out['left'].numpy()[keep_left][:, 1:], left[keep_left][:, 1:],
                             atol=1e-6)
  np.testing.assert_array_equal(out['right'].numpy()[..., 1:], right[..., 1:])


def test_mixture_without_channels_returns_the_fallbacks():
  left, right, d_left, d_right = _scene(seed=3)
  mixture = mixtures.mix('diplopia', left, right)
  out = colour_restore.restore_views(mixture, d_left, d_right,
                                     mixtures.get_mixture('diplopia'), left * 0.5, right * 0.5)
  np.testing.assert_array_equal(out['left'].numpy(), left * 0.5)
  np.testing.assert_array_equal(out['right'].numpy(), right * 0.5)


def test_subpixel_disagreement_within_threshold_is_consistent():
  d_left = np.full((1, 2, 8, 1), 2.0, np.float32)
  d_right = np.full((1, 2, 8, 1), 2.8, np.float32)
  cl, cr = colour_restore.lr_consistency_mask(d_left, d_right, threshold=1.0)
  np.testing.assert_array_equal(cl.numpy()[0, :, :, 0], [[0, 0, 1, 1, 1, 1, 1, 1]] * 2)
  # x + 2.8 <= 7 holds up to x = 4.
  np.testing.assert_array_equal(cr.numpy()[0, :, :, 0], [[1, 1, 1, 1, 1, 0, 0, 0]] * 2)
  cl, _ = colour_restore.lr_consistency_mask(d_left, d_right, threshold=0.5)
  np.testing.assert_array_equal(cl.numpy(), 0.0)


@pytest.mark.parametrize('kwargs, name', [
    ({'mixture': np.zeros((1, 4, 8, 2), np.float32)}, 'mixture'),
    ({'disparity_left': np.zeros((1, 4, 8, 3), np.float32)}, 'disparity_left'),
    ({'fallback_right': np.zeros((1, 4, 6, 3), np.float32)}, 'fallback_right'),
    ({'threshold': -1.0}, 'threshold'),
])
def test_bad_input_raises(kwargs, name):
  args = {'mixture': np.zeros((1, 4, 8, 3), np.float32),
          'disparity_left': np.zeros((1, 4, 8, 1), np.float32),
          'disparity_right': np.zeros((1, 4, 8, 1), np.float32),
          'spec': mixtures.get_mixture('anaglyph'),
          'fallback_left': np.zeros((1, 4, 8, 3), np.float32),
          'fallback_right': np.zeros((1, 4, 8, 3), np.float32)}
  args.update(kwargs)
  with pytest.raises(ValueError, match=name):
    colour_restore.restore_views(**args)


def test_runs_inside_tf_function():
  left, right, d_left, d_right = _scene(seed=4)
  spec = mixtures.get_mixture('anaglyph')
  mixture = mixtures.mix('anaglyph', left, right)
  fn = lambda m, dl, dr, fl, fr: colour_restore.restore_views(m, dl, dr, spec, fl, fr)
  eager = fn(mixture, d_left, d_right, left, right)
  compiled = tf.function(fn, jit_compile=True)(mixture, d_left, d_right, left, right)
  for key in eager:
    np.testing.assert_allclose(compiled[key].numpy(), eager[key].numpy(), atol=1e-6)
