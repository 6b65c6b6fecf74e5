"""Tests of the custom train step: what each mode trains, XLA, device-dependent auto."""

import dataclasses

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf import models
from mixstereo_tf.training import objective
from mixstereo_tf.training import step as step_lib
from tests import training_helpers

TRAINED = {'joint': ('separation', 'stereo'), 'separation_only': ('separation',),
           'stereo_only': ('stereo',)}


def _one_step(mode, jit_compile=False):
  tf.keras.utils.set_random_seed(0)
  model = models.build_model(training_helpers.MINI)
  optimizer = tf.keras.optimizers.RMSprop(1e-3)
  trainer = step_lib.TrainStep(model, optimizer, objective.LossConfig(), mode,
                               tf.distribute.get_strategy(), jit_compile)
  before = {m: [v.numpy().copy() for v in getattr(model, m).trainable_variables]
            for m in ('separation', 'stereo')}
  scalars, _ = trainer(training_helpers.stereo_batch(height=16, width=32, shift=2))
  return model, before, scalars


@pytest.mark.parametrize('mode', sorted(TRAINED))
def test_step_changes_exactly_the_trained_modules(mode):
  model, before, scalars = _one_step(mode)
  assert np.isfinite(float(scalars['loss']))
  for module, values in before.items():
    variables = getattr(model, module).trainable_variables
    changed = [not np.array_equal(v.numpy(), old) for v, old in zip(variables, values)]
    if module in TRAINED[mode]:
      unchanged = [v.name for v, c in zip(variables, changed) if not c]
      assert not unchanged, f'{mode}: {module} variables not updated: {unchanged}'
    else:
      assert not any(changed), f'{mode} must leave {module} unchanged'


def test_step_compiles_with_xla_and_matches_the_eager_graph():
  _, _, eager = _one_step('joint', jit_compile=False)
  _, _, compiled = _one_step('joint', jit_compile=True)
  for key in ('loss', 'separation/total', 'stereo/total'):
    np.testing.assert_allclose(float(compiled[key]), float(eager[key]), rtol=1e-3)


def test_xla_step_accepts_a_pipeline_batch_with_its_string_name():
  # Pipeline batches carry `name` (tf.string), which XLA cannot take as an argument.
  model = models.build_model(training_helpers.MINI)
  trainer = step_lib.TrainStep(model, tf.keras.optimizers.RMSprop(1e-3),
                               objective.LossConfig(), 'joint', tf.distribute.get_strategy(),
                               jit_compile=True)
  batch = dict(training_helpers.stereo_batch(height=16, width=32, shift=2),
               name=tf.constant(['scene_0']))
  scalars, _ = trainer(batch)
  assert np.isfinite(float(scalars['loss']))


def test_step_reports_every_loss_term_psnr_and_the_gradient_norm():
  _, _, scalars = _one_step('joint')
  for key in ('loss', 'separation/total', 'stereo/total', 'metrics/psnr_left',
              'metrics/psnr_right'):
    assert key in scalars
  assert 0 < float(scalars['metrics/gradient_norm']) < np.inf


def test_monocular_step_separates_only_the_right_view():
  config = dataclasses.replace(training_helpers.MINI, input_is_left=True)
  model = models.build_model(config)
  trainer = step_lib.TrainStep(model, tf.keras.optimizers.RMSprop(1e-3),
                               objective.LossConfig(), 'joint', tf.distribute.get_strategy(),
                               jit_compile=False)
  batch = training_helpers.stereo_batch(height=16, width=32, shift=2, mixture='monocular')
  scalars, outputs = trainer(batch)
  assert 'separation/content_right' in scalars and 'separation/content_left' not in scalars
  np.testing.assert_array_equal(outputs['left'].numpy(), batch['mixture'].numpy())


@pytest.mark.parametrize('setting, device, expected', [
    ('auto', 'CPU', False), ('auto', 'GPU', True), ('true', 'CPU', True),
    ('false', 'GPU', False)])
def test_resolve_jit_compile(setting, device, expected):
  assert step_lib.resolve_jit_compile(setting, device) is expected


def test_resolve_jit_compile_rejects_unknown_values():
  with pytest.raises(ValueError, match='jit_compile'):
    step_lib.resolve_jit_compile('yes', 'CPU')


@pytest.mark.parametrize('mixed, device, expected', [
    (False, 'GPU', 'float32'), (True, 'GPU', 'mixed_float16'), (True, 'gpu', 'mixed_float16'),
    (True, 'CPU', 'mixed_bfloat16'), (False, 'CPU', 'float32')])
def test_precision_policy(mixed, device, expected):
  assert step_lib.precision_policy(mixed, device) == expected


def _gradients_under(policy, weights=None):
  """(weights, scalars, unscaled gradients) of one batch under a dtype policy."""
  tf.keras.mixed_precision.set_global_policy(policy)
  try:
    model = models.build_model(training_helpers.MINI)
    if weights is not None:
      model.set_weights(weights)
    optimizer = tf.keras.optimizers.RMSprop(1e-3)
    if policy == 'mixed_float16':  # What the loop does on a GPU.
      optimizer = tf.keras.mixed_precision.LossScaleOptimizer(optimizer)
    trainer = step_lib.TrainStep(model, optimizer, objective.LossConfig(), 'joint',
                                 tf.distribute.get_strategy(), jit_compile=False)
    optimizer.build(trainer.variables)
    scalars, _, gradients = trainer._gradients(training_helpers.stereo_batch())
    scale = float(scalars.get('metrics/loss_scale', 1.0))
    return (model.get_weights(), {k: float(v) for k, v in scalars.items()},
            np.concatenate([g.numpy().ravel() / scale for g in gradients]))
  finally:
    tf.keras.mixed_precision.set_global_policy('float32')


def test_mixed_float16_step_is_finite_and_its_unscaled_gradients_match_float32():
  weights, full, reference = _gradients_under('float32')
  _, mixed, gradients = _gradients_under('mixed_float16', weights)
  assert mixed['metrics/loss_scale'] == 2.0 ** 15  # Keras' initial dynamic scale.
  assert all(np.isfinite(v) for v in mixed.values()) and np.all(np.isfinite(gradients))
  for key in ('loss', 'separation/total', 'stereo/total', 'stereo/smoothness_left'):
    np.testing.assert_allclose(mixed[key], full[key], rtol=1e-3)
  # The logged norm is unscaled: float32's within float16 rounding, not 32768 times it.
  np.testing.assert_allclose(mixed['metrics/gradient_norm'], full['metrics/gradient_norm'],
                             rtol=0.02)
  cosine = gradients @ reference / np.linalg.norm(gradients) / np.linalg.norm(reference)
  assert cosine > 0.995
  assert np.linalg.norm(gradients - reference) < 0.1 * np.linalg.norm(reference)
