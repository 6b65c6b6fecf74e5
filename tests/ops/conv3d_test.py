"""The CPU-fast stride-2 3D convolutions equal TensorFlow's strided ops exactly."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.models import stereo
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


def _value_and_gradients(op, x, kernel, implementation, upstream, jit_compile=False):
  """op's output and the gradients of <op(x, kernel), upstream> w.r.t. x and kernel."""

  @tf.function(jit_compile=jit_compile)
  def run():
    with tf.GradientTape() as tape:
      tape.watch([x, kernel])
      y = op(x, kernel, implementation)
      loss = tf.reduce_sum(y * upstream)
    return [y] + tape.gradient(loss, [x, kernel])

  return [t.numpy() for t in run()]


@pytest.mark.parametrize('size,channels', [(2, 3), (3, 3), (4, 3), (5, 3), (3, 17)])
def test_stride2_conv_gradients_match_native(size, channels):
  # 3 input channels take the phase-form kernel gradient, 17 TF's strided one.
  x = tf.random.stateless_normal([2, 4, 6, 8, channels], [6, size])
  kernel = tf.random.stateless_normal([size, size, size, channels, 5], [7, size])
  upstream = tf.random.stateless_normal([2, 2, 3, 4, 5], [8, size])
  native = _value_and_gradients(conv3d.conv3d_stride2, x, kernel, 'native', upstream)
  dense = _value_and_gradients(conv3d.conv3d_stride2, x, kernel, 'dense', upstream)
  for name, want, got in zip(('y', 'dx', 'dkernel'), native, dense):
    assert got.shape == want.shape, name
    np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-4, err_msg=name)


@pytest.mark.parametrize('size', [2, 3, 4, 5])
def test_stride2_transposed_conv_gradients_match_native(size):
  x = tf.random.stateless_normal([2, 2, 3, 4, 3], [9, size])
  kernel = tf.random.stateless_normal([size, size, size, 5, 3], [10, size])
  upstream = tf.random.stateless_normal([2, 4, 6, 8, 5], [11, size])
  op = conv3d.conv3d_transpose_stride2
  native = _value_and_gradients(op, x, kernel, 'native', upstream)
  dense = _value_and_gradients(op, x, kernel, 'dense', upstream)
  for name, want, got in zip(('y', 'dx', 'dkernel'), native, dense):
    assert got.shape == want.shape, name
    np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-4, err_msg=name)


def test_stride2_conv_input_gradient_of_an_impulse_is_the_kernel():
  # TF's SAME stride-2 conv with k = 3 on size 4 pads 0 before (1 after), so output voxel
  # (0, 0, 0) reads x[kk] through kernel[kk]: d y[0,0,0] / dx is the kernel in the corner.
  x = tf.zeros([1, 4, 4, 4, 1])
  kernel = tf.reshape(tf.range(27, dtype=tf.float32), [3, 3, 3, 1, 1])
  upstream = np.zeros([1, 2, 2, 2, 1], np.float32)
  upstream[0, 0, 0, 0, 0] = 1.0
  _, dx, _ = _value_and_gradients(conv3d.conv3d_stride2, x, kernel, 'dense',
                                  tf.constant(upstream))
  expected = np.zeros([4, 4, 4], np.float32)
  expected[:3, :3, :3] = kernel.numpy()[..., 0, 0]
  np.testing.assert_array_equal(dx[0, ..., 0], expected)


def test_chained_gradients_match_native_under_xla():
  x = tf.random.stateless_normal([1, 4, 4, 4, 2], [4, 0])
  kernel = tf.random.stateless_normal([3, 3, 3, 2, 2], [5, 0])

  def chain(x, kernel, implementation):
    return conv3d.conv3d_transpose_stride2(
        conv3d.conv3d_stride2(x, kernel, implementation), kernel, implementation)

  upstream = tf.random.stateless_normal([1, 4, 4, 4, 2], [12, 0])
  native = _value_and_gradients(chain, x, kernel, 'native', upstream)
  dense = _value_and_gradients(chain, x, kernel, 'dense', upstream, jit_compile=True)
  for want, got in zip(native, dense):
    np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-4)


def test_gradient_reaches_a_keras_layer_kernel():
  layer = stereo.Strided3D(4, 3, implementation='dense')
  native = stereo.Strided3D(4, 3, implementation='native')
  x = tf.random.stateless_normal([1, 4, 4, 4, 2], [13, 0])
  layer(x)
  native(x)
  native.kernel.assign(layer.kernel)
  gradients = []
  for conv in (layer, native):
    with tf.GradientTape() as tape:
      loss = tf.reduce_sum(tf.square(conv(x)))
    gradients.append(tape.gradient(loss, conv.kernel).numpy())
  np.testing.assert_allclose(gradients[0], gradients[1], rtol=1e-4, atol=1e-4)
  assert np.abs(gradients[0]).max() > 0


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


def test_auto_is_the_benchmarked_native_implementation():
  # experiments/BENCHMARKS.md: TF's strided ops were faster for every stride-2 layer.
  assert conv3d.resolve_implementation('auto') == 'native'
  assert conv3d.resolve_implementation('dense') == 'dense'
  # Under XLA on a CPU the strided gradients were measured >5x slower: 'dense' there.
  assert conv3d.auto_implementation('CPU', jit_compile=True) == 'dense'
  assert conv3d.auto_implementation('CPU', jit_compile=False) == 'native'
  assert conv3d.auto_implementation('GPU', jit_compile=True) == 'native'
