"""Tests of the matching-feature training: batches, real pairs, resuming, fine-tuning."""

import os

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.data import photo_warps
from mixstereo_tf.data import real_pairs
from mixstereo_tf.models import matching_features
from mixstereo_tf.training import feature_loop


def test_batches_are_deterministic_and_shaped(tmp_path):
  config = feature_loop.FeatureTrainConfig(model_dir=str(tmp_path), batch_size=2)
  warp = photo_warps.WarpConfig(height=32, width=64, max_disparity=16)
  atlas = feature_loop.textures(config)
  a = feature_loop.draw_batch(config, warp, atlas, 5)
  b = feature_loop.draw_batch(config, warp, atlas, 5)
  assert a['single'].shape == (2, 32, 64, 1) and a['pair'].shape == (2, 32, 64, 2)
  assert a['disparity'].shape == (2, 32, 64) and a['valid'].dtype == bool
  for key in a:
    np.testing.assert_array_equal(a[key], b[key])


def test_training_resumes_and_exports(tmp_path):
  warp = photo_warps.WarpConfig(height=32, width=64, max_disparity=16)
  features = matching_features.FeatureConfig(width=4, layers=2)
  config = feature_loop.FeatureTrainConfig(model_dir=str(tmp_path / 'run'), batch_size=1,
                                           num_steps=2, min_disparity=-8, num_disparities=24,
                                           checkpoint_every=1, log_every=1)
  assert feature_loop.train(config, warp, features).endswith('ckpt-2')
  config = feature_loop.FeatureTrainConfig(**dict(vars(config), num_steps=3))
  assert feature_loop.train(config, warp, features).endswith('ckpt-3')
  entry = pretrained.from_run(str(tmp_path / 'run'), str(tmp_path / 'shipped'), 'recipe', 'r')
  assert entry.kind == 'features' and entry.mixtures[0] == 'anaglyph'
  assert pretrained.load_model(entry).count_params() > 0
  assert os.path.exists(tmp_path / 'shipped' / 'weights.npz')


@pytest.mark.parametrize('field, value', [('mixtures', 'diplopia,anaglyph'),
                                          ('mixtures', 'monocular'), ('num_steps', 0),
                                          ('logit_scale', 0.0), ('weight_range', (0.5, 1.0))])
def test_bad_config_is_refused(field, value):
  with pytest.raises(ValueError, match=field if field != 'mixtures' else 'anaglyph'):
    feature_loop.FeatureTrainConfig(model_dir='x', **{field: value})


def test_double_image_batches_mix_with_a_weight_and_keep_disparities_positive(tmp_path):
  config = feature_loop.FeatureTrainConfig(model_dir=str(tmp_path), mixtures='diplopia',
                                           batch_size=2, degrade_probability=0.0,
                                           weight_range=(0.3, 0.3))
  assert feature_loop.kind_name(config) == 'echo_features'
  assert feature_loop.candidates(16, 'diplopia') == (1, 15)
  assert feature_loop.window_probability('diplopia') == 0.0
  warp = photo_warps.WarpConfig(height=32, width=64, max_disparity=16, window_probability=0.0)
  batch = feature_loop.draw_batch(config, warp, feature_loop.textures(config), 3)
  assert set(batch) == {'mixture', 'disparity', 'valid'}
  assert batch['mixture'].shape == (2, 32, 64, 3) and batch['disparity'].min() >= 1.0


def test_echo_features_train_and_export_as_their_own_kind(tmp_path):
  warp = photo_warps.WarpConfig(height=32, width=64, max_disparity=16, window_probability=0.0)
  config = feature_loop.FeatureTrainConfig(model_dir=str(tmp_path / 'run'), mixtures='diplopia',
                                           batch_size=1, num_steps=1, min_disparity=1,
                                           num_disparities=15, checkpoint_every=1, log_every=1)
  feature_loop.train(config, warp, matching_features.FeatureConfig(width=4, layers=2))
  entry = pretrained.from_run(str(tmp_path / 'run'), str(tmp_path / 'shipped'), 'recipe', 'r')
  assert entry.kind == 'echo_features' and entry.mixtures == ('diplopia',)
  here, there = pretrained.load_model(entry)(tf.zeros([1, 8, 8, 3]))
  assert here.shape == there.shape == (1, 8, 8, 4)


def test_real_pairs_replace_warps_at_their_rate_and_leave_warp_batches_as_they_were(tmp_path):
  warp = photo_warps.WarpConfig(height=32, width=64, max_disparity=16)
  plain = feature_loop.FeatureTrainConfig(model_dir=str(tmp_path), batch_size=2)
  atlas = feature_loop.textures(plain)
  motorcycle = real_pairs.load('motorcycle')
  # Off (the default), the draws are those of a run without the option.
  off = feature_loop.FeatureTrainConfig(model_dir=str(tmp_path), batch_size=2,
                                        real_pairs=('motorcycle',), real_probability=0.0)
  before, after = (feature_loop.draw_batch(c, warp, atlas, 4, [motorcycle]) for c in (plain, off))
  for key in before:
    np.testing.assert_array_equal(before[key], after[key])
  only = feature_loop.FeatureTrainConfig(model_dir=str(tmp_path), batch_size=2,
                                         real_pairs=('motorcycle',), real_probability=1.0)
  batch = feature_loop.draw_batch(only, warp, atlas, 4, [motorcycle])
  # Motorcycle scaled by at most 0.8 * 16 / 58: its disparities stay under 13 px.
  assert batch['valid'].any() and batch['disparity'][batch['valid']].max() < 13.0
  with pytest.raises(ValueError, match='real_pairs'):
    feature_loop.FeatureTrainConfig(model_dir='x', real_probability=0.5)
  with pytest.raises(ValueError, match='real_probability'):
    feature_loop.FeatureTrainConfig(model_dir='x', real_pairs=('motorcycle',),
                                    real_probability=1.5)


def test_a_run_can_start_from_the_shipped_features(tmp_path):
  entry = pretrained.get('anaglyph_matching')
  model = matching_features.build_features(matching_features.FeatureConfig(**entry.config))
  feature_loop.start_from(model, 'anaglyph_matching', 'features')
  shipped = pretrained.load_model(entry).get_weights()
  for mine, theirs in zip(model.get_weights(), shipped):
    np.testing.assert_array_equal(mine, theirs)
  with pytest.raises(ValueError, match='--init_from=anaglyph_matching.*architecture'):
    feature_loop.start_from(matching_features.build_features(
        matching_features.FeatureConfig(width=4, layers=2)), 'anaglyph_matching', 'features')
  with pytest.raises(ValueError, match="'features' model; this run trains 'echo_features'"):
    feature_loop.start_from(model, 'anaglyph_matching', 'echo_features')
