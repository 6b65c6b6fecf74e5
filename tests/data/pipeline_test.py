"""Tests of the tf.data pipeline on a stubbed loader with an analytic stereo scene."""

import logging

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.core import mixtures
from mixstereo_tf.data import pipeline
from mixstereo_tf.data import records
from mixstereo_tf.data import sources
from mixstereo_tf.data import layer_render

_H, _W, _D = 16, 40, 3  # A fronto-parallel scene at a constant disparity of 3 px.


def _scene(seed):
  """left(x) = T(x), right(x) = T(x + D): the left pixel x matches the right pixel x - D."""
  texture = np.random.default_rng(seed).integers(0, 256, (_H, _W + _D, 3), dtype=np.uint8)
  disparity = np.full((_H, _W), _D, np.float32)
  valid = np.ones((_H, _W), bool)
  return {'left': texture[:, :_W], 'right': texture[:, _D:_D + _W],
          'disparity_left': disparity, 'disparity_right': disparity.copy(),
          'valid_left': valid, 'valid_right': valid.copy(), 'nonocc_left': valid.copy(),
          'disc_left': np.zeros_like(valid)}


@pytest.fixture(name='samples')
def _samples(monkeypatch):
  monkeypatch.setattr(sources, 'load_sample', lambda s: _scene(int(s.name)))
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


def test_a_resumed_stream_continues_where_it_stopped(samples):
  """Batch k of the stream started at batch 2 is batch 2 + k of the whole stream (a
  resumed training run continues the data, it does not replay its first batches)."""
  whole = _take(pipeline.train_dataset(samples, _config()), 5)
  resumed = _take(pipeline.train_dataset(samples, _config(), start_batch=2), 3)
  for a, b in zip(whole[2:], resumed):
    for key in a:
      np.testing.assert_array_equal(a[key], b[key])
  assert not np.array_equal(whole[0]['left'], resumed[0]['left'])


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


def _occluding_scene():
  """A square at disparity 6 over a background at 2, random textures: d_L != d_R."""
  rng = np.random.default_rng(5)
  textures = [rng.uniform(0, 255, (32, 64, 3)).astype(np.float32) for _ in range(2)]
  layers = [layer_render.Layer('full', (), (2.0, 0.0, 0.0), texture=0),
            layer_render.Layer('rectangle', (25.0, 16.0, 5.0, 5.0, 0.0), (6.0, 0.0, 0.0),
                            texture=1)]
  scene = layer_render.render_layers(layers, textures, 32, 64)
  scene['valid_left'] = rng.uniform(size=(32, 64)) < 0.7
  scene['valid_right'] = rng.uniform(size=(32, 64)) < 0.7
  return scene


def test_flip_and_swap_mirrors_and_swaps_different_disparities():
  scene = _occluding_scene()
  assert not np.array_equal(scene['disparity_left'], scene['disparity_right'])
  element = {k: tf.constant(v.astype(np.float32)) for k, v in scene.items()}
  for key in ('disparity_left', 'disparity_right', 'valid_left', 'valid_right', 'nonocc_left'):
    element[key] = element[key][..., None]
  flipped = {k: v.numpy() for k, v in pipeline.flip_and_swap(element).items()}
  mirror = lambda key: scene[key][:, ::-1].astype(np.float32)
  np.testing.assert_array_equal(flipped['left'], mirror('right'))
  np.testing.assert_array_equal(flipped['right'], mirror('left'))
  for new, old in (('disparity_left', 'disparity_right'), ('disparity_right', 'disparity_left'),
                   ('valid_left', 'valid_right'), ('valid_right', 'valid_left'),
                   ('nonocc_left', 'valid_right')):
    np.testing.assert_array_equal(flipped[new][..., 0], mirror(old), err_msg=new)
  # New left pixel x = old right pixel W-1-x, visible in the old left view exactly where
  # the old pair is left-right consistent there; it must match new right pixel x - d_L(x).
  d_new = flipped['disparity_left'][..., 0].astype(int)
  d_old_left = flipped['disparity_right'][..., 0].astype(int)
  cols = np.clip(np.arange(64)[None, :] - d_new, 0, 63)
  consistent = ((np.arange(64)[None, :] >= d_new) &
                (np.take_along_axis(d_old_left, cols, 1) == d_new))
  matched = np.take_along_axis(flipped['right'], cols[..., None], 1)
  np.testing.assert_array_equal(flipped['left'][consistent], matched[consistent])
  assert (consistent & (d_new == 6)).sum() > 50  # The square's pixels are checked too.


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


def test_crop_offsets_of_consecutive_elements_are_independent(monkeypatch):
  # Both axes offer 33 offsets, so if element i's horizontal draw reused the seed of element
  # i + 1's vertical draw, the two offsets would be equal every time (chance: 1 in 33).
  rows, cols = np.mgrid[0:40, 0:40]
  image = np.stack([rows, cols, rows], axis=-1).astype(np.uint8)  # R = row, G = column.
  scene = dict(_scene(0), left=image, right=image)
  for key in ('disparity_left', 'disparity_right', 'valid_left', 'valid_right', 'nonocc_left',
              'disc_left'):
    scene[key] = np.zeros((40, 40), scene[key].dtype)
  monkeypatch.setattr(sources, 'load_sample', lambda s: scene)
  config = _config(crop_height=8, crop_width=8, batch_size=1, augment=False, flip=False)
  ds = pipeline.train_dataset([records.StereoSample('a', 'l', 'r')], config)
  corners = np.array([(e['left'][0, 0, 0, :2] + 1) / 2 * 255 for e in _take(ds, 200)])
  tops, lefts = np.rint(corners).astype(int).T
  assert len(set(tops)) > 20 and len(set(lefts)) > 20
  assert np.mean(tops[1:] == lefts[:-1]) < 0.15
  assert np.mean(tops == lefts) < 0.15


def test_photometric_draws_lie_in_monodepth_ranges_and_apply_half_the_time():
  draws = [{k: v.numpy() for k, v in pipeline.photometric_parameters(
      tf.constant([11, i], tf.int64)).items()} for i in range(200)]
  gamma = np.array([d['gamma'] for d in draws])
  brightness = np.array([d['brightness'] for d in draws])
  colour = np.array([d['colour'] for d in draws])
  assert colour.shape == (200, 3)
  for values, low, high in ((gamma, 0.8, 1.2), (brightness, 0.5, 2.0), (colour, 0.8, 1.2)):
    assert values.min() >= low and values.max() <= high
    # 200 uniform draws reach within 5% of the range of both ends.
    margin = 0.05 * (high - low)
    assert values.min() < low + margin and values.max() > high - margin
  assert np.mean(colour[:, 0] != colour[:, 1]) > 0.9  # One factor per channel.
  assert 0.35 <= np.mean([d['apply'] for d in draws]) <= 0.65


def test_augmentation_applies_its_drawn_parameters():
  rng = np.random.default_rng(2)
  left, right = (rng.uniform(0, 1, (4, 6, 3)).astype(np.float32) for _ in range(2))
  applied = []
  for i in range(12):
    seed = tf.constant([5, i], tf.int64)
    params = {k: v.numpy() for k, v in pipeline.photometric_parameters(seed).items()}
    outputs = pipeline.augment_photometric(tf.constant(left), tf.constant(right), seed)
    for view, out in zip((left, right), outputs):
      expected = view
      if params['apply']:
        expected = np.clip(view ** params['gamma'] * params['brightness'] * params['colour'],
                           0, 1)
      np.testing.assert_allclose(out.numpy(), expected, rtol=1e-5, atol=1e-6)
    applied.append(bool(params['apply']))
  assert any(applied) and not all(applied)


def test_small_images_are_padded_to_the_crop(samples):
  config = _config(crop_height=_H + 4, crop_width=_W + 8, batch_size=1, augment=False,
                   flip=False)
  (batch,) = _take(pipeline.train_dataset(samples, config), 1)
  assert batch['left'].shape == (1, _H + 4, _W + 8, 3)
  assert batch['valid_left'][0, _H:].max() == 0.0  # Padded ground truth is unknown.


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
  monkeypatch.setattr(sources, 'load_sample', broken)
  samples = [records.StereoSample('a', 'bad.png', 'r.png', source='list.txt:7')]
  with pytest.raises(tf.errors.InvalidArgumentError, match='list.txt:7'):
    _take(pipeline.train_dataset(samples, _config(batch_size=1)), 1)


def test_skip_bad_pairs_drops_failing_pairs(monkeypatch, caplog):
  def sometimes(sample):
    if sample.name == 'bad':
      raise ValueError('corrupt')
    return _scene(0)
  monkeypatch.setattr(sources, 'load_sample', sometimes)
  samples = [records.StereoSample(n, n, n) for n in ('good', 'bad')]
  config = _config(batch_size=1, skip_bad_pairs=True)
  caplog.set_level(logging.WARNING)
  names = {e['name'][0].decode() for e in _take(pipeline.train_dataset(samples, config), 6)}
  assert names == {'good'}
  assert 'Skipped a pair that does not decode (skip_bad_pairs): corrupt' in caplog.text
