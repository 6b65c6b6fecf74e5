"""Known-answer and consistency tests of the procedural layered stereo scenes."""

import numpy as np
import pytest

from mixstereo_tf.data import synthetic
from mixstereo_tf.data import texture_atlas
from mixstereo_tf.ops import warp

_SMALL = synthetic.SceneConfig(height=32, width=64, max_disparity=16)
_MEDIUM = synthetic.SceneConfig(height=64, width=128, max_disparity=32)


@pytest.fixture(scope='module', name='textures')
def _textures():
  return texture_atlas.load_textures('train')


def _constant(value):
  return np.full((4, 4, 3), value, np.float32)


def _two_layers():
  """A 10x10 fronto-parallel square of disparity 6 (left x in [20, 30), y in [11, 21))
  over a background of disparity 2; grey 200 over grey 50."""
  background = synthetic.Layer('full', (), (2.0, 0.0, 0.0), texture=0)
  square = synthetic.Layer('rectangle', (25.0, 16.0, 5.0, 5.0, 0.0), (6.0, 0.0, 0.0), texture=1)
  return synthetic.render_layers([background, square], [_constant(50), _constant(200)], 32, 64)


def test_two_layer_scene_has_exact_positions_and_occlusions():
  scene = _two_layers()
  rows = slice(11, 21)
  expected_left = np.full((32, 64), 50, np.uint8)
  expected_left[rows, 20:30] = 200
  expected_right = np.full((32, 64), 50, np.uint8)
  expected_right[rows, 14:24] = 200  # x_R = x_L - 6.
  for channel in range(3):
    np.testing.assert_array_equal(scene['left'][..., channel], expected_left)
    np.testing.assert_array_equal(scene['right'][..., channel], expected_right)
  np.testing.assert_array_equal(scene['disparity_left'], np.where(expected_left == 200, 6, 2))
  np.testing.assert_array_equal(scene['disparity_right'], np.where(expected_right == 200, 6, 2))
  # Hidden: columns 0-1 match outside the right image (x - 2 < 0); background columns 16-19
  # of the square's rows match right columns 14-17, which show the square.
  expected_occluded = np.zeros((32, 64), bool)
  expected_occluded[:, :2] = True
  expected_occluded[rows, 16:20] = True
  np.testing.assert_array_equal(~scene['nonocc_left'], expected_occluded)


def test_slanted_background_inverts_in_closed_form():
  layer = synthetic.Layer('full', (), (3.0, 0.05, -0.02), texture=0)
  scene = synthetic.render_layers([layer], [_constant(80)], 8, 40)
  y, x = np.mgrid[0:8, 0:40].astype(np.float64)
  np.testing.assert_allclose(scene['disparity_left'], 3.0 + 0.05 * x - 0.02 * y, atol=1e-5)
  # The right pixel x matches left x + d_R, whose left disparity is d_R itself.
  x_left = x + scene['disparity_right']
  np.testing.assert_allclose(scene['disparity_right'], 3.0 + 0.05 * x_left - 0.02 * y,
                             atol=1e-4)


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
    scene = synthetic.render_layers(layers, textures, _SMALL.height, _SMALL.width)
    for key in ('disparity_left', 'disparity_right'):
      assert scene[key].dtype == np.float32 and scene[key].shape == (32, 64)
      assert scene[key].min() >= _SMALL.min_disparity - 1e-4
      assert scene[key].max() <= _SMALL.near_limit + 1e-4 <= _SMALL.max_disparity - 1
    assert scene['left'].dtype == np.uint8 and scene['left'].shape == (32, 64, 3)
  assert len(counts) > 1


def test_polygon_mask_ignores_vertex_order():
  y, x = np.mgrid[0:12, 0:12].astype(np.float32)
  ccw = synthetic.Layer('polygon', (0, 0, 10, 0, 0, 10), (1, 0, 0), 0)
  cw = synthetic.Layer('polygon', (0, 0, 0, 10, 10, 0), (1, 0, 0), 0)
  mask = synthetic.shape_mask(ccw, x, y)
  np.testing.assert_array_equal(mask, synthetic.shape_mask(cw, x, y))
  np.testing.assert_array_equal(mask, x + y <= 10)


def test_bad_inputs_raise_clear_errors():
  with pytest.raises(ValueError, match='max_disparity'):
    synthetic.SceneConfig(max_disparity=1)
  with pytest.raises(ValueError, match='min_layers'):
    synthetic.SceneConfig(max_disparity=32, min_layers=5, max_layers=3)
  square = synthetic.Layer('rectangle', (5, 5, 2, 2, 0), (3, 0, 0), 0)
  with pytest.raises(ValueError, match='full'):
    synthetic.render_layers([square], [_constant(1)], 8, 8)
  background = synthetic.Layer('full', (), (1, 0, 0), texture=3)
  with pytest.raises(ValueError, match='texture indices'):
    synthetic.render_layers([background], [_constant(1)], 8, 8)
