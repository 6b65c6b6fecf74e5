"""Stride-2 3D convolution and transposed convolution with a CPU-fast implementation.

TensorFlow's CPU kernel for the input gradient of a stride-2 `conv3d` (the same kernel runs
the forward pass of `conv3d_transpose`) was measured 20-60x slower than a stride-1 conv of
the same output size (experiments/BENCHMARKS.md). The 'dense' implementations below compute
exactly the same function with stride-1 convolutions only:
  * stride-2 conv = stride-1 conv, then keep every other voxel;
  * stride-2 transposed conv = its sub-pixel form: one stride-1 conv at the input
    resolution whose 8 x C_out channels are the 8 output phases, interleaved afterwards.
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


def _phase_taps(size: int):
  """Per axis: for each output phase a (o = 2j + a), the kernel index of each input tap.

  A stride-2 'SAME' transposed conv sends input i through kernel index kk to output
  o = 2i + kk - p, p = (size - 2) // 2. Output 2j + a therefore reads inputs j + m with
  kk = a + p - 2m. Returns (table [2, taps] with `size` meaning 'no weight', first offset).
  """
  p = (size - 2) // 2
  offsets = {a: {(a + p - kk) // 2: kk for kk in range(size) if (a + p - kk) % 2 == 0}
             for a in (0, 1)}
  low = min(min(o) for o in offsets.values())
  high = max(max(o) for o in offsets.values())
  table = [[offsets[a].get(m, size) for m in range(low, high + 1)] for a in (0, 1)]
  return table, low, high


def conv3d_transpose_stride2(x: tf.Tensor, kernel: tf.Tensor,
                             implementation: str = 'auto') -> tf.Tensor:
  """3D transposed conv, stride 2, 'SAME': [B, D, H, W, C_in] -> [B, 2D, 2H, 2W, C_out]."""
  batch, depth, height, width = tf.unstack(tf.shape(x)[:4])
  size, out_channels, in_channels = kernel.shape[0], kernel.shape[3], kernel.shape[4]
  if resolve_implementation(implementation) == 'native':
    output_shape = tf.stack([batch, 2 * depth, 2 * height, 2 * width, out_channels])
    return tf.nn.conv3d_transpose(x, kernel, output_shape, [1, 2, 2, 2, 1], 'SAME')
  # Sub-pixel form: one stride-1 conv at the input resolution computes all 8 output
  # phases (2 per axis) as channels, then they are interleaved into the doubled grid.
  table, low, high = _phase_taps(size)
  taps = high - low + 1
  padded = tf.pad(kernel, [[0, 1]] * 3 + [[0, 0]] * 2)  # Index `size` = zero weight.
  phased = padded
  for axis in range(3):  # [.., k+1, ..] -> [.., 2, taps, ..] on each spatial axis.
    phased = tf.gather(phased, table, axis=2 * axis)
  # [2, T, 2, T, 2, T, out, in] -> [T, T, T, in, 2, 2, 2, out] -> [T, T, T, in, 8 out].
  phased = tf.transpose(phased, [1, 3, 5, 7, 0, 2, 4, 6])
  phased = tf.reshape(phased, [taps, taps, taps, in_channels, 8 * out_channels])
  pads = [[0, 0]] + [[-low, high]] * 3 + [[0, 0]]
  y = tf.nn.conv3d(tf.pad(x, pads), phased, [1, 1, 1, 1, 1], 'VALID')
  y = tf.reshape(y, tf.stack([batch, depth, height, width, 2, 2, 2, out_channels]))
  y = tf.transpose(y, [0, 1, 4, 2, 5, 3, 6, 7])
  return tf.reshape(y, tf.stack([batch, 2 * depth, 2 * height, 2 * width, out_channels]))
