"""Tests for mixstereo_tf.core.colormap: a fixed-range disparity colour map, NumPy and TF."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.core import colormap


def test_colorize_fixed_range():
  disparity = np.array([[0.0, 48.0, 96.0, 200.0]], np.float32)
  colour = colormap.colorize(disparity, 96.0)
  assert colour.shape == (1, 4, 3) and colour.dtype == np.uint8
  np.testing.assert_array_equal(colour[0, 0], [0, 0, 4])  # Ramp start.
  np.testing.assert_array_equal(colour[0, 2], [252, 255, 164])  # Ramp end.
  np.testing.assert_array_equal(colour[0, 3], colour[0, 2])  # Clipped above the range.
  # The same value gets the same colour whatever else is in the image.
  alone = colormap.colorize(np.full((1, 1), 48.0, np.float32), 96.0)
  np.testing.assert_array_equal(alone[0, 0], colour[0, 1])
  with pytest.raises(ValueError, match='low < high'):
    colormap.colorize(disparity, 0.0)


def test_signed_range_and_nan():
  disparity = np.array([[-20.0, 0.0, 20.0, np.nan]], np.float32)
  colour = colormap.colorize(disparity, high=20.0, low=-20.0)
  np.testing.assert_array_equal(colour[0, 0], [0, 0, 4])
  np.testing.assert_array_equal(colour[0, 2], [252, 255, 164])
  np.testing.assert_array_equal(colour[0, 1], colormap.colorize(np.full((1, 1), 0.5),
                                                                1.0)[0, 0])
  np.testing.assert_array_equal(colour[0, 3], colour[0, 0])  # NaN shows as `low`.


def test_tf_batches_match_numpy():
  disparity = np.random.default_rng(0).uniform(-5, 40, (2, 5, 7, 1)).astype(np.float32)
  batch = colormap.colorize_tf(tf.constant(disparity), 32.0).numpy()
  assert batch.shape == (2, 5, 7, 3)
  np.testing.assert_array_equal(batch[1], colormap.colorize(disparity[1, ..., 0], 32.0))
