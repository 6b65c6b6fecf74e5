"""Stride-2 3D convolution and transposed convolution, in two implementations.

'native' calls TF's strided ops. 'dense' computes exactly the same function and gradients
without TF's stride-2 input-gradient kernel (Conv3DBackpropInputV2, which also runs the
forward pass of `conv3d_transpose`), which some TF/CPU builds run far slower than the other
forms of the same maths:
  * stride-2 conv: forward = TF's strided conv; input gradient = the sub-pixel transposed
    conv below; kernel gradient = a stride-1 filter gradient on the input's 8 phases for
    narrow inputs, TF's stride-2 Conv3DBackpropFilterV2 for wide ones;
  * stride-2 transposed conv: forward = its sub-pixel form, one stride-1 conv at the input
    resolution whose 8 x C_out channels are the 8 output phases, interleaved afterwards;
    input gradient = TF's strided conv; kernel gradient = the same phase form.
Both are `tf.custom_gradient`s, so no activation larger than the layer's own input and
output is kept for the backward pass. 'auto' is 'native': on this project's CPU benchmark
(TF 2.21, oneDNN; experiments/BENCHMARKS.md section 8) it was faster for every stride-2
layer of the paper configuration, as it is on GPUs; the training loop makes it 'dense'
under XLA on a CPU (`auto_implementation`). Both take the same kernels, so
checkpoints do not depend on the choice.

Shapes: inputs [B, D, H, W, C]; kernels as Keras stores them: conv [k, k, k, C_in, C_out],
transposed conv [k, k, k, C_out, C_in]. Padding is TF 'SAME'; sizes must be even for the
stride-2 conv and are doubled by the transposed conv.
"""

import tensorflow as tf

IMPLEMENTATIONS = ('auto', 'native', 'dense')
_STRIDES = [1, 2, 2, 2, 1]
# Widest input of the phase-form kernel gradient (experiments/BENCHMARKS.md, section 8).
_PHASE_MAX_CHANNELS = 16


def auto_implementation(device_type: str, jit_compile: bool) -> str:
  """What 'auto' should mean for a train step on `device_type` ('CPU', 'GPU', ...).

  'dense' under XLA on a CPU: XLA's CPU code for the strided ops' gradients made the
  paper-configuration step more than 5x slower than 'dense' (experiments/BENCHMARKS.md);
  'native' everywhere else.
  """
  return 'dense' if jit_compile and device_type.upper() == 'CPU' else 'native'


def resolve_implementation(implementation: str) -> str:
  """Validates the name; 'auto' -> 'native' (the measured faster one, module docstring)."""
  if implementation not in IMPLEMENTATIONS:
    raise ValueError(f'conv3d implementation must be one of {IMPLEMENTATIONS}, got '
                     f'{implementation!r}.')
  return 'native' if implementation == 'auto' else implementation


def conv3d_stride2(x: tf.Tensor, kernel: tf.Tensor, implementation: str = 'auto'
                   ) -> tf.Tensor:
  """3D conv, stride 2, 'SAME' padding: [B, D, H, W, C] -> [B, D/2, H/2, W/2, C_out]."""
  if resolve_implementation(implementation) == 'native':
    return tf.nn.conv3d(x, kernel, _STRIDES, 'SAME')
  return _fast_conv3d_stride2(x, tf.convert_to_tensor(kernel))


def _filter_gradient(inputs: tf.Tensor, kernel: tf.Tensor, out_backprop: tf.Tensor
                     ) -> tf.Tensor:
  """Kernel gradient of the stride-2 'SAME' conv inputs -> out_backprop's shape.

  TF's stride-2 Conv3DBackpropFilterV2 was measured 6x slower than the alternative for
  narrow layers (C_in = 16) but 4x faster for wide ones (C_in = 64), where the stride-1
  kernel on 8 C_in channels is slow; narrow inputs therefore use the phase (space-to-depth)
  form: output o reads input 2(o + m) + a through kernel index
  kk = 2m + a + p, so splitting the input into its 8 phases (2 per axis, as channels) turns
  the stride-2 correlation into a stride-1 VALID one whose taps are rearranged into the
  kernel gradient [k, k, k, C_in, C_out].
  """
  size, in_channels, out_channels = kernel.shape[0], kernel.shape[3], kernel.shape[4]
  if in_channels > _PHASE_MAX_CHANNELS:
    return tf.raw_ops.Conv3DBackpropFilterV2(
        input=inputs, filter_sizes=tf.shape(kernel), out_backprop=out_backprop,
        strides=_STRIDES, padding='SAME')
  taps = [divmod(kk - (size - 2) // 2, 2) for kk in range(size)]  # (m, a) per index.
  low = min(m for m, _ in taps)
  span = max(m for m, _ in taps) - low + 1
  batch, depth, height, width = tf.unstack(tf.shape(inputs)[:4])
  phases = tf.reshape(inputs, tf.stack([batch, depth // 2, 2, height // 2, 2, width // 2, 2,
                                        in_channels]))
  phases = tf.transpose(phases, [0, 1, 3, 5, 2, 4, 6, 7])
  phases = tf.reshape(phases, tf.stack([batch, depth // 2, height // 2, width // 2,
                                        8 * in_channels]))
  phases = tf.pad(phases, [[0, 0]] + [[-low, span - 1 + low]] * 3 + [[0, 0]])
  gradient = tf.raw_ops.Conv3DBackpropFilterV2(
      input=phases, filter_sizes=[span, span, span, 8 * in_channels, out_channels],
      out_backprop=out_backprop, strides=[1] * 5, padding='VALID')
  gradient = tf.reshape(gradient, [span, span, span, 2, 2, 2, in_channels, out_channels])
  indices = [[[[m0 - low, m1 - low, m2 - low, a0, a1, a2]
               for m2, a2 in taps] for m1, a1 in taps] for m0, a0 in taps]
  return tf.gather_nd(gradient, indices)


@tf.custom_gradient
def _fast_conv3d_stride2(x, kernel):
  """Native strided forward; the backward avoids the slow stride-2 input-gradient kernel."""

  def gradient(dy):
    # d/dx of a SAME stride-2 conv is the SAME stride-2 transposed conv with the same kernel
    # (layout [k, k, k, C_in, C_out] = transposed [k, k, k, out, in]) back to x's shape.
    return _subpixel_transpose(dy, kernel), _filter_gradient(x, kernel, dy)

  return tf.nn.conv3d(x, kernel, _STRIDES, 'SAME'), gradient


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
  if resolve_implementation(implementation) == 'native':
    batch, depth, height, width = tf.unstack(tf.shape(x)[:4])
    output_shape = tf.stack([batch, 2 * depth, 2 * height, 2 * width, kernel.shape[3]])
    return tf.nn.conv3d_transpose(x, kernel, output_shape, _STRIDES, 'SAME')
  return _fast_conv3d_transpose_stride2(x, tf.convert_to_tensor(kernel))


@tf.custom_gradient
def _fast_conv3d_transpose_stride2(x, kernel):
  """Sub-pixel forward; the backward is the transposed conv's own adjoint, a strided conv."""

  def gradient(dy):
    # The transposed conv is the input gradient of conv(., kernel) evaluated at x, so its
    # adjoint maps dy through that conv, and its kernel gradient swaps the roles of x, dy.
    return (tf.nn.conv3d(dy, kernel, _STRIDES, 'SAME'),
            _filter_gradient(dy, kernel, x))

  return _subpixel_transpose(x, kernel), gradient


def _subpixel_transpose(x: tf.Tensor, kernel: tf.Tensor) -> tf.Tensor:
  """Stride-2 SAME transposed conv as one stride-1 conv emitting the 8 output phases."""
  batch, depth, height, width = tf.unstack(tf.shape(x)[:4])
  size, out_channels, in_channels = kernel.shape[0], kernel.shape[3], kernel.shape[4]
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
