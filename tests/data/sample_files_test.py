"""Tests for mixstereo_tf.data.sample_files on tiny files written into tmp_path."""

import numpy as np
import pytest

from mixstereo_tf.data import records
from mixstereo_tf.data import sample_files
from mixstereo_tf.data import sources
from tests import data_helpers

_write = data_helpers.write_image
_rgb = data_helpers.random_rgb


def _sample_files(tmp_path, height=8, width=12):
  left = _write(tmp_path / 'l.png', _rgb(height, width, 1)[:, :, ::-1])
  right = _write(tmp_path / 'r.png', _rgb(height, width, 2)[:, :, ::-1])
  return left, right


def test_load_sample_keys_dtypes_and_masks(tmp_path):
  left, right = _sample_files(tmp_path)
  disp = np.zeros((8, 12), np.uint16)
  disp[:, 4:] = 256 * 3
  all_mask = np.full((8, 12), 255, np.uint8)
  all_mask[:, -1] = 0
  nonocc = np.full((8, 12), 255, np.uint8)
  nonocc[0] = 128
  disc = np.zeros((8, 12), np.uint8)
  disc[:, 2:6] = 255
  disc[:, 6] = 128
  sample = records.StereoSample(
      'a', left, right, disparity_left=_write(tmp_path / 'd.png', disp), disparity_scale=256,
      all_left=_write(tmp_path / 'all.png', all_mask),
      nonocc_left=_write(tmp_path / 'noc.png', nonocc),
      disc_left=_write(tmp_path / 'disc.png', disc), source='list.txt:3')
  loaded = sources.load_sample(sample)
  assert set(loaded) == set(records.LOADED_KEYS)
  for key, dtype in records.LOADED_KEYS.items():
    assert loaded[key].dtype == dtype, key
    assert loaded[key].shape[:2] == (8, 12), key
  np.testing.assert_array_equal(loaded['left'], _rgb(8, 12, 1))
  expected_valid = np.zeros((8, 12), bool)
  expected_valid[:, 4:11] = True
  np.testing.assert_array_equal(loaded['valid_left'], expected_valid)
  np.testing.assert_array_equal(loaded['disparity_left'], np.where(expected_valid, 3.0, 0.0))
  disc_expected = expected_valid & (disc == 255)  # Columns 4-5: GT known and white.
  assert disc_expected[:, 4:6].all() and disc_expected.sum() == 16
  np.testing.assert_array_equal(loaded['disc_left'], disc_expected)
  expected_valid[0] = False
  np.testing.assert_array_equal(loaded['nonocc_left'], expected_valid)
  assert not loaded['valid_right'].any() and not loaded['disparity_right'].any()


def test_load_sample_without_gt_or_masks(tmp_path):
  left, right = _sample_files(tmp_path)
  pfm = str(tmp_path / 'd.pfm')
  data_helpers.write_pfm(pfm, np.ones((8, 12), np.float32))
  loaded = sample_files.load_file_sample(records.StereoSample('a', left, right))
  assert not loaded['valid_left'].any() and not loaded['nonocc_left'].any()
  assert not loaded['disc_left'].any()
  loaded = sample_files.load_file_sample(records.StereoSample('a', left, right,
                                                          disparity_right=pfm))
  assert loaded['valid_right'].all() and loaded['nonocc_left'].sum() == 0


def test_load_sample_size_mismatches_name_the_files(tmp_path):
  left, _ = _sample_files(tmp_path)
  small = _write(tmp_path / 'small.png', _rgb(8, 10))
  with pytest.raises(ValueError, match=r'scene7.*l\.png.*small\.png'):
    sample_files.load_file_sample(records.StereoSample('a', left, small, source='scene7'))
  disp = _write(tmp_path / 'disp.png', np.zeros((4, 12), np.uint16))
  with pytest.raises(ValueError, match=r'scene7.*disp\.png'):
    sample_files.load_file_sample(records.StereoSample('a', left, left, disparity_left=disp,
                                                   source='scene7'))
  disc = _write(tmp_path / 'disc.png', np.zeros((8, 10), np.uint8))
  with pytest.raises(ValueError, match=r'scene7.*mask .*disc\.png'):
    sample_files.load_file_sample(records.StereoSample('a', left, left, disc_left=disc,
                                                   source='scene7'))
  with pytest.raises(ValueError, match=r'scene7.*gone\.png'):
    sample_files.load_file_sample(records.StereoSample('a', left, str(tmp_path / 'gone.png'),
                                                   source='scene7'))


def test_fit_factor_is_the_smallest_that_fits():
  assert [sample_files.fit_factor(d, 8) for d in (0, 7, 7.01, 37.25)] == [1, 1, 2, 6]
  with pytest.raises(ValueError, match='fit_disparity'):
    sample_files.fit_factor(3, 1)


def test_shrink_averages_views_and_keeps_ground_truth_only_where_a_block_is_known():
  views = np.arange(16, dtype=np.uint8).reshape(4, 4, 1).repeat(3, axis=2)
  disparity = np.full((4, 4), 6, np.float32)
  valid = np.ones((4, 4), bool)
  valid[0, 0], disparity[0, 0] = False, 0
  disc = np.zeros((4, 4), bool)
  disc[3, 3] = True
  loaded = {'left': views, 'right': views, 'disparity_left': disparity,
            'disparity_right': disparity, 'valid_left': valid, 'valid_right': valid,
            'nonocc_left': valid, 'disc_left': disc}
  out = sample_files.shrink(loaded, 2)
  np.testing.assert_array_equal(out['left'][..., 0], [[2, 4], [10, 12]])  # rint(2.5) = 2.
  np.testing.assert_array_equal(out['valid_left'], [[False, True], [True, True]])
  np.testing.assert_array_equal(out['disparity_left'], [[0, 3], [3, 3]])
  np.testing.assert_array_equal(out['disc_left'], [[False, False], [False, True]])
  assert sample_files.shrink(loaded, 1) is loaded
