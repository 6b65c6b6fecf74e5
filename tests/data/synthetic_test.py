"""Known-answer and consistency tests of the procedural layered stereo scenes."""

import numpy as np
import pytest

from mixstereo_tf.data import layer_render
from mixstereo_tf.data import synthetic
from mixstereo_tf.data import texture_atlas
from mixstereo_tf.ops import warp

_SMALL = synthetic.SceneConfig(height=32, width=64, max_disparity=16)
_MEDIUM = synthetic.SceneConfig(height=64, width=128, max_disparity=32)


@pytest.fixture(scope='module', name='textures')
def _textures():
  return texture_atlas.load_textures('train')


@pytest.mark.parametrize('seed', [0, 1, 2])
def test_warping_right_view_reproduces_left_view(textures, seed):
  scene = synthetic.render_scene(seed, _MEDIUM, textures)
  mask = scene['nonocc_left']
  assert 0.02 < 1.0 - mask.mean() < 0.6  # Occlusions exist but do not dominate.
  disparity = scene['disparity_left'][None, ..., None]
  right = scene['right'][None].astype(np.float32)
  warped = warp.reconstruct_left(right, disparity).numpy()[0]
  error = np.abs(warped - scene['left'])[mask]
  assert error.mean() < 2.0  # Bilinear resampling of blurred textures: < 2/255 on average.
  # The disparities agree: d_R(x - d_L(x)) = d_L(x) except at a few depth-edge pixels.
  back = warp.reconstruct_left(scene['disparity_right'][None, ..., None], disparity).numpy()
  gap = np.abs(back[0, ..., 0] - scene['disparity_left'])[mask]
  assert np.median(gap) < 1e-3
  assert np.mean(gap > 0.5) < 0.03


def test_same_seed_is_identical_and_seeds_differ(textures):
  first = synthetic.render_scene(7, _SMALL, textures)
  again = synthetic.render_scene(7, _SMALL, textures)
  other = synthetic.render_scene(8, _SMALL, textures)
  for key in first:
    np.testing.assert_array_equal(first[key], again[key])
  assert not np.array_equal(first['left'], other['left'])
  assert not np.array_equal(first['disparity_left'], other['disparity_left'])


def test_disparities_stay_in_range_and_layers_vary(textures):
  counts = set()
  for seed in range(12):
    layers = synthetic.random_layers(seed, _SMALL, len(textures))
    counts.add(len(layers))
    assert _SMALL.min_layers <= len(layers) <= _SMALL.max_layers
    scene = layer_render.render_layers(layers, textures, _SMALL.height, _SMALL.width)
    for key in ('disparity_left', 'disparity_right'):
      assert scene[key].dtype == np.float32 and scene[key].shape == (32, 64)
      assert scene[key].min() >= _SMALL.min_disparity - 1e-4
      assert scene[key].max() <= _SMALL.near_limit + 1e-4 <= _SMALL.max_disparity - 1
    assert scene['left'].dtype == np.uint8 and scene['left'].shape == (32, 64, 3)
  assert len(counts) > 1


def test_bad_configs_raise_clear_errors():
  with pytest.raises(ValueError, match='max_disparity'):
    synthetic.SceneConfig(max_disparity=1)
  with pytest.raises(ValueError, match='min_layers'):
    synthetic.SceneConfig(max_disparity=32, min_layers=5, max_layers=3)
