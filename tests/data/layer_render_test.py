"""Known-answer tests of layer rendering: positions, disparities, occlusions, shapes."""

import numpy as np
import pytest

from mixstereo_tf.data import layer_render


def _constant(value):
  return np.full((4, 4, 3), value, np.float32)


def _two_layers():
  """A 10x10 fronto-parallel square of disparity 6 (left x in [20, 30), y in [11, 21))
  over a background of disparity 2; grey 200 over grey 50."""
  background = layer_render.Layer('full', (), (2.0, 0.0, 0.0), texture=0)
  square = layer_render.Layer('rectangle', (25.0, 16.0, 5.0, 5.0, 0.0), (6.0, 0.0, 0.0), texture=1)
  return layer_render.render_layers([background, square], [_constant(50), _constant(200)], 32, 64)


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
  layer = layer_render.Layer('full', (), (3.0, 0.05, -0.02), texture=0)
  scene = layer_render.render_layers([layer], [_constant(80)], 8, 40)
  y, x = np.mgrid[0:8, 0:40].astype(np.float64)
  np.testing.assert_allclose(scene['disparity_left'], 3.0 + 0.05 * x - 0.02 * y, atol=1e-5)
  # The right pixel x matches left x + d_R, whose left disparity is d_R itself.
  x_left = x + scene['disparity_right']
  np.testing.assert_allclose(scene['disparity_right'], 3.0 + 0.05 * x_left - 0.02 * y,
                             atol=1e-4)


def test_polygon_mask_ignores_vertex_order():
  y, x = np.mgrid[0:12, 0:12].astype(np.float32)
  ccw = layer_render.Layer('polygon', (0, 0, 10, 0, 0, 10), (1, 0, 0), 0)
  cw = layer_render.Layer('polygon', (0, 0, 0, 10, 10, 0), (1, 0, 0), 0)
  mask = layer_render.shape_mask(ccw, x, y)
  np.testing.assert_array_equal(mask, layer_render.shape_mask(cw, x, y))
  np.testing.assert_array_equal(mask, x + y <= 10)


def test_bad_layer_stacks_raise_clear_errors():
  square = layer_render.Layer('rectangle', (5, 5, 2, 2, 0), (3, 0, 0), 0)
  with pytest.raises(ValueError, match='full'):
    layer_render.render_layers([square], [_constant(1)], 8, 8)
  background = layer_render.Layer('full', (), (1, 0, 0), texture=3)
  with pytest.raises(ValueError, match='texture indices'):
    layer_render.render_layers([background], [_constant(1)], 8, 8)
