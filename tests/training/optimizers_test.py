"""Tests for mixstereo_tf.training.optimizers: TF1 RMSProp against its update written out."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.training import optimizers


def _tf1_reference(value, gradients, lr, rho=0.9, epsilon=1e-10):
  """TF1's ApplyRMSProp with momentum 0, accumulator started at one, in float64."""
  value, mean_square = np.array(value, np.float64), np.ones_like(value, np.float64)
  for gradient in gradients:
    mean_square = rho * mean_square + (1 - rho) * gradient**2
    value = value - lr * gradient / np.sqrt(mean_square + epsilon)
  return value


def test_tf1_rmsprop_follows_the_tf1_update_formula():
  rng = np.random.default_rng(0)
  start = rng.normal(size=(3, 4)).astype(np.float32)
  # Gradients from tiny (below Keras' epsilon floor) to large, five steps.
  gradients = [rng.normal(size=(3, 4)) * scale for scale in (1e-6, 1e-4, 1e-2, 1.0, 10.0)]
  variable = tf.Variable(start)
  optimizer = optimizers.make_optimizer('rmsprop_tf1', 1e-3)
  for gradient in gradients:
    optimizer.apply_gradients([(tf.constant(gradient, tf.float32), variable)])
  np.testing.assert_allclose(variable.numpy(), _tf1_reference(start, gradients, 1e-3),
                             rtol=1e-6, atol=1e-7)


def test_tiny_gradients_move_tf1_little_and_keras_a_whole_step():
  gradient = np.full((2,), 1e-6)
  moves = {}
  for name in optimizers.OPTIMIZERS:
    variable = tf.Variable(np.zeros(2, np.float32))
    optimizers.make_optimizer(name, 1e-3).apply_gradients(
        [(tf.constant(gradient, tf.float32), variable)])
    moves[name] = float(abs(variable.numpy()[0]))
  # TF1: lr g / sqrt(0.9): about 1e-9. Keras: lr g / sqrt(0.1 g^2 + 1e-7), about 3e-6.
  assert moves['rmsprop_tf1'] == pytest.approx(1e-3 * 1e-6 / np.sqrt(0.9), rel=1e-3)
  assert moves['rmsprop_keras'] > 1000 * moves['rmsprop_tf1']


def test_unknown_optimizer_is_named():
  with pytest.raises(ValueError, match='TrainConfig.optimizer'):
    optimizers.make_optimizer('adam', 1e-3)


def test_the_accumulator_is_checkpointed(tmp_path):
  variable = tf.Variable(np.ones(3, np.float32))
  optimizer = optimizers.make_optimizer('rmsprop_tf1', 1e-2)
  optimizer.apply_gradients([(tf.constant([1.0, 2.0, 3.0]), variable)])
  path = tf.train.Checkpoint(optimizer=optimizer, v=variable).write(str(tmp_path / 'c'))
  restored_variable = tf.Variable(np.zeros(3, np.float32))
  restored = optimizers.make_optimizer('rmsprop_tf1', 1e-2)
  restored.build([restored_variable])
  tf.train.Checkpoint(optimizer=restored, v=restored_variable).read(path).assert_consumed()
  for step in (optimizer, restored):
    step.apply_gradients([(tf.constant([0.5, 0.5, 0.5]), variable if step is optimizer
                           else restored_variable)])
  np.testing.assert_allclose(restored_variable.numpy(), variable.numpy(), rtol=1e-6)
