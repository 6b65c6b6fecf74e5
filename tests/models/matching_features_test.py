"""Tests of the learned matching features: shapes, unit descriptors, eye channels, config."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.artifacts import runs
from mixstereo_tf.models import layers_util
from mixstereo_tf.models import matching_features


def test_descriptors_are_unit_vectors_of_the_configured_width():
  model = matching_features.build_features(matching_features.FeatureConfig(width=8, layers=2))
  single, pair = model((tf.random.uniform([2, 12, 20, 1]), tf.random.uniform([2, 12, 20, 2])))
  assert single.shape == (2, 12, 20, 8) and pair.shape == (2, 12, 20, 8)
  np.testing.assert_allclose(tf.norm(single, axis=-1), 1.0, atol=1e-5)
  np.testing.assert_allclose(tf.norm(pair, axis=-1), 1.0, atol=1e-5)
  # 2 layers of 3x3 per branch: (1 * 9 + 1) * 8 + (8 * 9 + 1) * 8 and (2 * 9 + 1) * 8 + ...
  assert model.count_params() == (10 * 8 + 73 * 8) + (19 * 8 + 73 * 8)


def test_gain_and_offset_of_a_channel_do_not_change_the_descriptors():
  model = matching_features.build_features(matching_features.FeatureConfig(width=4, layers=2))
  image = tf.random.uniform([1, 16, 16, 1])
  a, _ = model((image, tf.zeros([1, 16, 16, 2])))
  b, _ = model((0.3 * image + 0.5, tf.zeros([1, 16, 16, 2])))
  np.testing.assert_allclose(a, b, atol=1e-4)


def test_config_round_trip_and_checkpoint_holds_every_layer(tmp_path):
  config = matching_features.FeatureConfig(width=4, layers=3)
  model = matching_features.build_features(config)
  clone = matching_features.MatchingFeatures.from_config(model.get_config())
  assert clone.feature_config == config
  prefix = tf.train.Checkpoint(model=model).save(str(tmp_path / 'ckpt'))
  restored = matching_features.build_features(config)
  runs.restore_model_weights(restored, prefix)  # Raises if a layer is missing.
  for x, y in zip(model.weights, restored.weights):
    np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize('name, single, pair, single_is_left', [
    ('anaglyph', [0], [1, 2], True), ('green_magenta', [1], [0, 2], True),
    ('amber_blue', [2], [0, 1], False)])
def test_eye_inputs_split_the_channels_by_eye(name, single, pair, single_is_left):
  mixture = np.arange(3, dtype=np.float32)[None, None] * np.ones((2, 3, 1), np.float32)
  got_single, got_pair, is_left = matching_features.eye_inputs(mixture, name)
  np.testing.assert_array_equal(got_single[0, 0], single)
  np.testing.assert_array_equal(got_pair[0, 0], pair)
  assert is_left == single_is_left


def test_eye_inputs_refuse_a_double_image():
  with pytest.raises(ValueError, match='diplopia'):
    matching_features.eye_inputs(np.zeros((2, 2, 3)), 'diplopia')


def test_bad_config_is_refused():
  with pytest.raises(ValueError, match='width'):
    matching_features.FeatureConfig(width=0)


def _changed_columns(config, column):
  """Columns left of 40 of the single branch's descriptors that change when input
  `column` of row 2 trades its value with column 55 (the image's moments, and so its
  standardisation, stay the same)."""
  model = matching_features.build_features(config)
  image = np.random.default_rng(3).uniform(size=(1, 5, 64, 1)).astype(np.float32)
  image[0, 2, column], image[0, 2, 55] = 0.9, 0.1
  poked = image.copy()
  poked[0, 2, column], poked[0, 2, 55] = 0.1, 0.9
  zeros = tf.zeros([1, 5, 64, 2])
  moved = tf.reduce_max(tf.abs(model((poked, zeros))[0] - model((image, zeros))[0]), [0, 1, 3])
  return np.flatnonzero(moved.numpy()[:40] > 1e-6)


def test_dilations_widen_the_receptive_field_to_its_stated_size():
  plain = matching_features.FeatureConfig(width=8, layers=3)
  dilated = matching_features.FeatureConfig(width=8, layers=3, dilations=[1, 2, 4])
  assert (plain.receptive_field, dilated.receptive_field) == (7, 15)
  np.testing.assert_array_equal(_changed_columns(plain, 20), np.arange(17, 24))
  changed = _changed_columns(dilated, 20)
  assert changed.min() >= 13 and changed.max() <= 27 and {13, 27} <= set(changed)
  clone = matching_features.MatchingFeatures.from_config(
      matching_features.build_features(dilated).get_config())
  assert clone.feature_config.dilations == (1, 2, 4)


def test_dilations_need_one_entry_per_layer():
  with pytest.raises(ValueError, match='dilations'):
    matching_features.FeatureConfig(layers=3, dilations=(1, 2))
  with pytest.raises(ValueError, match='dilations'):
    matching_features.FeatureConfig(layers=2, dilations=(1, 0))


def test_bfloat16_convolutions_give_float32_unit_descriptors_close_to_float32():
  model = matching_features.build_features(matching_features.FeatureConfig(width=8, layers=2))
  rng = np.random.default_rng(1)
  single, pair = (tf.constant(rng.random((1, 12, 20, c)), tf.float32) for c in (1, 2))
  expected = [t.numpy() for t in model((single, pair))]
  layers_util.compute_in_bfloat16(model)
  for got, want in zip(model((single, pair)), expected):
    assert got.dtype == tf.float32
    np.testing.assert_allclose(np.linalg.norm(got, axis=-1), 1.0, atol=1e-5)
    cosine = np.sum(got.numpy() * want, axis=-1)
    assert cosine.min() > 0.999  # 1 - cosine < 1e-3: 0.03 of a cost unit at cost_scale 32.
