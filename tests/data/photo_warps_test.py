"""Tests of the photograph warps: exact correspondences, occlusions, window alignment."""

import cv2
import numpy as np
import pytest

from mixstereo_tf.data import photo_warps
from mixstereo_tf.data import texture_atlas


@pytest.fixture(scope='module')
def atlas():
  return texture_atlas.load_textures('train')


def _warp_error(pair):
  """Mean |left - right warped by d_L| over the pixels whose match is visible, 0-255."""
  h, w = pair['disparity_left'].shape
  y, x = np.mgrid[0:h, 0:w].astype(np.float32)
  warped = cv2.remap(pair['right'].astype(np.float32), x - pair['disparity_left'], y,
                     cv2.INTER_LINEAR)
  return np.abs(warped - pair['left'])[pair['nonocc_left']].mean()


def test_right_view_is_the_left_warped_by_the_field(atlas):
  config = photo_warps.WarpConfig(height=64, width=128, max_disparity=32)
  for seed in range(4):
    pair = photo_warps.warped_pair(seed, config, atlas)
    assert pair['left'].shape == (64, 128, 3) and pair['left'].dtype == np.uint8
    assert 0.5 < pair['nonocc_left'].mean() < 1.0  # Occlusions exist, most pixels match.
    assert _warp_error(pair) < 2.0
    # A wrong field does not explain the pair.
    wrong = dict(pair, disparity_left=pair['disparity_left'] + 3.0)
    assert _warp_error(wrong) > 2 * _warp_error(pair)


def test_window_alignment_gives_both_signs_and_is_deterministic(atlas):
  config = photo_warps.WarpConfig(height=48, width=96, max_disparity=32,
                                  window_probability=1.0)
  pairs = [photo_warps.warped_pair(s, config, atlas) for s in range(6)]
  assert any((p['disparity_left'] < 0).any() for p in pairs)
  again = photo_warps.warped_pair(2, config, atlas)
  for key in ('left', 'right', 'disparity_left', 'nonocc_left'):
    np.testing.assert_array_equal(again[key], pairs[2][key])
  # A match outside the right view is never marked visible.
  for p in pairs:
    x = np.arange(96)[None] - p['disparity_left']
    assert not (p['nonocc_left'] & ((x < 0) | (x > 95))).any()


@pytest.mark.parametrize('field, value', [('zoom_range', (0.0, 1.0)),
                                          ('object_probability', 1.5),
                                          ('max_disparity', 2)])
def test_bad_config_names_the_field(field, value):
  with pytest.raises(ValueError):
    photo_warps.WarpConfig(**{field: value})


@pytest.mark.parametrize('name', ['Teddy.png', 'tsukuba_left.png', '000151_10.png',
                                  'motorcycle_im0.png', 'sceneflow_a.png'])
def test_evaluation_images_are_refused_as_photographs(tmp_path, name):
  (tmp_path / 'Dune.jpg').write_bytes(b'')
  (tmp_path / name).write_bytes(b'')
  with pytest.raises(ValueError, match=name):
    photo_warps.refuse_evaluation_photos(str(tmp_path))


def test_ordinary_photographs_pass_the_guard(tmp_path):
  for name in ('Dune.jpg', 'Kleiber_by_Lukas_Baubkus.jpg', '2004default.jpg'):
    (tmp_path / name).write_bytes(b'')
  photo_warps.refuse_evaluation_photos(str(tmp_path))


def test_without_photo_warps_the_same_geometry_keeps_its_drawn_textures(atlas):
  warped = photo_warps.WarpConfig(height=48, width=96, max_disparity=32, window_probability=0)
  procedural = photo_warps.WarpConfig(height=48, width=96, max_disparity=32,
                                      window_probability=0, photo_warps=False)
  for seed in range(3):
    a, b = (photo_warps.warped_pair(seed, c, atlas) for c in (warped, procedural))
    np.testing.assert_array_equal(a['disparity_left'], b['disparity_left'])
    assert np.abs(a['left'].astype(float) - b['left']).mean() > 5.0  # Other textures.
    assert _warp_error(b) < 2.0  # Still exact correspondences.
