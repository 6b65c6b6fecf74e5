"""Known-answer tests of the objective and its configuration."""

import dataclasses

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.training import objective

_H, _W, _D = 8, 16, 3


def _stereo_pair(seed=0):
  """A true pair related by a constant disparity _D that warping reproduces exactly.

  left(x) = T[x], right(x) = T[x + _D]; T is constant over its first 2 _D + 1 and last
  _D + 1 columns, so edge replication at the borders returns the correct values too.
  """
  rng = np.random.default_rng(seed)
  texture = rng.uniform(-1, 1, (2, _H, _W + _D, 3)).astype(np.float32)
  texture[:, :, :2 * _D + 1] = texture[:, :, :1]
  texture[:, :, -(_D + 1):] = texture[:, :, -1:]
  return tf.constant(texture[:, :, :_W]), tf.constant(texture[:, :, _D:])


def _disparity(value):
  return tf.fill([2, _H, _W, 1], float(value))


def test_defaults_are_the_papers():
  config = objective.LossConfig()
  assert (config.alpha_c, config.alpha_p, config.omega_w, config.omega_s,
          config.lambda_ssim, config.lambda_l1) == (1.0, 0.2, 1.0, 0.05, 0.85, 0.15)
  assert config.smoothness_scale == 'width'


@pytest.mark.parametrize('field, value', [
    ('alpha_c', -1.0), ('alpha_p', float('nan')), ('omega_w', float('inf')),
    ('omega_s', '0.05'), ('lambda_ssim', -0.1), ('lambda_l1', None),
    ('smoothness_scale', 'metres'),
])
def test_bad_config_raises(field, value):
  with pytest.raises(ValueError, match=field):
    objective.LossConfig(**{field: value})


def test_separation_losses_of_perfect_predictions():
  left, right = _stereo_pair()
  config = objective.LossConfig()
  out = objective.separation_losses({'left': left, 'right': right},
                                    {'left': left, 'right': right}, config)
  assert float(out['separation/content_left']) == 0.0
  assert float(out['separation/content_right']) == 0.0
  tv_left = float(out['separation/tv_left'])
  unit = (left.numpy() + 1) / 2  # TV on the [0, 1] scale.
  dx, dy = np.diff(unit, axis=2), np.diff(unit, axis=1)
  np.testing.assert_allclose(tv_left, np.abs(dx).mean() + np.abs(dy).mean(), rtol=1e-5)
  np.testing.assert_allclose(float(out['separation/total']),
                             0.2 * (tv_left + float(out['separation/tv_right'])), rtol=1e-6)


def test_separation_content_is_weighted_l1_on_the_unit_scale():
  left, right = _stereo_pair()
  config = objective.LossConfig(alpha_c=2.0, alpha_p=0.0)
  out = objective.separation_losses({'left': left + 0.25, 'right': right - 0.5},
                                    {'left': left, 'right': right}, config)
  # Offsets of 0.25 and 0.5 on [-1, 1] are 0.125 and 0.25 on [0, 1].
  np.testing.assert_allclose(float(out['separation/content_left']), 0.125, rtol=1e-5)
  np.testing.assert_allclose(float(out['separation/content_right']), 0.25, rtol=1e-5)
  np.testing.assert_allclose(float(out['separation/total']), 2.0 * 0.375, rtol=1e-5)


def test_every_term_sees_the_unit_scale():
  """One convention: a view error of e on [-1, 1] is e / 2 in L_C and in L_D alike."""
  shape = (1, 6, 8, 3)
  truth = tf.fill(shape, -0.2)  # 0.4 on [0, 1].
  off = tf.fill(shape, 0.2)  # 0.6 on [0, 1]: 0.2 above the truth on the unit scale.
  config = objective.LossConfig(alpha_c=1.0, alpha_p=0.0, lambda_ssim=0.0, lambda_l1=1.0,
                                omega_s=0.0)
  separation = objective.separation_losses({'left': off, 'right': truth},
                                           {'left': truth, 'right': truth}, config)
  np.testing.assert_allclose(float(separation['separation/content_left']), 0.2, rtol=1e-5)
  # Appearance: the left view vs the right one warped by d = 0, two constant images.
  zero = tf.zeros(shape[:3] + (1,))
  stereo = objective.stereo_losses(zero, zero, truth, off, config)
  np.testing.assert_allclose(float(stereo['stereo/appearance_left']), 0.2, rtol=1e-5)
  # TV: a vertical step of 1 on [-1, 1] (0.5 on [0, 1]) in one of three channels, 6 rows.
  step = np.zeros(shape, np.float32)
  step[:, 3:, :, 0] = 1.0
  tv = objective.separation_losses({'left': tf.constant(step), 'right': truth},
                                   {'left': truth, 'right': truth}, config)
  np.testing.assert_allclose(float(tv['separation/tv_left']), 0.5 / 5 / 3, rtol=1e-5)
  # Edge-aware weights: the same step as exp(-0.5 / 3) on the v gradient of the disparity.
  ramp = tf.reshape(tf.range(6, dtype=tf.float32), [1, 6, 1, 1]) * tf.ones([1, 1, 8, 1])
  pixels = objective.LossConfig(omega_s=1.0, smoothness_scale='pixels')
  smooth = objective.stereo_losses(ramp, ramp, tf.constant(step), tf.constant(step), pixels)
  expected = (4 + np.exp(-0.5 / 3)) / 5  # |dv d| = 1 on 5 rows, one of them at the edge.
  np.testing.assert_allclose(float(smooth['stereo/smoothness_left']), expected, rtol=1e-5)


def test_monocular_separation_counts_only_the_right_view():
  left, right = _stereo_pair()
  out = objective.total_loss({'left': left, 'right': right + 0.5}, {'left': left, 'right': right},
                             objective.LossConfig(), 'separation_only',
                             separated_views=('right',))
  assert 'separation/content_left' not in out and 'separation/tv_left' not in out
  np.testing.assert_allclose(float(out['separation/content_right']), 0.25, rtol=1e-5)


def test_stereo_losses_vanish_for_the_true_disparity():
  left, right = _stereo_pair()
  out = objective.stereo_losses(_disparity(_D), _disparity(_D), left, right,
                                objective.LossConfig())
  for key in ('appearance_left', 'appearance_right', 'smoothness_left', 'smoothness_right',
              'total'):
    assert abs(float(out[f'stereo/{key}'])) < 1e-6, key


def test_stereo_losses_penalise_a_wrong_disparity_and_sum_with_weights():
  left, right = _stereo_pair()
  ramp = tf.reshape(tf.range(_W, dtype=tf.float32) / _W, [1, 1, _W, 1])
  disparity = _disparity(_D - 1) + ramp
  config = objective.LossConfig(omega_w=2.0, omega_s=3.0)
  out = objective.stereo_losses(disparity, disparity, left, right, config)
  assert float(out['stereo/appearance_left']) > 0.05
  assert float(out['stereo/appearance_right']) > 0.05
  expected = (2.0 * (out['stereo/appearance_left'] + out['stereo/appearance_right']) +
              3.0 * (out['stereo/smoothness_left'] + out['stereo/smoothness_right']))
  np.testing.assert_allclose(float(out['stereo/total']), float(expected), rtol=1e-6)


def test_smoothness_scale_width_divides_by_width():
  left, right = _stereo_pair()
  ramp = tf.reshape(tf.range(_W, dtype=tf.float32), [1, 1, _W, 1]) * tf.ones([2, _H, 1, 1])
  pixels = objective.stereo_losses(ramp, ramp, left, right,
                                   objective.LossConfig(smoothness_scale='pixels'))
  width = objective.stereo_losses(ramp, ramp, left, right, objective.LossConfig())
  for view in ('left', 'right'):
    key = f'stereo/smoothness_{view}'
    assert float(pixels[key]) > 0.1
    np.testing.assert_allclose(float(pixels[key]), _W * float(width[key]), rtol=1e-5)


def _outputs(left, right):
  return {'left': left, 'right': right, 'disparity_left': _disparity(_D),
          'disparity_right': _disparity(_D)}


def test_total_loss_modes():
  left, right = _stereo_pair()
  batch = {'left': left, 'right': right}
  config = objective.LossConfig()
  outputs = _outputs(left + 0.1, right)
  joint = objective.total_loss(outputs, batch, config, 'joint')
  np.testing.assert_allclose(float(joint['loss']),
                             float(joint['separation/total'] + joint['stereo/total']))
  np.testing.assert_allclose(float(joint['separation/content_left']), 0.05, rtol=1e-5)
  assert float(joint['separation/content_right']) == 0.0

  separation = objective.total_loss({'left': left + 0.1, 'right': right}, batch, config,
                                    'separation_only')
  assert not any(k.startswith('stereo/') for k in separation)
  np.testing.assert_allclose(float(separation['loss']), float(joint['separation/total']))

  stereo = objective.total_loss({'disparity_left': _disparity(_D - 2),
                                 'disparity_right': _disparity(_D - 2)}, batch, config,
                                'stereo_only')
  assert not any(k.startswith('separation/') for k in stereo)
  assert float(stereo['loss']) > 0.05
  np.testing.assert_allclose(float(stereo['loss']), float(stereo['stereo/total']))


def test_total_loss_bad_mode_and_missing_keys_raise():
  left, right = _stereo_pair()
  batch = {'left': left, 'right': right}
  with pytest.raises(ValueError, match='joint'):
    objective.total_loss(_outputs(left, right), batch, objective.LossConfig(), 'both')
  with pytest.raises(ValueError, match='disparity_left'):
    objective.total_loss({'left': left, 'right': right}, batch, objective.LossConfig(),
                         'joint')


def test_total_loss_compiles_with_xla():
  left, right = _stereo_pair()
  batch = {'left': left, 'right': right}
  outputs = _outputs(left * 0.9, right + 0.05)
  outputs['disparity_left'] += tf.reshape(tf.range(_W, dtype=tf.float32) / 7, [1, 1, _W, 1])
  config = dataclasses.replace(objective.LossConfig(), omega_s=1.0)
  compiled = tf.function(lambda o, b: objective.total_loss(o, b, config, 'joint'),
                         jit_compile=True)
  got, want = compiled(outputs, batch), objective.total_loss(outputs, batch, config, 'joint')
  assert set(got) == set(want)
  for key in want:
    np.testing.assert_allclose(float(got[key]), float(want[key]), rtol=1e-5, atol=1e-7)
  assert float(want['loss']) > 0.0
