"""Tests of the real stereo pairs as training crops: occlusion, layouts, the evaluation
guard and crops whose disparities match their views."""

import os

import cv2
import numpy as np
import pytest

from mixstereo_tf.data import real_pairs


def _write_pfm(path, array):
  with open(path, 'wb') as f:
    f.write(b'Pf\n%d %d\n-1.0\n' % (array.shape[1], array.shape[0]))
    f.write(np.ascontiguousarray(array[::-1], '<f4').tobytes())


def _pair(height=96, width=320, shift=9, seed=0):
  """A textured pair whose left view is the right one shifted by `shift` px (left x shows
  right x - shift), plus a nearer square (disparity 2 shift) occluding the background."""
  rng = np.random.default_rng(seed)
  texture = cv2.GaussianBlur(rng.uniform(0, 255, (height, width + 80, 3)), (0, 0), 1.5)
  right = texture[:, 40:40 + width].astype(np.uint8)
  disparity = np.full((height, width), float(shift), np.float32)
  left = np.zeros_like(right)
  cols = np.arange(width)
  left[:] = texture[:, 40 + cols - shift].astype(np.uint8)
  return {'left': left, 'right': right, 'disparity_left': disparity}


def test_a_nearer_surface_occludes_the_pixels_just_left_of_it():
  disparity = np.full((1, 12), 1.0, np.float32)
  disparity[0, 6:9] = 4.0  # Lands on right x 2..4, over background pixels 3..5 (-> 2..4).
  valid = np.ones_like(disparity, bool)
  occluded = real_pairs.occluded_left(disparity, valid)
  np.testing.assert_array_equal(np.nonzero(occluded[0])[0], [3, 4, 5])
  # Sparse truth: only known pixels occlude and are occluded.
  valid[0, 6] = valid[0, 7] = False
  np.testing.assert_array_equal(np.nonzero(real_pairs.occluded_left(disparity, valid)[0])[0],
                                [5])


@pytest.mark.parametrize('name', ['kitti2015_aanet_000151', '000151_10', 'Teddy',
                                  'cones-2003', 'tsukuba'])
def test_evaluation_sources_are_refused_by_name(tmp_path, name):
  with pytest.raises(ValueError, match=f'{name}.*evaluation data'):
    real_pairs.load(str(tmp_path / name))


def test_a_sceneflow_folder_loads_with_its_occlusion_mask(tmp_path):
  pair = _pair()
  for key in ('left', 'right'):
    cv2.imwrite(str(tmp_path / f'{key}.png'), pair[key][..., ::-1])
  _write_pfm(str(tmp_path / 'disp_left.pfm'), pair['disparity_left'])
  occlusion = np.zeros(pair['disparity_left'].shape, np.uint8)
  occlusion[:, :5] = 255
  cv2.imwrite(str(tmp_path / 'occ_left.png'), occlusion)
  loaded = real_pairs.load(str(tmp_path))
  np.testing.assert_array_equal(loaded['left'], pair['left'])
  assert not loaded['nonocc_left'][:, :5].any() and loaded['nonocc_left'][:, 5:].all()
  os.remove(tmp_path / 'disp_left.pfm')
  with pytest.raises(ValueError, match=f'{tmp_path}.*disp_left.pfm'):
    real_pairs.load(str(tmp_path))


def test_motorcycle_loads_with_occlusions_found_from_its_truth():
  pair = real_pairs.load('motorcycle')
  assert pair['left'].shape == (500, 741, 3)
  assert 0.75 < pair['nonocc_left'].mean() < 0.93  # 93% finite, some occluded.


@pytest.mark.parametrize('window', [0.0, 1.0])
def test_crops_keep_their_views_matched_at_scaled_signed_disparities(window):
  pair = _pair(shift=20)
  pair['nonocc_left'] = np.ones(pair['disparity_left'].shape, bool)
  pair['nonocc_left'][:, :20] = False  # Their match lies outside the right view.
  rng = np.random.default_rng(3)
  for _ in range(4):
    crop = real_pairs.crop(rng, pair, 32, 64, 16, window)
    assert crop['left'].shape == crop['right'].shape == (32, 64, 3)
    d = crop['disparity_left'][crop['nonocc_left']]
    # 0.8 * 16 / 20: scaled by 0.32-0.64 (never below 32 / 96 rows, 65 / 320 cols).
    assert np.ptp(d) < 1e-4 and (d[0] < 12.9 if window == 0 else d[0] < 0.75 * 12.9)
    ys, xs = np.nonzero(crop['nonocc_left'])
    match = np.round(xs - crop['disparity_left'][ys, xs]).astype(int)
    inside = (match >= 0) & (match < 64)
    left, right = crop['left'].astype(float), crop['right'].astype(float)
    error = np.abs(left[ys[inside], xs[inside]] - right[ys[inside], match[inside]]).mean()
    wrong = np.abs(left[ys[inside], xs[inside]]
                   - right[ys[inside], np.clip(match[inside] + 3, 0, 63)]).mean()
    assert error < 0.4 * wrong


def test_a_folder_without_visible_ground_truth_is_refused_by_name(tmp_path):
  pair = _pair()
  for key in ('left', 'right'):
    cv2.imwrite(str(tmp_path / f'{key}.png'), pair[key][..., ::-1])
  _write_pfm(str(tmp_path / 'disp_left.pfm'), np.full(pair['disparity_left'].shape, np.inf,
                                                      np.float32))
  with pytest.raises(ValueError, match=f'{tmp_path} has no visible pixel'):
    real_pairs.load(str(tmp_path))
