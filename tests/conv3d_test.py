"""The CPU-fast stride-2 3D convolutions equal TensorFlow's strided ops exactly."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.ops import conv3d


@pytest.mark.parametrize('size', [2, 3, 4, 5])
def test_dense_stride2_conv_matches_native(size):
  x = tf.random.stateless_normal([2, 4, 6, 8, 3], [0, size])
  kernel = tf.random.stateless_normal([size, size, size, 3, 5], [1, size])
  native = conv3d.conv3d_stride2(x, kernel, 'native')
  dense = conv3d.conv3d_stride2(x, kernel, 'dense')
  assert dense.shape == native.shape == (2, 2, 3, 4, 5)
  np.testing.assert_allclose(dense.numpy(), native.numpy(), atol=1e-5)


@pytest.mark.parametrize('size', [2, 3, 4, 5])
def test_dense_stride2_transposed_conv_matches_native(size):
  x = tf.random.stateless_normal([2, 2, 3, 4, 3], [2, size])
  kernel = tf.random.stateless_normal([size, size, size, 5, 3], [3, size])
  native = conv3d.conv3d_transpose_stride2(x, kernel, 'native')
  dense = conv3d.conv3d_transpose_stride2(x, kernel, 'dense')
  assert dense.shape == native.shape == (2, 4, 6, 8, 5)
  np.testing.assert_allclose(dense.numpy(), native.numpy(), atol=1e-5)


def test_gradients_match_native():
  x = tf.random.stateless_normal([1, 4, 4, 4, 2], [4, 0])
  kernel = tf.random.stateless_normal([3, 3, 3, 2, 2], [5, 0])

  def gradients(implementation):
    with tf.GradientTape() as tape:
      tape.watch([x, kernel])
      y = conv3d.conv3d_transpose_stride2(
          conv3d.conv3d_stride2(x, kernel, implementation), kernel, implementation)
      loss = tf.reduce_sum(y * y)
    return tape.gradient(loss, [x, kernel])

  for native, dense in zip(gradients('native'), gradients('dense')):
    np.testing.assert_allclose(dense.numpy(), native.numpy(), rtol=1e-4, atol=1e-4)


def test_single_impulse_transposed_conv_places_the_kernel():
  # One input voxel at the origin: TF's SAME transposed conv (k = 3, stride 2, no padding
  # before) writes kernel[k] to output k.
  x = np.zeros([1, 2, 2, 2, 1], np.float32)
  x[0, 0, 0, 0, 0] = 1.0
  kernel = np.arange(27, dtype=np.float32).reshape(3, 3, 3, 1, 1)
  y = conv3d.conv3d_transpose_stride2(tf.constant(x), tf.constant(kernel), 'dense').numpy()
  np.testing.assert_array_equal(y[0, :3, :3, :3, 0], kernel[..., 0, 0])
  assert np.count_nonzero(y) == 26  # kernel[0, 0, 0] = 0.


def test_unknown_implementation_is_an_error():
  with pytest.raises(ValueError, match='implementation'):
    conv3d.resolve_implementation('fast')
