"""Known-answer tests of the concatenation cost volume and soft-argmin."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.ops import cost_volume


def test_slices_pair_left_x_with_right_x_minus_d():
  rng = np.random.default_rng(0)
  left = rng.normal(size=(2, 3, 7, 2)).astype(np.float32)
  right = rng.normal(size=(2, 3, 7, 2)).astype(np.float32)
  volume = cost_volume.concat_cost_volume(tf.constant(left), tf.constant(right), 4).numpy()
  assert volume.shape == (2, 4, 3, 7, 4)
  for d in range(4):
    np.testing.assert_array_equal(volume[:, d, :, :, :2], left)
    expected = np.zeros_like(right)
    expected[:, :, d:] = right[:, :, :7 - d]  # Right feature at x - d, zero outside.
    np.testing.assert_array_equal(volume[:, d, :, :, 2:], expected)


def test_rejects_non_positive_levels():
  with pytest.raises(ValueError, match='num_disparities'):
    cost_volume.concat_cost_volume(tf.zeros([1, 2, 2, 1]), tf.zeros([1, 2, 2, 1]), 0)


def test_one_hot_cost_soft_argmins_to_its_index():
  index = np.array([[0, 3], [5, 2]])
  cost = np.full((1, 6, 2, 2), 100.0, np.float32)
  for (y, x), d in np.ndenumerate(index):
    cost[0, d, y, x] = 0.0  # The only plausible level.
  disparity = cost_volume.soft_argmin(tf.constant(cost)).numpy()
  assert disparity.shape == (1, 2, 2, 1)
  np.testing.assert_allclose(disparity[0, ..., 0], index, atol=1e-6)


def test_uniform_cost_gives_the_mean_level():
  disparity = cost_volume.soft_argmin(tf.zeros([1, 5, 1, 1])).numpy()
  np.testing.assert_allclose(disparity, 2.0, atol=1e-6)  # Mean of 0..4.


def test_two_equal_minima_give_their_midpoint():
  cost = np.full((1, 8, 1, 1), 50.0, np.float32)
  cost[0, 2] = cost[0, 3] = 0.0
  np.testing.assert_allclose(cost_volume.soft_argmin(tf.constant(cost)).numpy(), 2.5,
                             atol=1e-6)
