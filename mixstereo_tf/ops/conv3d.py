"""Stride-2 3D convolution and transposed convolution with a CPU-fast implementation.

TensorFlow's CPU kernel for the input gradient of a stride-2 `conv3d` (the same kernel runs
the forward pass of `conv3d_transpose`) was measured 20-60x slower than a stride-1 conv of
the same output size (experiments/BENCHMARKS.md). The 'dense' implementations below compute
exactly the same function with stride-1 convolutions only:
  * stride-2 conv = stride-1 conv, then keep every other voxel;
  * stride-2 transposed conv = zero-insertion upsampling, then a stride-1 conv with the
    spatially flipped kernel.
'native' calls the strided ops directly (the better choice on GPUs). Both take the same
kernels, so checkpoints do not depend on the choice.

Shapes: inputs [B, D, H, W, C]; kernels as Keras stores them: conv [k, k, k, C_in, C_out],
transposed conv [k, k, k, C_out, C_in]. Padding is TF 'SAME'; sizes must be even for the
stride-2 conv and are doubled by the transposed conv.
"""

import tensorflow as tf

IMPLEMENTATIONS = ('auto', 'native', 'dense')


def resolve_implementation(implementation: str) -> str:
  """'auto' -> 'native' when a GPU is visible, else 'dense'."""
  if implementation not in IMPLEMENTATIONS:
    raise ValueError(f'conv3d implementation must be one of {IMPLEMENTATIONS}, got '
                     f'{implementation!r}.')
  if implementation == 'auto':
    return 'native' if tf.config.list_logical_devices('GPU') else 'dense'
  return implementation


def conv3d_stride2(x: tf.Tensor, kernel: tf.Tensor, implementation: str = 'auto'
                   ) -> tf.Tensor:
  """3D conv, stride 2, 'SAME' padding: [B, D, H, W, C] -> [B, D/2, H/2, W/2, C_out]."""
  if resolve_implementation(implementation) == 'native':
    return tf.nn.conv3d(x, kernel, [1, 2, 2, 2, 1], 'SAME')
  size = kernel.shape[0]
  # TF 'SAME' with stride 2 on an even size pads (k - 2) // 2 before; with stride 1 it
  # pads (k - 1) // 2 before, so the stride-1 output is offset by `start` voxels.
  start = (size - 1) // 2 - (size - 2) // 2
  full = tf.nn.conv3d(x, kernel, [1, 1, 1, 1, 1], 'SAME')
  return full[:, start::2, start::2, start::2, :]


def _zero_insert(x: tf.Tensor) -> tf.Tensor:
  """[B, D, H, W, C] -> [B, 2D, 2H, 2W, C] with x at even positions, zeros elsewhere."""
  for axis in (1, 2, 3):
    x = tf.stack([x, tf.zeros_like(x)], axis=axis + 1)
    shape = tf.unstack(tf.shape(x))
    new_shape = shape[:axis] + [shape[axis] * 2] + shape[axis + 2:]
    x = tf.reshape(x, tf.stack(new_shape))
  return x


def conv3d_transpose_stride2(x: tf.Tensor, kernel: tf.Tensor,
                             implementation: str = 'auto') -> tf.Tensor:
  """3D transposed conv, stride 2, 'SAME': [B, D, H, W, C_in] -> [B, 2D, 2H, 2W, C_out]."""
  batch, depth, height, width = tf.unstack(tf.shape(x)[:4])
  out_channels = kernel.shape[3]
  if resolve_implementation(implementation) == 'native':
    output_shape = tf.stack([batch, 2 * depth, 2 * height, 2 * width, out_channels])
    return tf.nn.conv3d_transpose(x, kernel, output_shape, [1, 2, 2, 2, 1], 'SAME')
  size = kernel.shape[0]
  # The transposed conv scatters x[i] to outputs 2i + k - p (p = (k - 2) // 2); as a
  # correlation over the zero-inserted input that is padding k - 1 - p before, p after.
  before = (size - 2) // 2
  pads = [[0, 0]] + [[size - 1 - before, before]] * 3 + [[0, 0]]
  flipped = tf.transpose(tf.reverse(kernel, [0, 1, 2]), [0, 1, 2, 4, 3])
  upsampled = tf.pad(_zero_insert(x), pads)
  return tf.nn.conv3d(upsampled, flipped, [1, 1, 1, 1, 1], 'VALID')
