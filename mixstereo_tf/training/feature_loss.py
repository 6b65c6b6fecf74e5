"""The loss of the learned matching features (not in the paper; the training pairs have
exact disparities): the correlation volume of the left and right descriptors over
[min_disparity, min_disparity + num_disparities) is read as logits (cosine * logit_scale) of
a distribution over disparities, and the cross-entropy against the true disparity's two
nearest integers (weights 1 - frac, frac) is averaged over the left pixels whose match is
visible. It asks the true match to beat every other candidate, which is what
winner-take-all and SGM need. Pure and XLA-safe.
"""

from typing import Dict

import tensorflow as tf


def matching_loss(left: tf.Tensor, right: tf.Tensor, disparity: tf.Tensor, valid: tf.Tensor,
                  min_disparity: int, num_disparities: int,
                  logit_scale: float) -> Dict[str, tf.Tensor]:
  """The module docstring's cross-entropy.

  The candidates of a left pixel x are the right pixels x' of its row with x - x' in
  [min_disparity, min_disparity + num_disparities): the row's full correlation matrix (a
  batched matmul, [B * H, W, W]) masked to that band.

  Args:
    left, right: [B, H, W, C] unit descriptors of the left and right eyes.
    disparity: [B, H, W] true left disparities, signed pixels (x matches x - d).
    valid: [B, H, W] bool, pixels to count (their match visible in the right view).
    min_disparity, num_disparities: the candidates.
    logit_scale: cosine -> logit factor.

  Returns:
    'loss' (nats per counted pixel) and 'accuracy' (share of counted pixels whose best
    candidate is within 1 px of the truth).
  """
  shape = tf.shape(left)
  width = shape[2]
  rows = lambda t: tf.reshape(t, [-1, width, shape[3]])
  logits = tf.matmul(rows(left), rows(right), transpose_b=True) * logit_scale  # [BH, x, x']
  x = tf.range(width, dtype=tf.float32)
  offset = x[:, None] - x[None, :] - float(min_disparity)  # x - x' - d_0, [x, x']
  band = (offset >= 0) & (offset <= num_disparities - 1)
  logits = tf.where(band[None], logits, -1e4)
  match = tf.reshape(x[None, None, :] - disparity, [-1, width])  # x - d, [BH, x]
  valid = tf.reshape(valid, [-1, width]) & (match >= 0) & (match <= tf.cast(width - 1, tf.float32))
  offset_true = tf.reshape(disparity, [-1, width]) - float(min_disparity)
  valid &= (offset_true >= 0) & (offset_true <= num_disparities - 1)
  # Two-hot: 1 - frac at floor(x - d), frac at the next column.
  target = tf.nn.relu(1.0 - tf.abs(x[None, None, :] - match[..., None]))
  cross = -tf.reduce_sum(target * tf.nn.log_softmax(logits, axis=-1), axis=-1)
  weight = tf.cast(valid, tf.float32)
  count = tf.maximum(tf.reduce_sum(weight), 1.0)
  best = tf.cast(tf.argmax(logits, axis=-1), tf.float32)
  hit = tf.cast(tf.abs(best - match) <= 1.0, tf.float32)
  return {'loss': tf.reduce_sum(cross * weight) / count,
          'accuracy': tf.reduce_sum(hit * weight) / count}
