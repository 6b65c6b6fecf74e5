"""Known-answer tests of the horizontal bilinear sampler."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.ops import warp


def _random(shape, seed=0, low=-1.0, high=1.0, dtype=np.float32):
  return np.random.default_rng(seed).uniform(low, high, shape).astype(dtype)


def _numpy_sample(image, offset):
  """Reference: per-row np.interp at clamp(x + offset, 0, W - 1)."""
  b, h, w, c = image.shape
  out = np.empty_like(image)
  columns = np.arange(w, dtype=np.float64)
  for i in range(b):
    for y in range(h):
      x = np.clip(columns + offset[i, y, :, 0], 0, w - 1)
      for k in range(c):
        out[i, y, :, k] = np.interp(x, columns, image[i, y, :, k])
  return out


def test_zero_offset_is_identity():
  image = _random((2, 3, 7, 3))
  out = warp.sample_horizontal(image, np.zeros((2, 3, 7, 1), np.float32))
  np.testing.assert_array_equal(out.numpy(), image)


def test_integer_offset_shifts_with_edge_replication():
  image = _random((1, 2, 6, 2))
  out = warp.sample_horizontal(image, np.full((1, 2, 6, 1), 2.0, np.float32)).numpy()
  # Output x reads column min(x + 2, 5): columns 2, 3, 4, 5, 5, 5.
  np.testing.assert_array_equal(out, image[:, :, [2, 3, 4, 5, 5, 5], :])
  out = warp.sample_horizontal(image, np.full((1, 2, 6, 1), -3.0, np.float32)).numpy()
  np.testing.assert_array_equal(out, image[:, :, [0, 0, 0, 0, 1, 2], :])


def test_reconstruct_left_and_right_signs():
  right = _random((1, 1, 8, 1), seed=1)
  d = np.full((1, 1, 8, 1), 3.0, np.float32)
  # Left pixel x matches right pixel x - d.
  np.testing.assert_array_equal(warp.reconstruct_left(right, d).numpy()[0, 0, 3:, 0],
                                right[0, 0, :5, 0])
  left = _random((1, 1, 8, 1), seed=2)
  # Right pixel x matches left pixel x + d.
  np.testing.assert_array_equal(warp.reconstruct_right(left, d).numpy()[0, 0, :5, 0],
                                left[0, 0, 3:, 0])


def test_subpixel_matches_numpy_reference():
  image = _random((2, 3, 9, 3), seed=3)
  offset = _random((2, 3, 9, 1), seed=4, low=-4.0, high=4.0)
  out = warp.sample_horizontal(image, offset).numpy()
  np.testing.assert_allclose(out, _numpy_sample(image, offset), atol=1e-6)


def test_half_pixel_is_the_average():
  image = np.arange(5, dtype=np.float32).reshape(1, 1, 5, 1) ** 2
  out = warp.sample_horizontal(image, np.full((1, 1, 5, 1), 0.5, np.float32)).numpy()
  np.testing.assert_allclose(out[0, 0, :, 0], [0.5, 2.5, 6.5, 12.5, 16.0])


def test_gradients_match_central_differences():
  image = _random((1, 2, 5, 2), seed=5, dtype=np.float64)
  # Fractional parts away from 0 and positions inside the image: the sampler is smooth.
  offset = np.array([0.3, 1.4, -0.6, 0.2, -2.7, 0.45, -0.35, 1.25, 0.6, -3.3],
                    np.float64).reshape(1, 2, 5, 1)
  weights = _random((1, 2, 5, 2), seed=6, dtype=np.float64)

  def objective(img, off):
    return tf.reduce_sum(warp.sample_horizontal(img, off) * weights)

  img_t, off_t = tf.constant(image), tf.constant(offset)
  with tf.GradientTape() as tape:
    tape.watch([img_t, off_t])
    value = objective(img_t, off_t)
  grad_image, grad_offset = tape.gradient(value, [img_t, off_t])

  eps = 1e-6
  for array, analytic, is_image in ((image, grad_image.numpy(), True),
                                    (offset, grad_offset.numpy(), False)):
    numeric = np.zeros_like(array)
    for idx in np.ndindex(array.shape):
      plus, minus = array.copy(), array.copy()
      plus[idx] += eps
      minus[idx] -= eps
      args_p = (plus, offset) if is_image else (image, plus)
      args_m = (minus, offset) if is_image else (image, minus)
      numeric[idx] = (objective(*args_p) - objective(*args_m)).numpy() / (2 * eps)
    np.testing.assert_allclose(analytic, numeric, atol=1e-7)
  assert np.abs(grad_offset.numpy()).min() > 0  # Every offset moved its sample.


def test_offset_gradient_is_zero_where_clamped():
  image = _random((1, 1, 4, 1), seed=7)
  offset = tf.constant(np.full((1, 1, 4, 1), 10.0, np.float32))
  with tf.GradientTape() as tape:
    tape.watch(offset)
    value = tf.reduce_sum(warp.sample_horizontal(image, offset))
  np.testing.assert_array_equal(tape.gradient(value, offset).numpy(), 0.0)


def test_jit_compiled_matches_eager():
  image = _random((2, 4, 16, 3), seed=8)
  offset = _random((2, 4, 16, 1), seed=9, low=-5.0, high=5.0)
  compiled = tf.function(warp.sample_horizontal, jit_compile=True)
  np.testing.assert_allclose(compiled(tf.constant(image), tf.constant(offset)).numpy(),
                             warp.sample_horizontal(image, offset).numpy(), atol=1e-6)


def test_in_bounds_mask():
  offset = np.array([-0.5, -1.0, 0.0, 1.0, 1.5], np.float32).reshape(1, 1, 5, 1)
  # Positions x + offset: -0.5, 0, 2, 4, 5.5 with W - 1 = 4.
  mask = warp.in_bounds_mask(offset).numpy()
  assert mask.shape == (1, 1, 5, 1)
  np.testing.assert_array_equal(mask[0, 0, :, 0], [0, 1, 1, 1, 0])


@pytest.mark.parametrize('image_shape, offset_shape, name', [
    ((2, 4, 5), (2, 4, 5, 1), 'image'),
    ((1, 2, 4, 5), (1, 2, 4, 2), 'offset'),
    ((1, 2, 4, 5), (1, 2, 3, 1), 'offset'),
])
def test_bad_shapes_raise(image_shape, offset_shape, name):
  with pytest.raises(ValueError, match=name):
    warp.sample_horizontal(np.zeros(image_shape, np.float32),
                           np.zeros(offset_shape, np.float32))
