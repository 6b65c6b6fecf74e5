"""Tests of the tf.data pipeline on a stubbed loader with an analytic stereo scene."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf import mixtures
from mixstereo_tf.data import pipeline
from mixstereo_tf.data import records

_H, _W, _D = 16, 40, 3  # A fronto-parallel scene at a constant disparity of 3 px.


def _scene(seed):
  """left(x) = T(x), right(x) = T(x + D): the left pixel x matches the right pixel x - D."""
  texture = np.random.default_rng(seed).integers(0, 256, (_H, _W + _D, 3), dtype=np.uint8)
  disparity = np.full((_H, _W), _D, np.float32)
  valid = np.ones((_H, _W), bool)
  return {'left': texture[:, :_W], 'right': texture[:, _D:_D + _W],
          'disparity_left': disparity, 'disparity_right': disparity.copy(),
          'valid_left': valid, 'valid_right': valid.copy(), 'nonocc_left': valid.copy()}


@pytest.fixture(name='samples')
def _samples(monkeypatch):
  monkeypatch.setattr(records, 'load_sample', lambda s: _scene(int(s.name)))
  return [records.StereoSample(name=str(i), left=f'l{i}', right=f'r{i}') for i in range(4)]


def _take(ds, n):
  return [{k: v.numpy() for k, v in e.items()} for e in ds.take(n)]


def _config(**kwargs):
  base = dict(mixture='anaglyph', crop_height=_H, crop_width=_W - 8, batch_size=2, seed=3)
  base.update(kwargs)
  return pipeline.PipelineConfig(**base)


def test_element_keys_shapes_and_range(samples):
  (batch,) = _take(pipeline.train_dataset(samples, _config()), 1)
  assert set(batch) == {'mixture', 'left', 'right', 'disparity_left', 'disparity_right',
                        'valid_left', 'valid_right', 'nonocc_left', 'name'}
  for key in ('mixture', 'left', 'right'):
    assert batch[key].shape == (2, _H, _W - 8, 3)
    assert batch[key].min() >= -1.0 and batch[key].max() <= 1.0
  assert batch['disparity_left'].shape == (2, _H, _W - 8, 1)


def test_same_seed_same_batches_other_seed_differs(samples):
  first = _take(pipeline.train_dataset(samples, _config()), 3)
  second = _take(pipeline.train_dataset(samples, _config()), 3)
  other = _take(pipeline.train_dataset(samples, _config(seed=4)), 3)
  for a, b in zip(first, second):
    for key in a:
      np.testing.assert_array_equal(a[key], b[key])
  assert any(not np.array_equal(a['left'], c['left']) for a, c in zip(first, other))


@pytest.mark.parametrize('mixture', ['anaglyph', 'diplopia', 'dubois'])
def test_mixture_matches_operator_after_flip_and_augmentation(samples, mixture):
  for batch in _take(pipeline.train_dataset(samples, _config(mixture=mixture)), 4):
    expected = mixtures.mix(mixture, batch['left'], batch['right']).numpy()
    np.testing.assert_allclose(batch['mixture'], expected, atol=1e-6)


def _left_from_right(left, right, disparity):
  """Checks left(x) == right(x - d_L(x)) for every pixel whose match is inside the crop."""
  width = left.shape[1]
  matched = 0
  for x in range(width):
    for y in range(left.shape[0]):
      xr = x - int(round(float(disparity[y, x, 0])))
      if 0 <= xr < width:
        np.testing.assert_allclose(left[y, x], right[y, xr], atol=1e-6)
        matched += 1
  return matched


def test_flip_and_swap_keeps_the_geometry():
  scene = {k: tf.constant(v.astype(np.float32)) for k, v in _scene(0).items()}
  for key in ('disparity_left', 'disparity_right', 'valid_left', 'valid_right', 'nonocc_left'):
    scene[key] = scene[key][..., None]
  flipped = {k: v.numpy() for k, v in pipeline.flip_and_swap(scene).items()}
  np.testing.assert_array_equal(flipped['left'], scene['right'].numpy()[:, ::-1])
  assert _left_from_right(flipped['left'], flipped['right'], flipped['disparity_left']) > 0


def test_pipeline_batches_keep_disparities_consistent(samples):
  config = _config(augment=False, batch_size=1, crop_width=_W)
  flips = []
  for batch in _take(pipeline.train_dataset(samples, config), 8):
    left, right, disp = batch['left'][0], batch['right'][0], batch['disparity_left'][0]
    assert _left_from_right(left, right, disp) > 0
    scene = _scene(int(batch['name'][0]))
    as_float = lambda x: x.astype(np.float32) / 255 * 2 - 1
    flipped = np.allclose(left, as_float(scene['right'][:, ::-1]), atol=1e-6)
    assert flipped or np.allclose(left, as_float(scene['left']), atol=1e-6)
    flips.append(flipped)
  assert any(flips) and not all(flips)  # Both branches were exercised.


def test_augmentation_is_identical_for_both_views(samples):
  config = _config(flip=False, batch_size=1, crop_width=_W)
  for batch in _take(pipeline.train_dataset(samples, config), 6):
    left, right = batch['left'][0], batch['right'][0]
    np.testing.assert_allclose(left[:, _D:], right[:, :-_D], atol=1e-5)


def test_small_images_are_padded_to_the_crop(samples):
  config = _config(crop_height=_H + 4, crop_width=_W + 8, batch_size=1, augment=False,
                   flip=False)
  (batch,) = _take(pipeline.train_dataset(samples, config), 1)
  assert batch['left'].shape == (1, _H + 4, _W + 8, 3)
  assert batch['valid_left'][0, _H:].max() == 0.0  # Padded ground truth is unknown.


def test_eval_dataset_is_full_size_in_order(samples):
  elements = _take(pipeline.eval_dataset(samples, 'diplopia'), 4)
  assert [e['name'][0].decode() for e in elements] == ['0', '1', '2', '3']
  assert elements[0]['left'].shape == (1, _H, _W, 3)
  expected = (_scene(0)['left'].astype(np.float32) / 255 * 2 - 1)
  np.testing.assert_allclose(elements[0]['left'][0], expected, atol=1e-6)


def test_bad_config_and_empty_list():
  with pytest.raises(ValueError, match='crop_height'):
    pipeline.PipelineConfig(crop_height=0)
  with pytest.raises(ValueError, match='Unknown mixture'):
    pipeline.PipelineConfig(mixture='nope')
  with pytest.raises(ValueError, match='empty'):
    pipeline.train_dataset([], pipeline.PipelineConfig())


def test_decode_error_names_the_sample(monkeypatch):
  def broken(sample):
    raise ValueError(f'{sample.source}: cannot decode {sample.left}')
  monkeypatch.setattr(records, 'load_sample', broken)
  samples = [records.StereoSample('a', 'bad.png', 'r.png', source='list.txt:7')]
  with pytest.raises(tf.errors.InvalidArgumentError, match='list.txt:7'):
    _take(pipeline.train_dataset(samples, _config(batch_size=1)), 1)


def test_skip_bad_pairs_drops_failing_pairs(monkeypatch):
  def sometimes(sample):
    if sample.name == 'bad':
      raise ValueError('corrupt')
    return _scene(0)
  monkeypatch.setattr(records, 'load_sample', sometimes)
  samples = [records.StereoSample(n, n, n) for n in ('good', 'bad')]
  config = _config(batch_size=1, skip_bad_pairs=True)
  names = {e['name'][0].decode() for e in _take(pipeline.train_dataset(samples, config), 6)}
  assert names == {'good'}
