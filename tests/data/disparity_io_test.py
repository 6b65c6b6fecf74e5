"""Tests for mixstereo_tf.data.disparity_io on tiny files written into tmp_path."""

import numpy as np
import pytest

from mixstereo_tf.data import disparity_io
from tests import data_helpers

_write = data_helpers.write_image
_rgb = data_helpers.random_rgb


def test_pfm_round_trip_keeps_inf_nan_and_row_order(tmp_path):
  gray = np.arange(12, dtype=np.float32).reshape(3, 4) - 2.5
  gray[0, 0], gray[2, 3] = np.inf, np.nan
  path = str(tmp_path / 'd.pfm')
  data_helpers.write_pfm(path, gray)
  np.testing.assert_array_equal(disparity_io.read_pfm(path), gray)  # NaN == NaN here.
  color = np.random.default_rng(1).normal(size=(2, 5, 3)).astype(np.float32)
  data_helpers.write_pfm(path, color)
  np.testing.assert_array_equal(disparity_io.read_pfm(path), color)


def test_pfm_big_endian_bottom_to_top(tmp_path):
  # Positive scale = big-endian; the first stored row is the bottom image row.
  path = tmp_path / 'be.pfm'
  path.write_bytes(b'Pf\n2 2\n1.0\n' + np.array([3, 4, 1, 2], '>f4').tobytes())
  np.testing.assert_array_equal(disparity_io.read_pfm(str(path)), [[1, 2], [3, 4]])


def test_pfm_bad_input(tmp_path):
  path = tmp_path / 'short.pfm'
  path.write_bytes(b'Pf\n4 4\n-1.0\n' + b'\0' * 8)
  with pytest.raises(ValueError, match='Truncated.*short.pfm'):
    disparity_io.read_pfm(str(path))
  path.write_bytes(b'P6\n4 4\n255\n')
  with pytest.raises(ValueError, match='header.*short.pfm'):
    disparity_io.read_pfm(str(path))


def test_kitti_16_bit_disparity(tmp_path):
  stored = np.array([[256 * 5, 0], [256 * 7 + 128, 1]], np.uint16)
  disparity, valid = disparity_io.read_disparity(_write(tmp_path / 'd.png', stored), 256.0)
  assert disparity.dtype == np.float32
  np.testing.assert_allclose(disparity, [[5, 0], [7.5, 1 / 256]])
  np.testing.assert_array_equal(valid, [[True, False], [True, True]])
  # Saved as 8 bits by mistake: every disparity would read below 1 px.
  eight = _write(tmp_path / 'd8.png', np.array([[200, 0]], np.uint8))
  with pytest.raises(ValueError, match=r'd8.png is an 8-bit image.*at most 1.00 px'):
    disparity_io.read_disparity(eight, 256.0)


def test_8_bit_and_pfm_disparity(tmp_path):
  pgm = _write(tmp_path / 'truedisp.pgm', np.array([[80, 0, 16]], np.uint8))
  disparity, valid = disparity_io.read_disparity(pgm, 16.0)
  np.testing.assert_allclose(disparity, [[5, 0, 1]])
  np.testing.assert_array_equal(valid, [[True, False, True]])
  pfm = str(tmp_path / 'disp0.pfm')
  data_helpers.write_pfm(pfm, np.array([[2.5, np.inf, np.nan, 0.0]], np.float32))
  disparity, valid = disparity_io.read_disparity(pfm)
  np.testing.assert_array_equal(disparity, [[2.5, 0, 0, 0]])
  np.testing.assert_array_equal(valid, [[True, False, False, False]])
  with pytest.raises(ValueError, match='positive.*disp0.pfm'):
    disparity_io.read_disparity(pfm, 0.0)
  color = _write(tmp_path / 'c.png', _rgb())
  with pytest.raises(ValueError, match='single-channel.*c.png'):
    disparity_io.read_disparity(color, 1.0)


def test_read_mask(tmp_path):
  mask = disparity_io.read_mask(_write(tmp_path / 'm.png', np.array([[255, 128, 0]], np.uint8)))
  np.testing.assert_array_equal(mask, [[True, False, False]])
  noc = disparity_io.read_mask(_write(tmp_path / 'noc.png', np.array([[0, 1, 300]], np.uint16)))
  np.testing.assert_array_equal(noc, [[False, True, True]])
