"""Tests for mixstereo_tf.training.distribution: strategies, device type, writers, batches."""

import pytest
import tensorflow as tf

from mixstereo_tf.training import distribution


def test_default_strategy_runs_on_this_machines_device_and_writes_to_model_dir():
  strategy = distribution.make_strategy('default')
  assert strategy is tf.distribute.get_strategy()
  expected = 'GPU' if tf.config.list_logical_devices('GPU') else 'CPU'
  assert distribution.device_type(strategy) == expected
  assert distribution.write_dir(strategy, '/runs/a') == (True, '/runs/a')


def test_unknown_strategy_names_the_valid_ones():
  with pytest.raises(ValueError, match="'tpu_pod'.*mirrored"):
    distribution.make_strategy('tpu_pod')


def test_batch_must_be_static_and_split_evenly():
  strategy = tf.distribute.get_strategy()
  fixed = tf.data.Dataset.from_tensors({'mixture': tf.zeros([3, 4, 4, 3])})
  assert distribution.check_batch(fixed, strategy) == 3
  dynamic = tf.data.Dataset.from_tensor_slices({'mixture': tf.zeros([6, 4, 4, 3])}).batch(4)
  with pytest.raises(ValueError, match='static batch size'):
    distribution.check_batch(dynamic, strategy)
