"""Tests for mixstereo_tf.training.resumable: the step loop of the stage trainers."""

import logging
import os
import signal

import pytest
import tensorflow as tf

from mixstereo_tf.training import resumable


def _run(tmp_path, step, num_steps):
  calls = []
  counter = tf.Variable(step, dtype=tf.int64)
  manager = tf.train.CheckpointManager(tf.train.Checkpoint(step=counter), str(tmp_path), 2)

  def one_step():
    calls.append(int(counter))
    counter.assign_add(1)
    return [0.0]

  resumable.run_steps(one_step, counter, num_steps, manager, 10, 10, 'loss %.1f')
  return calls


def test_steps_run_up_to_num_steps_and_a_finished_run_says_so(tmp_path, caplog):
  assert _run(tmp_path / 'a', 2, 5) == [2, 3, 4]
  with caplog.at_level(logging.WARNING):
    assert not _run(tmp_path / 'b', 5, 5)
  assert 'at step 5 already, not below --num_steps=5' in caplog.text


def test_a_signal_saves_the_step_and_raises_interrupted(tmp_path):
  counter = tf.Variable(0, dtype=tf.int64)
  manager = tf.train.CheckpointManager(tf.train.Checkpoint(step=counter), str(tmp_path), 2)
  before = signal.getsignal(signal.SIGINT)

  def one_step():
    counter.assign_add(1)
    if int(counter) == 3:
      os.kill(os.getpid(), signal.SIGINT)
    return [0.0]

  with pytest.raises(resumable.Interrupted, match=r'SIGINT at step 3; checkpoint .*ckpt-3') as e:
    resumable.run_steps(one_step, counter, 100, manager, 10, 10, 'loss %.1f')
  assert e.value.exit_code == 130 and manager.latest_checkpoint.endswith('ckpt-3')
  assert signal.getsignal(signal.SIGINT) == before  # Restored.
