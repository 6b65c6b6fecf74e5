"""Known answers of the matching features' loss."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.training import feature_loss


def _shifted_pair(d):
  """Distinct unit descriptors per column; the left pixel x shows the right pixel x - d."""
  w = 24
  right = np.eye(w, dtype=np.float32)[None, None].repeat(2, axis=1)  # [1, 2, W, W]
  left = np.roll(right, d, axis=2)  # left[x] = right[x - d]
  return tf.constant(left), tf.constant(right)


def test_the_true_disparity_wins_and_costs_little():
  left, right = _shifted_pair(3)
  disparity = tf.fill([1, 2, 24], 3.0)
  valid = tf.ones([1, 2, 24], tf.bool)
  good = feature_loss.matching_loss(left, right, disparity, valid, -4, 12, 10.0)
  wrong = feature_loss.matching_loss(left, right, disparity + 4.0, valid, -4, 12, 10.0)
  assert float(good['accuracy']) == pytest.approx(1.0)
  assert float(wrong['accuracy']) == pytest.approx(0.0)
  # Logit 10 at the match, 0 at the (at most 11) others: loss <= log(1 + 11 exp(-10)).
  assert float(good['loss']) < 1e-3 < float(wrong['loss'])


def test_fractional_disparities_split_the_target_and_invalid_pixels_do_not_count():
  left, right = _shifted_pair(2)
  valid = tf.constant(np.arange(24)[None, None].repeat(2, 1) >= 12)
  half = feature_loss.matching_loss(left, right, tf.fill([1, 2, 24], 2.5), valid, -4, 12, 10.0)
  # Half the target sits on a candidate 10 logits below the winner: ~0.5 * 10 nats.
  assert float(half['loss']) == pytest.approx(5.0, abs=0.05)
  assert float(half['accuracy']) == pytest.approx(1.0)
