"""Architecture tests: the paper's parameter budget, shapes, configs, gradient paths."""

import dataclasses
import os
import subprocess
import sys

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf import models
from mixstereo_tf.models import summary
from mixstereo_tf.training import objective

TINY = models.ModelConfig(separation_widths=(4, 4, 8, 8, 8, 8), stereo_features=4,
                          stereo_residual_blocks=1, stereo_3d_widths=(4, 4, 4, 8),
                          max_disparity=32)


def _mixture(height=32, width=64, seed=0):
  return tf.random.stateless_uniform([1, height, width, 3], [seed, 1], -1.0, 1.0)


def test_default_model_has_the_papers_parameter_count():
  model = models.build_model()
  total = summary.count(model.trainable_variables)
  assert abs(total - 17.1e6) <= 0.01 * 17.1e6, total
  # The 32-64-128-256-512-512 U-Net, counted by hand (weights + biases).
  assert summary.count(model.separation.trainable_variables) == 14_313_862
  assert model.separation.num_conv_layers == 22  # Paper: "22 convolutional layers".


def test_parameter_table_ends_with_the_total():
  table = summary.parameter_table(TINY)
  model = models.build_model(TINY)
  assert table.splitlines()[-1] == (
      f'total trainable parameters: {summary.count(model.trainable_variables)}')


def test_models_module_prints_the_default_configuration_total():
  # `python -m mixstereo_tf.models` builds the paper configuration (a subprocess keeps
  # its 17M parameters out of this process).
  env = dict(os.environ, TF_CPP_MIN_LOG_LEVEL='2', CUDA_VISIBLE_DEVICES='')
  done = subprocess.run([sys.executable, '-m', 'mixstereo_tf.models'], capture_output=True,
                        text=True, timeout=300, env=env, check=True)
  last = done.stdout.strip().splitlines()[-1]
  total = int(last.removeprefix('total trainable parameters: '))
  assert abs(total - 17.1e6) <= 0.01 * 17.1e6, last
  assert 'stereo (total)' in done.stdout and 'separation (total)' in done.stdout


def test_joint_outputs_shapes_and_ranges():
  model = models.build_model(TINY)
  outputs = model(_mixture(), training=False)
  assert sorted(outputs) == ['disparity_left', 'disparity_right', 'left', 'right']
  assert outputs['left'].shape == (1, 32, 64, 3)
  assert outputs['disparity_right'].shape == (1, 32, 64, 1)
  for key in ('left', 'right'):
    assert np.abs(outputs[key].numpy()).max() <= 1.0  # tanh output.
  for key in ('disparity_left', 'disparity_right'):
    values = outputs[key].numpy()
    assert values.min() >= 0.0 and values.max() <= TINY.max_disparity - 1


def test_monocular_model_passes_the_input_through_as_the_left_view():
  """Paper 3.1: for monocular depth "the left image has been provided as input"."""
  model = models.build_model(dataclasses.replace(TINY, input_is_left=True))
  mixture = _mixture(seed=3)
  outputs = model(mixture, training=False)
  np.testing.assert_array_equal(outputs['left'].numpy(), mixture.numpy())
  # The stereo module sees the input and the separated right view.
  separated = model.separate(mixture)
  direct = model.compute_disparity(mixture, separated['right'])
  np.testing.assert_allclose(outputs['disparity_left'].numpy(),
                             direct['disparity_left'].numpy(), atol=1e-5)
  np.testing.assert_array_equal(outputs['right'].numpy(), separated['right'].numpy())
  assert not np.allclose(separated['left'].numpy(), mixture.numpy())


def test_mirrored_pass_swaps_the_disparities():
  model = models.build_model(TINY)
  rng = np.random.default_rng(1)
  left = tf.constant(rng.uniform(-1, 1, (1, 32, 64, 3)), tf.float32)
  right = tf.constant(rng.uniform(-1, 1, (1, 32, 64, 3)), tf.float32)
  direct = model.compute_disparity(left, right)
  mirrored = model.compute_disparity(tf.reverse(right, [2]), tf.reverse(left, [2]))
  np.testing.assert_allclose(mirrored['disparity_left'].numpy(),
                             tf.reverse(direct['disparity_right'], [2]).numpy(), atol=1e-4)
  np.testing.assert_allclose(mirrored['disparity_right'].numpy(),
                             tf.reverse(direct['disparity_left'], [2]).numpy(), atol=1e-4)


def test_conv3d_implementations_give_the_same_model():
  native = models.build_model(dataclasses.replace(TINY, conv3d_implementation='native'))
  dense = models.build_model(dataclasses.replace(TINY, conv3d_implementation='dense'))
  dense.set_weights(native.get_weights())
  expected = native(_mixture())
  for key, value in dense(_mixture()).items():
    np.testing.assert_allclose(value.numpy(), expected[key].numpy(), atol=1e-4)


def test_input_not_a_multiple_of_32_is_a_clear_error():
  model = models.build_model(TINY)
  with pytest.raises(ValueError, match='width 60 is not a multiple of 32'):
    model(tf.zeros([1, 32, 60, 3]))


@pytest.mark.parametrize('kwargs, message', [
    ({'max_disparity': 40}, 'multiple of 32'),
    ({'separation_widths': (8,)}, 'at least 2'),
    ({'stereo_3d_widths': ()}, 'at least one'),
])
def test_config_validation(kwargs, message):
  with pytest.raises(ValueError, match=message):
    models.ModelConfig(**kwargs)


def test_config_dict_round_trip_and_unknown_field():
  assert models.ModelConfig.from_dict(TINY.to_dict()) == TINY
  with pytest.raises(ValueError, match='Unknown ModelConfig fields'):
    models.ModelConfig.from_dict({'width': 3})


@pytest.mark.parametrize('factory, args', [
    (lambda: models.SeparationNet((4, 8, 8)), lambda: (_mixture(32, 32),)),
    (lambda: models.StereoNet(4, 1, (4, 8), 16), lambda: (_mixture(32, 32), _mixture(32, 32, 2))),
    (lambda: models.MixStereoNet(TINY), lambda: (_mixture(),)),
])
def test_keras_models_round_trip_through_get_config(factory, args):
  original = factory()
  inputs = args()
  expected = original(*inputs)
  clone = type(original).from_config(original.get_config())
  clone(*inputs)
  clone.set_weights(original.get_weights())
  assert clone.get_config() == original.get_config()
  for key, value in clone(*inputs).items():
    np.testing.assert_allclose(value.numpy(), expected[key].numpy(), atol=1e-5)


def test_stereo_loss_gradients_reach_the_separation_module():
  model = models.build_model(TINY)
  mixture = _mixture()
  truth = {'left': _mixture(seed=3), 'right': _mixture(seed=4)}
  with tf.GradientTape() as tape:
    outputs = model(mixture, training=True)
    loss = objective.stereo_losses(outputs['disparity_left'], outputs['disparity_right'],
                                   truth['left'], truth['right'],
                                   objective.LossConfig())['stereo/total']
  gradients = tape.gradient(loss, model.separation.trainable_variables)
  assert all(g is not None for g in gradients)
  assert sum(float(tf.reduce_sum(tf.abs(g))) for g in gradients) > 0.0


def test_checkpoint_saves_and_restores_every_variable(tmp_path):
  model = models.build_model(TINY)
  path = tf.train.Checkpoint(model=model).write(str(tmp_path / 'ckpt'))
  stored = [k for k in tf.train.load_checkpoint(path).get_variable_to_shape_map()
            if k.startswith('model/')]
  assert len(stored) == len(model.variables)  # Layers held in lists included.
  clone = models.build_model(TINY)
  tf.train.Checkpoint(model=clone).read(path).assert_consumed()
  for key, value in clone(_mixture()).items():
    np.testing.assert_array_equal(value.numpy(), model(_mixture())[key].numpy())


def test_a_tiny_model_with_the_census_cost_builds_and_runs_on_its_smallest_input():
  config = models.ModelConfig(separation_widths=(4, 4), stereo_features=4,
                              stereo_residual_blocks=1, stereo_3d_widths=(4,), max_disparity=8,
                              census_cost=True)
  # Half-resolution views must hold the 7 x 9 census window: 8 px is too small.
  assert config.size_multiple == 4 and config.smallest_input == 12
  assert dataclasses.replace(config, census_cost=False).smallest_input == 4
  model = models.build_model(config)
  outputs = model(_mixture(12, 24))
  assert outputs['disparity_left'].shape[1:3] == (12, 24)
