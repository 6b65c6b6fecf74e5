"""Cost volume and soft-argmin of the stereo module (GC-Net lineage, paper section 3.2).

Sign convention (docs/DESIGN.md): the volume is left-referenced, so slice `d` pairs the left
feature at column x with the right feature at column x - d, the match of a left pixel with
positive disparity d.
"""

import tensorflow as tf


def concat_cost_volume(left_features: tf.Tensor, right_features: tf.Tensor,
                       num_disparities: int) -> tf.Tensor:
  """GC-Net's concatenation cost volume.

  Args:
    left_features: [B, H, W, C] features of the left view.
    right_features: [B, H, W, C] features of the right view.
    num_disparities: D, the number of disparity hypotheses 0 .. D - 1 (in feature pixels).

  Returns:
    [B, D, H, W, 2C]: slice d holds concat(left[x], right[x - d]); where x - d < 0 the right
    half is zero (no match inside the image), as in GC-Net.
  """
  if num_disparities <= 0:
    raise ValueError(f'num_disparities must be positive, got {num_disparities}.')
  width = left_features.shape[2]
  if width is None:
    width = tf.shape(left_features)[2]
  # One zero-padded copy of the right features, sliced D times: every slice is a view the
  # concat below fuses, with no per-disparity index tensors.
  padded = tf.pad(right_features, [[0, 0], [0, 0], [num_disparities - 1, 0], [0, 0]])
  shifted = [padded[:, :, num_disparities - 1 - d:num_disparities - 1 - d + width, :]
             for d in range(num_disparities)]
  right_volume = tf.stack(shifted, axis=1)
  left_volume = tf.broadcast_to(left_features[:, None],
                                tf.shape(right_volume))
  return tf.concat([left_volume, right_volume], axis=-1)


def soft_argmin(cost: tf.Tensor) -> tf.Tensor:
  """GC-Net's soft argmin: d_hat = sum_d d * softmax(-c_d), paper eq. for disparity regression.

  Args:
    cost: [B, D, H, W] matching costs (lower is better) for disparities 0 .. D - 1.

  Returns:
    [B, H, W, 1] float32 sub-pixel disparity in pixels of the cost volume's grid, positive.
  """
  cost = tf.cast(cost, tf.float32)  # Softmax in float32 even under mixed precision.
  probability = tf.nn.softmax(-cost, axis=1)
  levels = tf.range(tf.shape(cost)[1], dtype=tf.float32)
  disparity = tf.reduce_sum(probability * levels[None, :, None, None], axis=1)
  return disparity[..., None]
