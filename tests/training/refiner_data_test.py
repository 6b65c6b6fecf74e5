"""Tests for mixstereo_tf.training.refiner_data: examples with the classical result, shards."""

import dataclasses
import os

import numpy as np
import pytest

from mixstereo_tf.classical import anaglyph
from mixstereo_tf.classical import matcher
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import texture_atlas
from mixstereo_tf.models import refiner
from mixstereo_tf.training import refiner_data
from mixstereo_tf.unmixing import predictors

SMALL = refiner_data.ExampleConfig(mixtures='gray,anaglyph', height=48, width=64,
                                   max_disparity=16, window_probability=1.0, degrade=False)


@pytest.fixture(scope='module')
def textures():
  return refiner_data._textures(SMALL)  # pylint: disable=protected-access


def _assert_undegraded_pair(example):
  """The left view is the right one sampled at x - d (the scene's own convention), and
  the mixture is the encoding of the views."""
  height, width = example['left'].shape[:2]
  rows, cols = np.mgrid[0:height, 0:width]
  source = np.round(cols - example['disparity_left']).astype(int)
  inside = (source >= 0) & (source < width)
  diff = np.abs(example['left'][inside].astype(float) -
                example['right'][rows[inside], source[inside]].astype(float))
  assert np.median(diff) < 8
  expected = mixtures.mix(example['name'], example['left'] / 127.5 - 1,
                          example['right'] / 127.5 - 1).numpy()
  assert np.abs((expected + 1) * 127.5 - example['mixture']).max() <= 1


def test_window_aligned_example_matches_its_ground_truth(textures):
  example = refiner_data.make_example(5, SMALL, textures)
  assert example['name'] in ('gray', 'anaglyph')
  assert example['mixture'].shape == (48, 64, 3) and example['mixture'].dtype == np.uint8
  d = example['disparity_left']
  assert d.min() < 0 < d.max()  # Window-aligned: the disparities straddle zero.
  _assert_undegraded_pair(example)
  # The classical result is the de-anaglyph's on the mixture, its matcher on one strip.
  one_strip = anaglyph.AnaglyphConfig(matching=matcher.MatcherConfig(strips=1))
  again = anaglyph.unmix_anaglyph(example['mixture'], example['name'], None, one_strip)
  np.testing.assert_array_equal(again['disparity_left'], example['classical_disparity_left'])


@pytest.mark.parametrize('name', ['anaglyph', 'diplopia'])
def test_the_same_frame_through_both_routes_gives_bit_identical_arrays(name, textures):
  """A training example's classical arrays are what the served classical method returns
  on its mixture, with the same one-strip option."""
  example = refiner_data.make_example(3, dataclasses.replace(SMALL, mixtures=name), textures)
  unmixer = predictors.build_unmixer(predictors.PredictorConfig('classical', mixture=name))
  served = unmixer(example['mixture'],
                   hint=dataclasses.replace(refiner_data.ONE_STRIP, mixture=name))
  for key in ('left', 'right', 'disparity_left', 'disparity_right'):
    np.testing.assert_array_equal(served[key], example[f'classical_{key}'], err_msg=key)


def test_shards_are_built_once_and_loaded_in_order(tmp_path, textures):
  del textures
  folder = str(tmp_path)
  path = refiner_data.build_shard(folder, 1, 2, SMALL)
  stamp = os.path.getmtime(path)
  assert refiner_data.build_shard(folder, 1, 2, SMALL) == path
  assert os.path.getmtime(path) == stamp
  with pytest.raises(ValueError, match='Missing refiner example shards'):
    refiner_data.load_shards(folder, 2)
  refiner_data.build_shard(folder, 0, 2, SMALL)
  data = refiner_data.load_shards(folder, 2)
  assert data['mixture'].shape == (4, 48, 64, 3)
  first = refiner_data.make_example(2, SMALL, texture_atlas.load_textures('train'))
  np.testing.assert_array_equal(data['left'][2], first['left'])
  inputs = refiner.network_input(data['mixture'], data['classical_left'],
                                      data['classical_right'],
                                      data['classical_disparity_left'],
                                      data['classical_disparity_right'])
  assert inputs.shape == (4, 48, 64, 11) and inputs.dtype == np.float32
  np.testing.assert_array_equal(inputs[..., 9], data['classical_disparity_left'])


def test_clean_share_keeps_the_encoding_and_draws_nothing_else(textures):
  degraded = dataclasses.replace(SMALL, degrade=True)
  clean = dataclasses.replace(degraded, clean_probability=1.0)
  plain, kept = (refiner_data.make_example(5, c, textures) for c in (degraded, clean))
  np.testing.assert_array_equal(plain['left'], kept['left'])  # Same scene and shift.
  assert plain['name'] == kept['name']
  assert kept['clean'] and not plain['clean']
  expected = mixtures.mix(kept['name'], kept['left'] / 127.5 - 1,
                          kept['right'] / 127.5 - 1).numpy()
  assert np.abs((expected + 1) * 127.5 - kept['mixture']).max() <= 1
  assert np.abs((expected + 1) * 127.5 - plain['mixture']).mean() > 2  # Degraded.


def test_large_example_is_a_window_of_a_scene_twice_as_large(textures):
  large = dataclasses.replace(SMALL, large_probability=1.0)
  example = refiner_data.make_example(5, large, textures)
  assert example['mixture'].shape == (48, 64, 3)
  assert example['classical_disparity_left'].shape == (48, 64)
  # The same draws as the small examples, on scenes twice as deep: the encodings are
  # kept and the windows' disparity spreads are about twice the small scenes'.
  drawn = {config: [refiner_data.make_example(i, config, textures) for i in range(4)]
           for config in (SMALL, large)}
  assert [e['name'] for e in drawn[SMALL]] == [e['name'] for e in drawn[large]]
  spread = {config: np.mean([np.ptp(e['disparity_left']) for e in examples])
            for config, examples in drawn.items()}
  assert spread[large] > 1.5 * spread[SMALL]
  _assert_undegraded_pair(example)  # The window keeps the pair's geometry.


def test_config_checks():
  with pytest.raises(ValueError, match='window_probability'):
    refiner_data.ExampleConfig(window_probability=2.0)
  with pytest.raises(ValueError, match='clean_probability'):
    refiner_data.ExampleConfig(clean_probability=-0.1)
  with pytest.raises(ValueError, match='large_probability'):
    refiner_data.ExampleConfig(large_probability=1.5)
  with pytest.raises(ValueError, match='large_factor'):
    refiner_data.ExampleConfig(large_factor=0)
  with pytest.raises(ValueError, match='weighted_probability'):
    refiner_data.ExampleConfig(weighted_probability=1.2)
  with pytest.raises(ValueError, match='weight_range'):
    refiner_data.ExampleConfig(weight_range=(0.6, 0.4))
  with pytest.raises(ValueError, match='weight_range'):
    refiner_data.ExampleConfig(weight_range=(0.0, 0.5))
  with pytest.raises(ValueError):
    refiner_data.ExampleConfig(mixtures='nothing')


def test_weights_are_drawn_for_double_images_only_and_keep_the_other_draws():
  weighted = dataclasses.replace(SMALL, weighted_probability=1.0, weight_range=(0.3, 0.4))
  assert refiner_data.mixing_weight(3, 'anaglyph', weighted) is None
  assert refiner_data.mixing_weight(3, 'diplopia', SMALL) is None
  drawn = [refiner_data.mixing_weight(i, 'diplopia', weighted) for i in range(20)]
  assert all(0.3 <= a <= 0.4 for a in drawn) and len(set(drawn)) == 20
  half = dataclasses.replace(weighted, weighted_probability=0.5)
  share = np.mean([refiner_data.mixing_weight(i, 'diplopia', half) is not None
                   for i in range(400)])
  assert 0.4 < share < 0.6


def test_a_weighted_double_image_and_its_classical_stage_with_the_weight_estimated(textures):
  config = dataclasses.replace(SMALL, mixtures='diplopia', height=64, width=128,
                               max_disparity=24, weighted_probability=1.0,
                               weight_range=(0.3, 0.3))
  example = refiner_data.make_example(3, config, textures)
  left, right = (example[k].astype(float) for k in ('left', 'right'))
  assert np.abs(0.3 * left + 0.7 * right - example['mixture']).max() <= 1
  assert np.abs((left + right) / 2 - example['mixture']).mean() > 2
  # Its classical arrays are the served method's with --mixing_weight=auto, not 1/2.
  unmixer = predictors.build_unmixer(predictors.PredictorConfig('classical',
                                                                mixture='diplopia'))
  served = {weight: unmixer(example['mixture'], hint=dataclasses.replace(
      refiner_data.ONE_STRIP, mixture='diplopia', mixing_weight=weight))
            for weight in ('auto', None)}
  for key in ('left', 'right', 'disparity_left', 'disparity_right'):
    np.testing.assert_array_equal(served['auto'][key], example[f'classical_{key}'])
  assert not np.array_equal(served[None]['left'], example['classical_left'])


def test_a_shipped_base_stage_gives_the_examples_first_stage_as_served(textures):
  config = dataclasses.replace(SMALL, mixtures='anaglyph', height=64, width=128,
                               max_disparity=24, base='anaglyph_matching')
  stage = refiner_data.base_stage(config)
  example = refiner_data.make_example(3, config, textures, stage)
  plain = refiner_data.make_example(3, dataclasses.replace(config, base=''), textures)
  np.testing.assert_array_equal(example['mixture'], plain['mixture'])
  # Its first-stage arrays are what `--pretrained=anaglyph_matching` serves, not classical.
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'model', mixture='anaglyph', pretrained='anaglyph_matching'))
  served = unmixer(example['mixture'], hint=dataclasses.replace(refiner_data.ONE_STRIP,
                                                                mixture='anaglyph'))
  for key in ('left', 'right', 'disparity_left', 'disparity_right'):
    np.testing.assert_array_equal(served[key], example[f'classical_{key}'])
  assert not np.array_equal(plain['classical_disparity_left'],
                            example['classical_disparity_left'])


@pytest.mark.parametrize('base, message', [('no_such_model', 'No pretrained model'),
                                           ('anaglyph', 'no first stage'),
                                           ('diplopia_echo', 'no first stage')])
def test_a_base_that_is_no_first_stage_of_the_mixtures_is_refused(base, message):
  with pytest.raises(ValueError, match=message):
    dataclasses.replace(SMALL, base=base)


def test_texture_photographs_that_look_like_evaluation_scenes_are_refused(tmp_path):
  (tmp_path / 'teddy.png').write_bytes(b'')
  with pytest.raises(ValueError, match='teddy.png'):
    refiner_data._textures(dataclasses.replace(SMALL, texture_dir=str(tmp_path)))  # pylint: disable=protected-access
