"""Known-answer tests of the loss terms (images on the [0, 1] scale)."""

import numpy as np
import pytest
from skimage.metrics import structural_similarity
import tensorflow as tf

from mixstereo_tf.ops import losses

_C1 = 0.01**2
_C2 = 0.03**2


def _random(shape, seed=0, dtype=np.float32):
  return np.random.default_rng(seed).uniform(0, 1, shape).astype(dtype)


def test_ssim_of_identical_images_is_one():
  x = _random((2, 6, 8, 3))
  out = losses.ssim(x, x).numpy()
  assert out.shape == (2, 4, 6, 3)
  np.testing.assert_allclose(out, 1.0, atol=1e-5)


def test_ssim_matches_skimage_on_the_interior():
  # float64 removes rounding from the comparison; the tolerance is for the algebra only.
  x = _random((1, 10, 12, 3), seed=1, dtype=np.float64)
  y = np.clip(x + 0.3 * _random((1, 10, 12, 3), seed=2, dtype=np.float64) - 0.15, 0, 1)
  ours = losses.ssim(x, y).numpy()[0]
  # Same statistics: 3x3 uniform window, population covariance, data range 1.
  _, full = structural_similarity(x[0], y[0], win_size=3,
                                  gaussian_weights=False, use_sample_covariance=False,
                                  data_range=1.0, channel_axis=-1, full=True)
  np.testing.assert_allclose(ours, full[1:-1, 1:-1], atol=1e-10)
  assert ours.min() < 0.9  # The images differ: the comparison is not trivially all ones.


def test_ssim_of_constant_images():
  a01, b01 = 0.8, 0.3
  x = np.full((1, 4, 4, 1), a01, np.float64)
  y = np.full((1, 4, 4, 1), b01, np.float64)
  expected = (2 * a01 * b01 + _C1) / (a01**2 + b01**2 + _C1)  # Zero variances.
  np.testing.assert_allclose(losses.ssim(x, y).numpy(), expected, rtol=1e-12)


def test_appearance_loss_of_identical_images_is_zero():
  x = _random((2, 8, 10, 3), seed=3)
  assert abs(float(losses.appearance_loss(x, x, 0.85, 0.15))) < 1e-6


def test_appearance_loss_of_constant_images():
  a01, b01 = 0.9, 0.2
  x = np.full((1, 5, 6, 3), a01, np.float64)
  y = np.full((1, 5, 6, 3), b01, np.float64)
  s = (2 * a01 * b01 + _C1) / (a01**2 + b01**2 + _C1)
  expected = 0.85 * (1 - s) / 2 + 0.15 * abs(a01 - b01)
  np.testing.assert_allclose(float(losses.appearance_loss(x, y, 0.85, 0.15)), expected,
                             rtol=1e-12)
  np.testing.assert_allclose(float(losses.appearance_loss(x, y, 0.0, 1.0)), 0.7, rtol=1e-12)


def test_appearance_loss_of_anticorrelated_stripes():
  stripes = np.tile(np.array([0.0, 1.0]), 4).reshape(1, 1, 8, 1)
  x = np.tile(stripes, (1, 4, 1, 1))
  # Every 3x3 window of x has mean 1/3 or 2/3, variance 2/9; 1 - x has the
  # complementary mean and covariance -2/9 with x: SSIM < 0, so (1 - SSIM) / 2 > 0.5.
  s = ((2 * (1 / 3) * (2 / 3) + _C1) * (-4 / 9 + _C2) /
       (((1 / 3)**2 + (2 / 3)**2 + _C1) * (4 / 9 + _C2)))
  np.testing.assert_allclose(float(losses.appearance_loss(x, 1 - x, 1.0, 0.0)), (1 - s) / 2,
                             rtol=1e-12)


def test_l1():
  a = np.array([1.0, -2.0, 0.5, 0.0]).reshape(1, 1, 2, 2)
  b = np.array([0.0, 1.0, 0.5, -1.0]).reshape(1, 1, 2, 2)
  np.testing.assert_allclose(float(losses.l1(a, b)), (1 + 3 + 0 + 1) / 4)


def test_total_variation_hand_computed():
  image = np.array([[0.0, 1.0, 3.0],
                    [2.0, 2.0, 2.0]]).reshape(1, 2, 3, 1)
  # |du|: 1, 2, 0, 0 -> mean 0.75; |dv|: 2, 1, 1 -> mean 4/3.
  np.testing.assert_allclose(float(losses.total_variation(image)), 0.75 + 4 / 3)


def test_total_variation_both_directions_contribute():
  vertical = np.zeros((1, 3, 4, 1))
  vertical[:, 1:] = 1.0  # Only a v edge: one of two rows of differences is 1.
  np.testing.assert_allclose(float(losses.total_variation(vertical)), 0.5)
  np.testing.assert_allclose(
      float(losses.total_variation(np.transpose(vertical, (0, 2, 1, 3)))), 0.5)


def test_smoothness_with_flat_image_is_mean_disparity_gradient():
  disparity = np.array([[0.0, 1.0, 3.0],
                        [2.0, 2.0, 2.0]]).reshape(1, 2, 3, 1)
  image = np.zeros((1, 2, 3, 3))
  np.testing.assert_allclose(float(losses.edge_aware_smoothness(disparity, image)),
                             0.75 + 4 / 3)


def test_smoothness_edge_weights_hand_computed():
  # A v-only disparity step under a v-only image edge: the v term alone, weighted.
  disparity = np.array([[1.0, 1.0], [4.0, 4.0]]).reshape(1, 2, 2, 1)
  image = np.zeros((1, 2, 2, 3))
  image[:, 1, :, 0] = 0.5  # One channel steps by 0.5.
  # Mean over channels of |dv I|: 0.5 / 3; dv d = 3 at both columns.
  expected = 3.0 * np.exp(-0.5 / 3)
  np.testing.assert_allclose(float(losses.edge_aware_smoothness(disparity, image)),
                             expected, rtol=1e-12)
  # The same along u: the u term is weighted identically.
  np.testing.assert_allclose(
      float(losses.edge_aware_smoothness(np.transpose(disparity, (0, 2, 1, 3)),
                                         np.transpose(image, (0, 2, 1, 3)))),
      expected, rtol=1e-12)


def test_smoothness_of_constant_disparity_is_zero():
  disparity = np.full((1, 4, 5, 1), 7.0, np.float32)
  assert float(losses.edge_aware_smoothness(disparity, _random((1, 4, 5, 3)))) == 0.0


def test_losses_compile_with_xla():
  x = tf.constant(_random((2, 8, 12, 3), seed=4))
  y = tf.constant(_random((2, 8, 12, 3), seed=5))
  d = tf.constant(_random((2, 8, 12, 1), seed=6))
  fn = lambda x, y, d: (losses.appearance_loss(x, y, 0.85, 0.15),
                        losses.edge_aware_smoothness(d, x), losses.total_variation(y))
  compiled = tf.function(fn, jit_compile=True)
  for got, want in zip(compiled(x, y, d), fn(x, y, d)):
    np.testing.assert_allclose(got.numpy(), want.numpy(), rtol=1e-5)


@pytest.mark.parametrize('fn, args, name', [
    (losses.ssim, ((4, 4, 3), (1, 4, 4, 3)), 'x'),
    (losses.total_variation, ((4, 4),), 'image'),
    (losses.edge_aware_smoothness, ((1, 4, 4, 2), (1, 4, 4, 3)), 'disparity'),
])
def test_bad_shapes_raise(fn, args, name):
  with pytest.raises(ValueError, match=name):
    fn(*[np.zeros(shape, np.float32) for shape in args])
