"""Tests for mixstereo_tf.training.resumable: the step loop of the stage trainers."""

import logging

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
