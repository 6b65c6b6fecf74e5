"""Tests of the learned echo stage of double images: its cost volume and its route."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import diplopia_cepstrum
from mixstereo_tf.classical import diplopia_costs
from mixstereo_tf.classical import sgm
from mixstereo_tf.core import hints
from mixstereo_tf.models import matching_features
from mixstereo_tf.unmixing import learned_diplopia

_H, _W, _D = 6, 40, 5


def _column_echo(mixture):
  """A stand-in for trained features: here(x) = one-hot of x, there(x) = one-hot of x + _D,
  so here(x) . there(x - d) = 1 exactly at the lag d = _D."""
  width = mixture.shape[2]
  here = tf.one_hot(tf.range(width), width + _D)[None, None]
  there = tf.one_hot(tf.range(width) + _D, width + _D)[None, None]
  height = tf.shape(mixture)[1]
  return tf.tile(here, [1, height, 1, 1]), tf.tile(there, [1, height, 1, 1])


def _config(low=1, high=12):
  return diplopia.DiplopiaConfig(matching=sgm.SgmConfig(min_disparity=low, max_disparity=high,
                                                         p1=8, p2=64))


def test_learned_costs_are_zero_at_the_echo_and_blend_with_zncc():
  mixture = np.random.default_rng(0).uniform(0, 1, (_H, _W, 3)).astype(np.float32)
  learned = learned_diplopia.echo_costs(_column_echo, learned_diplopia.EchoConfig(
      zncc_weight=0.0))(mixture, _config())
  assert learned.shape == (_H, _W, 12) and learned.dtype == np.uint8
  inside = np.arange(_W) >= 12  # x - d inside the image for every lag.
  assert (learned[:, inside, _D - 1] == 0).all()  # Lag d_i = 1 + i.
  assert (np.delete(learned[:, inside], _D - 1, axis=2) == 32).all()  # 1 - 0 cosine.
  blended = learned_diplopia.echo_costs(_column_echo)(mixture, _config())
  zncc = diplopia_costs.zncc_costs(mixture, _config())
  np.testing.assert_allclose(blended, np.rint(0.5 * zncc + 0.5 * learned), atol=1)


def test_the_stage_finds_the_lag_its_costs_say_and_reports_the_weight():
  rng = np.random.default_rng(1)
  image = (rng.uniform(0, 255, (_H, _W, 3))).astype(np.uint8)
  config = learned_diplopia.EchoConfig(zncc_weight=0.0)
  out = learned_diplopia.learned_unmix(_column_echo, image, 'diplopia', (1, 12), None, config)
  assert np.median(out['disparity_left'][:, _D + 2:]) == pytest.approx(_D)
  assert out['left'].shape == image.shape and out['info'] == {'mixing_weight': 0.5}


def test_a_video_frames_prior_reaches_the_self_matching(monkeypatch):
  seen = {}
  def spy(image, search, **kwargs):
    del image, search
    seen.update(kwargs)
    return dict(dict.fromkeys(('left', 'right', 'disparity_left', 'disparity_right')),
                mixing_weight=0.5)
  monkeypatch.setattr(diplopia, 'unmix_diplopia', spy)
  prior = np.full((_H, _W), 9.0, np.float32)
  learned_diplopia.learned_unmix(_column_echo, np.zeros((_H, _W, 3), np.uint8), 'diplopia',
                                 (1, 12), hints.FrameHint(prior=prior, prior_window=(0, 1)))
  assert seen['prior'] is prior and seen['prior_window'] == (0, 1)


def test_a_trained_kind_runs_end_to_end():
  model = matching_features.build_echo_features(matching_features.FeatureConfig(4, 2))
  echo = learned_diplopia.echo_function(model)
  image = np.random.default_rng(2).integers(0, 256, (16, 32, 3), dtype=np.uint8)
  out = learned_diplopia.learned_unmix(echo, image, 'diplopia', (1, 8))
  assert out['disparity_left'].shape == (16, 32) and 1 <= out['disparity_left'].min()


def test_bad_configs_are_refused():
  for bad in (dict(cost_scale=0.0), dict(zncc_weight=1.0)):
    with pytest.raises(ValueError, match='EchoConfig'):
      learned_diplopia.EchoConfig(**bad)


def test_the_stage_aggregates_with_its_own_penalties_not_the_classical_ones():
  rng = np.random.default_rng(3)
  image = rng.integers(0, 256, (24, 48, 3), dtype=np.uint8)
  config = learned_diplopia.EchoConfig(zncc_weight=0.5, penalties=(8, 64))
  out = learned_diplopia.learned_unmix(_column_echo, image, 'diplopia', (1, 12), None, config)
  costs = learned_diplopia.echo_costs(_column_echo, config)
  for p1, p2, same in ((8, 64, True), (diplopia.DiplopiaConfig().matching.p1,
                                        diplopia.DiplopiaConfig().matching.p2, False)):
    classical = diplopia.DiplopiaConfig()
    run = diplopia.DiplopiaConfig(matching=sgm.SgmConfig(
        min_disparity=1, max_disparity=classical.matching.max_disparity, p1=p1, p2=p2),
        cepstrum=diplopia_cepstrum.CepstrumConfig(weight=0))  # The stage runs without it.
    reference = diplopia.unmix_diplopia(image, (1, 12), run, costs=costs)
    assert np.array_equal(out['disparity_left'], reference['disparity_left']) == same
