"""Tests for mixstereo_tf.models.refiner: the hybrid refiner of the classical result."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.models import refiner

TINY = refiner.RefinerConfig(view_widths=(4, 4), disparity_features=4, dilations=(1, 2))


def _inputs(height=8, width=16, seed=0):
  rng = np.random.default_rng(seed)
  images = rng.uniform(-0.9, 0.9, (1, height, width, 9))
  disparities = rng.uniform(-5, 5, (1, height, width, 2))
  return tf.constant(np.concatenate([images, disparities], -1), tf.float32)


def test_untrained_refiner_returns_the_classical_result():
  model = refiner.build_refiner(TINY)
  inputs = _inputs()
  out = model(inputs)
  np.testing.assert_allclose(out['left'], inputs[..., 3:6], atol=1e-6)
  np.testing.assert_allclose(out['right'], inputs[..., 6:9], atol=1e-6)
  np.testing.assert_allclose(out['disparity_left'], inputs[..., 9:10], atol=1e-5)
  np.testing.assert_allclose(out['disparity_right'], inputs[..., 10:11], atol=1e-5)


def test_right_disparity_is_the_left_network_on_the_mirrored_swapped_pair():
  model = refiner.build_refiner(TINY)
  # A non-zero disparity network (its correction is not the identity); the views network
  # stays zero, so the refined views are the classical ones, swapped by the mirroring.
  for weight in model.correction.weights:
    weight.assign(tf.random.stateless_normal(weight.shape, [1, 2]) * 0.1)
  inputs = _inputs(seed=3)
  out = model(inputs)
  mirror = lambda t: tf.reverse(t, axis=[2])
  swapped = tf.concat([inputs[..., :3], inputs[..., 6:9], inputs[..., 3:6],
                       inputs[..., 10:11], inputs[..., 9:10]], -1)
  mirrored = model(mirror(swapped))
  np.testing.assert_allclose(mirror(mirrored['disparity_left']), out['disparity_right'],
                             atol=1e-4)
  assert np.abs(out['disparity_left'] - inputs[..., 9:10]).max() > 1e-3


def test_config_round_trip_and_checks():
  assert refiner.RefinerConfig.from_dict(TINY.to_dict()) == TINY
  model = refiner.RefinerNet.from_config(refiner.build_refiner(TINY).get_config())
  assert model.refiner_config == TINY
  assert TINY.size_multiple == 2
  with pytest.raises(ValueError, match='view_widths'):
    refiner.RefinerConfig(view_widths=(4,))
  with pytest.raises(ValueError, match='Unknown RefinerConfig fields'):
    refiner.RefinerConfig.from_dict({'widths': 3})
  with pytest.raises(ValueError, match='not a multiple of 2'):
    refiner.build_refiner(TINY)(tf.zeros([1, 5, 8, refiner.INPUT_CHANNELS]))
