"""Op- and layer-level measurements of experiments/benchmark.py (each in a fresh process).

Where the 3D encoder-decoder's time goes: every layer of `StereoNet.filter_volume` timed
alone, forward + backward, at the shapes it has in the paper-configuration train step
(batch 2: the direct and the mirrored pass), and TF's three kernels of the stride-2 3D conv
and transposed conv at the largest such layers; the two stride-2 conv implementations of
`ops/conv3d.py`; the warp op against a gather-based implementation of the same maths.
"""

import numpy as np
import tensorflow as tf

from experiments import benchmark_workers as workers
from mixstereo_tf import models
from mixstereo_tf.models import stereo
from mixstereo_tf.ops import conv3d
from mixstereo_tf.ops import warp

_STRIDES = [1, 2, 2, 2, 1]


def _layer_flops(layer, x, y) -> float:
  """Forward GFLOP of a conv layer: 2 x k^3 x C_in x C_out x (the strided side's voxels)."""
  conv = getattr(layer, 'conv', layer)
  transposed = getattr(conv, 'transposed', False)
  voxels = np.prod(x.shape[:-1]) if transposed else np.prod(y.shape[:-1])
  return 2.0 * float(np.prod(conv.kernel.shape)) * float(voxels) / 1e9


def _time_layer(layer, x, repeats):
  """(forward+backward timing of layer at input x, its train GFLOP, its output)."""
  y = layer(x, training=True)
  time_fn = workers.gradient_fn(lambda: layer(x, training=True),
                                [x] + layer.trainable_variables)
  return workers.timed(time_fn, repeats), 3 * _layer_flops(layer, x, y), y


def stereo_layers(repeats: int = 2) -> dict:
  """Each layer of the paper-configuration 3D encoder-decoder, forward + backward alone."""
  config = models.ModelConfig()
  net = models.build_model(config).stereo
  height, width = 256 // 2, 512 // 2
  volume = tf.random.stateless_normal(
      [2, config.max_disparity // 2, height, width, 2 * config.stereo_features], [5, 0])
  rows = []

  def run(layer, x, name):
    result, gflop, y = _time_layer(layer, x, repeats)
    rows.append({'layer': name, 'input': list(x.shape), 'seconds': result['median'],
                 'train_gflop': gflop})
    return y

  # The wiring of StereoNet.filter_volume (GC-Net layers 19-37).
  x = volume
  for layer in net.volume_in:
    x = run(layer, x, layer.name)
  skips, down = [x], volume
  for strided, first, second in zip(net.encoder_strided, net.encoder_first,
                                    net.encoder_second):
    down = run(strided, down, strided.name)
    skips.append(run(second, run(first, down, first.name), second.name))
  x = skips.pop()
  for deconv, skip in zip(net.decoder, reversed(skips)):
    x = run(deconv, x, deconv.name) + skip
  run(net.volume_out, x, net.volume_out.name)
  return {'rows': rows}


def stride2_kernels(repeats: int = 3) -> dict:
  """TF's forward, input-gradient and kernel-gradient kernels of the largest stride-2 layers.

  conv3d_down0: stride-2 conv [2, 48, 128, 256, 64] -> 64; deconv3d_0: stride-2 transposed
  conv [2, 24, 64, 128, 64] -> 32. A transposed conv's forward is TF's conv input gradient
  and its input gradient a strided conv.
  """
  rng = tf.random.Generator.from_seed(4)
  rows = {}
  for name, big, small, kernel_shape in (
      ('conv3d_down0', [2, 48, 128, 256, 64], [2, 24, 64, 128, 64], [3, 3, 3, 64, 64]),
      ('deconv3d_0', [2, 48, 128, 256, 32], [2, 24, 64, 128, 64], [3, 3, 3, 32, 64])):
    x, dy, kernel = rng.normal(big), rng.normal(small), rng.normal(kernel_shape)
    gflop = 2.0 * np.prod(kernel_shape) * np.prod(small[:-1]) / 1e9
    kernels = {
        'strided conv (Conv3D)': lambda x=x, k=kernel: tf.nn.conv3d(x, k, _STRIDES, 'SAME'),
        'input gradient (Conv3DBackpropInputV2)': lambda x=x, k=kernel, dy=dy: (
            tf.raw_ops.Conv3DBackpropInputV2(input_sizes=x.shape, filter=k, out_backprop=dy,
                                             strides=_STRIDES, padding='SAME')),
        'kernel gradient (Conv3DBackpropFilterV2)': lambda x=x, k=kernel, dy=dy: (
            tf.raw_ops.Conv3DBackpropFilterV2(input=x, filter_sizes=k.shape,
                                              out_backprop=dy, strides=_STRIDES,
                                              padding='SAME'))}
    for kernel_name, fn in kernels.items():
      compiled = tf.function(fn)
      result = workers.timed(lambda f=compiled: f().numpy(), repeats)
      rows[f'{name}: {kernel_name}'] = {'seconds': result['median'], 'gflop': gflop}
  return rows


def gather_sample_horizontal(image: tf.Tensor, offset: tf.Tensor) -> tf.Tensor:
  """Reference for warp.sample_horizontal: flat-index gathers on [B*H*W, C] rows."""
  batch, height, width, channels = tf.unstack(tf.shape(image))
  x = tf.range(width, dtype=image.dtype)[None, None, :] + offset[..., 0]
  x = tf.clip_by_value(x, 0.0, tf.cast(width - 1, image.dtype))
  x0 = tf.floor(x)
  weight = (x - x0)[..., None]
  row_start = tf.reshape(tf.range(batch * height) * width, [batch, height, 1])
  i0 = tf.cast(x0, tf.int32)
  i1 = tf.minimum(i0 + 1, width - 1)
  flat = tf.reshape(image, [-1, channels])
  v0 = tf.gather(flat, row_start + i0)
  v1 = tf.gather(flat, row_start + i1)
  return (1.0 - weight) * v0 + weight * v1


def warp_ops(repeats: int = 10) -> dict:
  """sample_horizontal vs the gather reference, forward+backward on [2, 256, 512, 3]."""
  rng = tf.random.Generator.from_seed(1)
  image = rng.uniform([2, 256, 512, 3], -1.0, 1.0)
  offset = rng.uniform([2, 256, 512, 1], -60.0, 4.0)
  difference = float(tf.reduce_max(tf.abs(warp.sample_horizontal(image, offset) -
                                          gather_sample_horizontal(image, offset))))
  result = {'max_abs_difference': difference}
  for name, fn in (('warp.sample_horizontal', warp.sample_horizontal),
                   ('gather reference', gather_sample_horizontal)):
    result[name] = workers.timed(
        workers.gradient_fn(lambda fn=fn: fn(image, offset), [image, offset]), repeats)
  return result


def conv3d_implementation(implementation: str, repeats: int = 2) -> dict:
  """Stereo module fwd+bwd (128x256 input, 96 levels) and single stride-2 layers."""
  net = stereo.StereoNet(conv3d_implementation=implementation)
  rng = tf.random.Generator.from_seed(2)
  left, right = (rng.uniform([1, 128, 256, 3], -1.0, 1.0) for _ in range(2))
  net(left[:, :32, :32], right[:, :32, :32])
  timed, gradient_fn = workers.timed, workers.gradient_fn
  result = {'stereo module 128x256 fwd+bwd': timed(gradient_fn(
      lambda: net(left, right, training=True), net.trainable_variables), repeats,
                                                   warmup=False)}
  x = rng.normal([2, 48, 128, 256, 64])
  kernel = tf.Variable(rng.normal([3, 3, 3, 64, 64]) * 0.05)
  forward = tf.function(lambda: conv3d.conv3d_stride2(x, kernel, implementation))
  result['stride-2 conv 2x48x128x256x64 -> 64 fwd'] = timed(lambda: forward().numpy(),
                                                            repeats)
  result['stride-2 conv 2x48x128x256x64 -> 64 fwd+bwd'] = timed(gradient_fn(
      lambda: conv3d.conv3d_stride2(x, kernel, implementation), [x, kernel]), repeats)
  y = rng.normal([2, 24, 64, 128, 64])
  transposed = tf.Variable(rng.normal([3, 3, 3, 32, 64]) * 0.05)
  result['transposed 2x24x64x128x64 -> 32 fwd+bwd'] = timed(gradient_fn(
      lambda: conv3d.conv3d_transpose_stride2(y, transposed, implementation), [y, transposed]),
      repeats)
  return result


WORKERS = {'layers': stereo_layers, 'stride2_kernels': stride2_kernels,
           'warp': warp_ops, 'conv3d_impl': conv3d_implementation}
