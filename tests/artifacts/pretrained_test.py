"""Tests for mixstereo_tf.artifacts.pretrained: the shipped models, their format and their choice."""

import json
import os

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.models import refiner
from mixstereo_tf.restoration import views
from mixstereo_tf.unmixing import predictors
from tests.unmixing import predictors_test

TINY = refiner.RefinerConfig(view_widths=(4, 4), disparity_features=4, dilations=(1,))


def test_save_and_load_round_trip_in_float16(tmp_path):
  model = refiner.build_refiner(TINY)
  for weight in model.weights:
    weight.assign(tf.random.stateless_normal(weight.shape, [0, 1]))
  entry = pretrained.save(model, str(tmp_path / 'tiny'), 'refiner', 'anaglyph,gray',
                          TINY.to_dict(), 'recipe text', 'numbers', (64, 128))
  assert (entry.name, entry.kind, entry.mixtures, entry.crop) == (
      'tiny', 'refiner', ('anaglyph', 'gray'), (64, 128))
  loaded = pretrained.load_model(pretrained.get(str(tmp_path / 'tiny')))
  for saved, restored in zip(model.get_weights(), loaded.get_weights()):
    np.testing.assert_array_equal(restored, saved.astype(np.float16).astype(np.float32))


def test_joint_model_from_a_training_run(tmp_path):
  model, _ = predictors_test.make_run_dir(str(tmp_path / 'run'), mixture='diplopia')
  entry = pretrained.from_run(str(tmp_path / 'run'), str(tmp_path / 'dip'), 'r', 'n')
  assert (entry.kind, entry.mixtures, entry.crop) == ('joint', ('diplopia',), (64, 128))
  loaded = pretrained.load_model(entry)
  for saved, restored in zip(model.get_weights(), loaded.get_weights()):
    np.testing.assert_allclose(restored, saved, rtol=1e-3, atol=1e-4)


def test_bad_folders_are_named(tmp_path):
  with pytest.raises(ValueError, match='No info.json'):
    pretrained.read(str(tmp_path))
  (tmp_path / 'info.json').write_text(json.dumps({'kind': 'other', 'mixture': 'anaglyph',
                                                  'config': {}}))
  with pytest.raises(ValueError, match="unknown kind 'other'"):
    pretrained.read(str(tmp_path))
  with pytest.raises(ValueError, match='No pretrained model .nothing.; shipped: '):
    pretrained.get('nothing')


def test_the_shipped_models_cover_anaglyphs_and_diplopia_within_25_mb():
  entries = pretrained.available()
  assert pretrained.choose(None, 'auto').mixtures[0] == 'anaglyph'
  assert 'gray' in pretrained.choose(None, 'gray').mixtures
  assert pretrained.choose(None, 'diplopia').mixtures == ('diplopia',)
  total = sum(os.path.getsize(os.path.join(e.folder, f)) for e in entries
              for f in os.listdir(e.folder))
  assert total <= 25 * 2 ** 20
  for entry in entries:
    assert entry.recipe and entry.results
    pretrained.load_model(entry)  # Weights fit the architecture.
  assert all(e.name in pretrained.describe() for e in entries)


def test_untrained_refiner_unmixes_like_the_classical_method(tmp_path):
  """A refiner whose heads are zero (as initialised) returns the classical disparities."""
  entry = pretrained.save(refiner.build_refiner(TINY), str(tmp_path / 'zero'), 'refiner',
                          'anaglyphs', TINY.to_dict(), 'r', 'n')
  rng = np.random.default_rng(0)
  left = (rng.uniform(size=(40, 64, 3)) * 255).astype(np.uint8)
  right = np.roll(left, -3, axis=1)
  image = np.concatenate([left[..., :1], right[..., 1:]], -1)  # Colour red-cyan.
  model = predictors.build_unmixer(predictors.PredictorConfig(pretrained=entry.folder,
                                                            mixture='anaglyph'))
  classical = predictors.build_unmixer(predictors.PredictorConfig('classical',
                                                                mixture='anaglyph'))
  ours, theirs = model(image), classical(image)
  np.testing.assert_allclose(ours['disparity_left'], theirs['disparity_left'], atol=1e-4)
  np.testing.assert_allclose(ours['disparity_right'], theirs['disparity_right'], atol=1e-4)
  # Both hand a video's next frame the left-right check of their disparities (the
  # model's: its final restoration's, of the refined disparities).
  assert theirs['consistent_left'].shape == (40, 64) and theirs['consistent_left'].any()
  np.testing.assert_array_equal(ours['consistent_left'], views.lr_consistency(
      ours['disparity_left'], ours['disparity_right'])[0])
  assert ours['info']['method'] == 'model' and model.restore_colour
  assert not predictors.build_unmixer(predictors.PredictorConfig(mixture='diplopia')).restore_colour
  with pytest.raises(ValueError, match='trained on'):
    predictors.build_unmixer(predictors.PredictorConfig(pretrained=entry.folder,
                                                      mixture='diplopia'))
  with pytest.raises(ValueError, match='pretrained excludes'):
    predictors.build_unmixer(predictors.PredictorConfig(pretrained=entry.folder,
                                                      checkpoint=str(tmp_path)))


def test_a_refiner_saved_with_a_base_runs_on_that_shipped_stage(tmp_path):
  """A zero refiner on `base` returns the base stage's disparities, not classical's."""
  entry = pretrained.save(refiner.build_refiner(TINY), str(tmp_path / 'zero'), 'refiner',
                          'anaglyphs', TINY.to_dict(), 'r', 'n', base='anaglyph_matching')
  assert entry.base == 'anaglyph_matching'
  assert json.loads((tmp_path / 'zero' / 'info.json').read_text())['base'] == entry.base
  rng = np.random.default_rng(1)
  left = (rng.uniform(size=(48, 96, 3)) * 255).astype(np.uint8)
  right = np.roll(left, -4, axis=1)
  image = np.concatenate([left[..., :1], right[..., 1:]], -1)
  run = lambda **kw: predictors.build_unmixer(predictors.PredictorConfig(
      mixture='anaglyph', disparity_range=(0, 15), **kw))(image)
  ours, stage = run(pretrained=entry.folder), run(pretrained='anaglyph_matching')
  assert ours['info']['pretrained'] == 'zero on anaglyph_matching'
  np.testing.assert_allclose(ours['disparity_left'], stage['disparity_left'], atol=1e-4)
  assert not np.allclose(ours['disparity_left'], run(method='classical')['disparity_left'])


def test_choose_prefers_the_model_marked_default(tmp_path, monkeypatch):
  model = refiner.build_refiner(TINY)
  for name, default in (('a_first', False), ('b_marked', True), ('c_other', False)):
    pretrained.save(model, str(tmp_path / name), 'refiner', 'anaglyph' if name != 'c_other'
                    else 'gray', TINY.to_dict(), 'r', 'n')
    if default:
      info = json.loads((tmp_path / name / 'info.json').read_text())
      (tmp_path / name / 'info.json').write_text(json.dumps(dict(info, default=True)))
  monkeypatch.setattr(pretrained, 'FOLDER', str(tmp_path))
  assert pretrained.choose(None, 'auto').name == 'b_marked'
  assert pretrained.choose(None, 'gray').name == 'c_other'  # No default among those.
  assert pretrained.choose('a_first', 'anaglyph').name == 'a_first'  # Named: as named.
  assert 'b_marked: refiner model for anaglyph (the default)' in pretrained.describe()
