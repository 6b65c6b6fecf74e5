"""Tests of the training loop: resume, NaN stop, distribution, fine-tuning, outputs, mixed
precision and determinism."""

import glob
import json
import math
import os
import types

import numpy as np
import pytest
import tensorflow as tf
from tensorflow.python.framework import config as tf_config

from mixstereo_tf import models
from mixstereo_tf.artifacts import runs
from mixstereo_tf.training import config as config_lib
from mixstereo_tf.training import distribution
from mixstereo_tf.training import loop
from mixstereo_tf.training import objective
from tests import training_helpers


def _train(model_dir, num_steps, batch_size=1, **kwargs):
  nan_from_step = kwargs.pop('nan_from_step', None)
  config = config_lib.TrainConfig(model_dir=str(model_dir), num_steps=num_steps,
                                  learning_rate=1e-3, checkpoint_every=1, summary_every=1,
                                  image_summary_every=2, log_every=1, **kwargs)
  return loop.train(config, training_helpers.MINI, objective.LossConfig(),
                    training_helpers.dataset_fn(batch_size, nan_from_step=nan_from_step,
                                                height=16, width=32, shift=2),
                    flags_text='--num_steps=%d\n' % num_steps)


def _checkpoint_values(path):
  reader = tf.train.load_checkpoint(path)
  return {k: reader.get_tensor(k) for k in reader.get_variable_to_shape_map()
          if k.startswith('model/')}


def test_resume_continues_from_the_saved_step(tmp_path):
  first = _train(tmp_path, 2)
  assert (first.start_step, first.final_step, first.num_replicas) == (0, 2, 1)
  assert first.last_checkpoint.endswith('ckpt-2')
  saved = _checkpoint_values(first.last_checkpoint)
  second = _train(tmp_path, 3)
  assert (second.start_step, second.final_step) == (2, 3)
  assert np.isfinite(second.final_loss)
  assert json.loads((tmp_path / 'config.json').read_text())['model'][
      'max_disparity'] == training_helpers.MINI.max_disparity
  assert (tmp_path / 'flags.txt').read_text() == '--num_steps=3\n'
  assert glob.glob(str(tmp_path / 'train' / 'events.out.tfevents.*'))
  # Resuming with nothing left to do restores the checkpoint as it was.
  model = models.build_model(training_helpers.MINI)
  tf.train.Checkpoint(model=model).read(second.last_checkpoint).expect_partial()
  assert saved.keys() == _checkpoint_values(second.last_checkpoint).keys()


def test_nan_loss_stops_naming_the_step_and_keeps_the_last_good_checkpoint(tmp_path):
  with pytest.raises(loop.NonFiniteLossError, match='at step 3'):
    _train(tmp_path, 5, nan_from_step=3)
  latest = tf.train.latest_checkpoint(str(tmp_path))
  assert latest.endswith('ckpt-2')
  assert all(np.all(np.isfinite(v)) for v in _checkpoint_values(latest).values())


def test_mirrored_strategy_splits_the_batch_over_two_devices(tmp_path):
  assert len(tf.config.list_logical_devices('CPU')) == 2  # tests/conftest.py
  result = _train(tmp_path, 2, batch_size=2, strategy='mirrored')
  assert result.num_replicas == 2
  assert result.final_step == 2 and np.isfinite(result.final_loss)


def test_mirrored_strategy_rejects_a_batch_it_cannot_split(tmp_path):
  with pytest.raises(ValueError, match='not divisible by the 2 replicas'):
    _train(tmp_path, 1, batch_size=1, strategy='mirrored')


def test_init_checkpoint_starts_a_new_run_from_given_weights(tmp_path):
  pretrained = _train(tmp_path / 'pretrain', 1)
  weights = _checkpoint_values(pretrained.last_checkpoint)
  finetune = _train(tmp_path / 'finetune', 1, init_checkpoint=pretrained.last_checkpoint,
                    mode='separation_only')
  assert finetune.start_step == 0
  after = _checkpoint_values(finetune.last_checkpoint)
  stereo = [k for k in weights if k.startswith('model/stereo/')]
  assert stereo and all(np.array_equal(weights[k], after[k]) for k in stereo)


def test_init_checkpoint_may_name_a_run_directory(tmp_path):
  pretrained = _train(tmp_path / 'pretrain', 2)
  weights = _checkpoint_values(pretrained.last_checkpoint)
  assert runs.resolve_checkpoint(str(tmp_path / 'pretrain'))[1] == pretrained.last_checkpoint
  finetune = _train(tmp_path / 'finetune', 1, init_checkpoint=str(tmp_path / 'pretrain'),
                    mode='separation_only')
  after = _checkpoint_values(finetune.last_checkpoint)
  stereo = [k for k in weights if k.startswith('model/stereo/')]
  assert stereo and all(np.array_equal(weights[k], after[k]) for k in stereo)


def test_init_checkpoint_errors_name_the_path(tmp_path):
  (tmp_path / 'empty').mkdir()
  with pytest.raises(ValueError, match='No checkpoint in .*empty'):
    _train(tmp_path / 'run', 1, init_checkpoint=str(tmp_path / 'empty'))
  with pytest.raises(ValueError, match='missing/ckpt-3 is neither'):
    _train(tmp_path / 'run2', 1, init_checkpoint=str(tmp_path / 'missing' / 'ckpt-3'))


def test_a_crash_before_the_first_step_writes_no_checkpoint(tmp_path):
  def broken_dataset(start):
    def fail(element):
      tf.debugging.assert_equal(0, 1, message='corrupt input')
      return element
    return training_helpers.dataset_fn(height=16, width=32, shift=2)(start).map(fail)

  config = config_lib.TrainConfig(model_dir=str(tmp_path), num_steps=3)
  with pytest.raises(tf.errors.InvalidArgumentError, match='corrupt input'):
    loop.train(config, training_helpers.MINI, objective.LossConfig(), broken_dataset)
  assert tf.train.latest_checkpoint(str(tmp_path)) is None


def test_config_validation_names_the_field():
  with pytest.raises(ValueError, match='TrainConfig.num_steps'):
    config_lib.TrainConfig(model_dir='x', num_steps=0)
  with pytest.raises(ValueError, match='TrainConfig.mode'):
    config_lib.TrainConfig(model_dir='x', mode='stereo')
  with pytest.raises(ValueError, match=r'TrainConfig.seed must be in \[0, 2\*\*32\), got -5'):
    config_lib.TrainConfig(model_dir='x', seed=-5)


def test_deterministic_runs_give_identical_weights(tmp_path):
  try:
    first = _train(tmp_path / 'a', 3, deterministic=True)
    second = _train(tmp_path / 'b', 3, deterministic=True)
  finally:
    tf_config.disable_op_determinism()
  a, b = _checkpoint_values(first.last_checkpoint), _checkpoint_values(second.last_checkpoint)
  assert a.keys() == b.keys() and len(a) > 10
  for key in a:
    np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_a_resumed_run_trains_on_the_batches_a_straight_run_would(tmp_path):
  """2 steps, then resumed to 4, equal 4 steps straight: the loop asks the data for the
  batches from the restored step on (they differ per batch here)."""
  batch = training_helpers.stereo_batch(1, height=16, width=32, shift=2)

  def varying(start):  # Batch i is the pair scaled by 1 / (1 + i).
    ds = tf.data.Dataset.range(start, 1 << 30)
    return ds.map(lambda i: {k: v / tf.cast(1 + i, tf.float32) for k, v in batch.items()})

  def train(model_dir, steps):
    config = config_lib.TrainConfig(model_dir=str(model_dir), num_steps=steps,
                                    learning_rate=1e-3, checkpoint_every=1)
    return loop.train(config, training_helpers.MINI, objective.LossConfig(), varying)

  straight = train(tmp_path / 'a', 4)
  train(tmp_path / 'b', 2)
  resumed = train(tmp_path / 'b', 4)
  assert (resumed.start_step, resumed.final_step) == (2, 4)
  a = _checkpoint_values(straight.last_checkpoint)
  b = _checkpoint_values(resumed.last_checkpoint)
  for key in a:
    np.testing.assert_allclose(a[key], b[key], rtol=1e-4, atol=1e-6, err_msg=key)


def test_mixed_precision_on_a_gpu_scales_the_loss_and_logs_unscaled_scalars(
    tmp_path, monkeypatch):
  # The GPU path (mixed_float16, LossScaleOptimizer) run on the CPU's float16 kernels.
  monkeypatch.setattr(distribution, 'device_type', lambda strategy: 'GPU')
  try:
    result = _train(tmp_path, 2, mixed_precision=True, jit_compile='false')
  finally:
    tf.keras.mixed_precision.set_global_policy('float32')
  assert result.final_step == 2 and np.isfinite(result.final_loss)
  assert all(np.all(np.isfinite(v)) for v in _checkpoint_values(result.last_checkpoint).values())
  reader = tf.train.load_checkpoint(result.last_checkpoint)
  assert any('dynamic_scale' in k for k in reader.get_variable_to_shape_map())
  events = glob.glob(str(tmp_path / 'train' / 'events.out.tfevents.*'))
  logged = {}
  for record in tf.data.TFRecordDataset(events):
    for value in tf.compat.v1.Event.FromString(record.numpy()).summary.value:
      if value.tag.startswith('metrics/'):
        logged[value.tag] = float(tf.make_ndarray(value.tensor))
  assert logged['metrics/loss_scale'] == 2.0 ** 15
  assert 0 < logged['metrics/gradient_norm'] < 100  # Unscaled (scaled: ~1e4).


def test_forty_updates_in_a_row_skipped_by_loss_scaling_stop_the_run():
  session = types.SimpleNamespace(trainer=types.SimpleNamespace(loss_scaled=True),
                                  manager=types.SimpleNamespace(latest_checkpoint='ckpt-7'))
  loop._check_finite(0.5, math.inf, session, 7, skipped=39)  # Overflow: a normal skip.
  with pytest.raises(loop.NonFiniteLossError, match='40 updates skipped in a row'):
    loop._check_finite(0.5, math.inf, session, 7, skipped=40)


def test_init_checkpoint_of_another_kind_of_model_is_refused(tmp_path):
  dense = tf.keras.layers.Dense(3)
  dense.build((None, 2))
  other = tf.train.Checkpoint(model=dense).write(str(tmp_path / 'other' / 'ckpt-1'))
  with pytest.raises(ValueError, match=r'ckpt-1: lacks weights of this MixStereoNet'):
    _train(tmp_path / 'run', 1, init_checkpoint=other)
  assert not os.path.exists(tmp_path / 'run' / 'checkpoint')
