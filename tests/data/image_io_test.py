"""Tests for mixstereo_tf.data.image_io on tiny files written into tmp_path."""

import os
import struct
import zlib

import cv2
import numpy as np
from PIL import Image
import pytest

from mixstereo_tf.data import image_io
from mixstereo_tf.data import records
from mixstereo_tf.data import sources
from tests import data_helpers


def _write(path, array):
  assert cv2.imwrite(str(path), array), path
  return str(path)


def _palette_png(path, palette, indices):
  """Writes an indexed-colour (PNG colour type 3) file by hand, without PIL."""
  def chunk(kind, data):
    return (struct.pack('>I', len(data)) + kind + data
            + struct.pack('>I', zlib.crc32(kind + data) & 0xffffffff))
  height, width = indices.shape
  raw = b''.join(b'\x00' + row.astype(np.uint8).tobytes() for row in indices)
  with open(path, 'wb') as f:
    f.write(b'\x89PNG\r\n\x1a\n'
            + chunk(b'IHDR', struct.pack('>IIBBBBB', width, height, 8, 3, 0, 0, 0))
            + chunk(b'PLTE', bytes(np.asarray(palette, np.uint8).ravel()))
            + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))
  return str(path)


def _rgb(height=8, width=12, seed=0):
  return np.random.default_rng(seed).integers(0, 256, (height, width, 3), dtype=np.uint8)


@pytest.mark.parametrize('ext', ['.png', '.ppm', '.jpg'])
def test_read_image_returns_rgb(tmp_path, ext):
  rgb = _rgb()
  path = _write(tmp_path / f'a{ext}', rgb[:, :, ::-1])  # cv2 writes BGR.
  image = image_io.read_image(path)
  assert image.dtype == np.uint8 and image.shape == (8, 12, 3)
  if ext == '.jpg':  # Lossy: only check the channel order survived.
    error = np.abs(image.astype(int) - rgb).mean()
    assert error < np.abs(image.astype(int) - rgb[..., ::-1]).mean()
  else:
    np.testing.assert_array_equal(image, rgb)


@pytest.mark.parametrize('ext', ['.png', '.pgm'])
def test_gray_becomes_three_equal_channels(tmp_path, ext):
  gray = _rgb()[:, :, 0]
  image = image_io.read_image(_write(tmp_path / f'g{ext}', gray))
  for c in range(3):
    np.testing.assert_array_equal(image[:, :, c], gray)


def test_rgba_drops_alpha(tmp_path):
  rgb = _rgb()
  bgra = np.concatenate([rgb[:, :, ::-1], np.full((8, 12, 1), 7, np.uint8)], axis=2)
  np.testing.assert_array_equal(image_io.read_image(_write(tmp_path / 'a.png', bgra)), rgb)


def test_palette_png_is_expanded(tmp_path):
  palette = [[255, 0, 0], [0, 255, 0], [10, 20, 30]]
  indices = np.array([[0, 1, 2], [2, 1, 0]])
  image = image_io.read_image(_palette_png(tmp_path / 'p.png', palette, indices))
  np.testing.assert_array_equal(image, np.asarray(palette, np.uint8)[indices])


def test_16_bit_scaled_by_257_with_rounding(tmp_path):
  values = np.array([[0, 65535, 257 * 3, 257 * 3 + 128, 257 * 3 + 129]], np.uint16)
  image = image_io.read_image(_write(tmp_path / 'g16.png', values))
  np.testing.assert_array_equal(image[0, :, 1], [0, 255, 3, 3, 4])
  color = np.zeros((1, 1, 3), np.uint16)
  color[0, 0] = [257 * 10, 257 * 20, 257 * 30]  # BGR on disk.
  np.testing.assert_array_equal(
      image_io.read_image(_write(tmp_path / 'c16.ppm', color))[0, 0], [30, 20, 10])


def test_missing_and_undecodable_images_name_the_path(tmp_path):
  missing = str(tmp_path / 'nope.png')
  with pytest.raises(ValueError, match='nope.png'):
    image_io.read_image(missing)
  junk = tmp_path / 'junk.png'
  junk.write_bytes(b'not an image')
  with pytest.raises(ValueError, match='Cannot decode.*junk.png'):
    image_io.read_image(str(junk))


def test_find_image_swaps_jpg_and_png(tmp_path):
  png = _write(tmp_path / 'x.png', _rgb())
  jpg = _write(tmp_path / 'y.jpg', _rgb())
  assert image_io.find_image(png) == png
  assert image_io.find_image(str(tmp_path / 'x.jpg')) == png
  assert image_io.find_image(str(tmp_path / 'y.png')) == jpg
  with pytest.raises(ValueError, match=r'z\.jpg.*tried.*z\.jpg.*z\.png'):
    image_io.find_image(str(tmp_path / 'z.jpg'))


def test_pfm_round_trip_keeps_inf_nan_and_row_order(tmp_path):
  gray = np.arange(12, dtype=np.float32).reshape(3, 4) - 2.5
  gray[0, 0], gray[2, 3] = np.inf, np.nan
  path = str(tmp_path / 'd.pfm')
  data_helpers.write_pfm(path, gray)
  np.testing.assert_array_equal(image_io.read_pfm(path), gray)  # NaN == NaN here.
  color = np.random.default_rng(1).normal(size=(2, 5, 3)).astype(np.float32)
  data_helpers.write_pfm(path, color)
  np.testing.assert_array_equal(image_io.read_pfm(path), color)


def test_pfm_big_endian_bottom_to_top(tmp_path):
  # Positive scale = big-endian; the first stored row is the bottom image row.
  path = tmp_path / 'be.pfm'
  path.write_bytes(b'Pf\n2 2\n1.0\n' + np.array([3, 4, 1, 2], '>f4').tobytes())
  np.testing.assert_array_equal(image_io.read_pfm(str(path)), [[1, 2], [3, 4]])


def test_pfm_bad_input(tmp_path):
  path = tmp_path / 'short.pfm'
  path.write_bytes(b'Pf\n4 4\n-1.0\n' + b'\0' * 8)
  with pytest.raises(ValueError, match='Truncated.*short.pfm'):
    image_io.read_pfm(str(path))
  path.write_bytes(b'P6\n4 4\n255\n')
  with pytest.raises(ValueError, match='header.*short.pfm'):
    image_io.read_pfm(str(path))


def test_kitti_16_bit_disparity(tmp_path):
  stored = np.array([[256 * 5, 0], [256 * 7 + 128, 1]], np.uint16)
  disparity, valid = image_io.read_disparity(_write(tmp_path / 'd.png', stored), 256.0)
  assert disparity.dtype == np.float32
  np.testing.assert_allclose(disparity, [[5, 0], [7.5, 1 / 256]])
  np.testing.assert_array_equal(valid, [[True, False], [True, True]])
  # Saved as 8 bits by mistake: every disparity would read below 1 px.
  eight = _write(tmp_path / 'd8.png', np.array([[200, 0]], np.uint8))
  with pytest.raises(ValueError, match=r'd8.png is an 8-bit image.*at most 1.00 px'):
    image_io.read_disparity(eight, 256.0)


def test_8_bit_and_pfm_disparity(tmp_path):
  pgm = _write(tmp_path / 'truedisp.pgm', np.array([[80, 0, 16]], np.uint8))
  disparity, valid = image_io.read_disparity(pgm, 16.0)
  np.testing.assert_allclose(disparity, [[5, 0, 1]])
  np.testing.assert_array_equal(valid, [[True, False, True]])
  pfm = str(tmp_path / 'disp0.pfm')
  data_helpers.write_pfm(pfm, np.array([[2.5, np.inf, np.nan, 0.0]], np.float32))
  disparity, valid = image_io.read_disparity(pfm)
  np.testing.assert_array_equal(disparity, [[2.5, 0, 0, 0]])
  np.testing.assert_array_equal(valid, [[True, False, False, False]])
  with pytest.raises(ValueError, match='positive.*disp0.pfm'):
    image_io.read_disparity(pfm, 0.0)
  color = _write(tmp_path / 'c.png', _rgb())
  with pytest.raises(ValueError, match='single-channel.*c.png'):
    image_io.read_disparity(color, 1.0)


def test_read_mask(tmp_path):
  mask = image_io.read_mask(_write(tmp_path / 'm.png', np.array([[255, 128, 0]], np.uint8)))
  np.testing.assert_array_equal(mask, [[True, False, False]])
  noc = image_io.read_mask(_write(tmp_path / 'noc.png', np.array([[0, 1, 300]], np.uint16)))
  np.testing.assert_array_equal(noc, [[False, True, True]])


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
  loaded = image_io.load_file_sample(records.StereoSample('a', left, right))
  assert not loaded['valid_left'].any() and not loaded['nonocc_left'].any()
  assert not loaded['disc_left'].any()
  loaded = image_io.load_file_sample(records.StereoSample('a', left, right,
                                                          disparity_right=pfm))
  assert loaded['valid_right'].all() and loaded['nonocc_left'].sum() == 0


def test_load_sample_size_mismatches_name_the_files(tmp_path):
  left, _ = _sample_files(tmp_path)
  small = _write(tmp_path / 'small.png', _rgb(8, 10))
  with pytest.raises(ValueError, match=r'scene7.*l\.png.*small\.png'):
    image_io.load_file_sample(records.StereoSample('a', left, small, source='scene7'))
  disp = _write(tmp_path / 'disp.png', np.zeros((4, 12), np.uint16))
  with pytest.raises(ValueError, match=r'scene7.*disp\.png'):
    image_io.load_file_sample(records.StereoSample('a', left, left, disparity_left=disp,
                                                   source='scene7'))
  disc = _write(tmp_path / 'disc.png', np.zeros((8, 10), np.uint8))
  with pytest.raises(ValueError, match=r'scene7.*mask .*disc\.png'):
    image_io.load_file_sample(records.StereoSample('a', left, left, disc_left=disc,
                                                   source='scene7'))
  with pytest.raises(ValueError, match=r'scene7.*gone\.png'):
    image_io.load_file_sample(records.StereoSample('a', left, str(tmp_path / 'gone.png'),
                                                   source='scene7'))


def test_fit_factor_is_the_smallest_that_fits():
  assert [image_io.fit_factor(d, 8) for d in (0, 7, 7.01, 37.25)] == [1, 1, 2, 6]
  with pytest.raises(ValueError, match='fit_disparity'):
    image_io.fit_factor(3, 1)


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
  out = image_io.shrink(loaded, 2)
  np.testing.assert_array_equal(out['left'][..., 0], [[2, 4], [10, 12]])  # rint(2.5) = 2.
  np.testing.assert_array_equal(out['valid_left'], [[False, True], [True, True]])
  np.testing.assert_array_equal(out['disparity_left'], [[0, 3], [3, 3]])
  np.testing.assert_array_equal(out['disc_left'], [[False, False], [False, True]])
  assert image_io.shrink(loaded, 1) is loaded


def test_a_missing_or_folder_path_says_where_it_was_looked_for(tmp_path, monkeypatch):
  monkeypatch.chdir(tmp_path)
  with pytest.raises(ValueError, match=r'File not found: b/a1.png \(relative to the current '
                                       f'folder {tmp_path}\\)'):
    image_io.read_image('b/a1.png')
  with pytest.raises(ValueError, match=r'File not found: /no/such.png$'):
    image_io.read_image('/no/such.png')
  with pytest.raises(ValueError, match='is a folder, not an image file'):
    image_io.read_image(str(tmp_path))


def test_chroma_halved_names_files_stored_with_half_resolution_colour(tmp_path):
  image = Image.fromarray(np.random.default_rng(0).integers(0, 256, (16, 24, 3), np.uint8))
  saved = {'420.jpg': dict(quality=90), '422.jpg': dict(subsampling=1),
           '444.jpg': dict(subsampling=0), 'lossy.webp': dict(quality=80),
           'lossless.webp': dict(lossless=True), 'plain.png': {}}
  for name, options in saved.items():
    image.save(tmp_path / name, **options)
  (tmp_path / 'broken.jpg').write_bytes(b'\xff\xd8 not a jpeg')
  assert {name: image_io.chroma_halved(str(tmp_path / name))
          for name in list(saved) + ['broken.jpg']} == {
              '420.jpg': True, '422.jpg': True, '444.jpg': False, 'lossy.webp': True,
              'lossless.webp': False, 'plain.png': False, 'broken.jpg': False}


def test_a_tiff_opencv_cannot_read_is_read_without_opencvs_error_lines(tmp_path, capfd):
  """OpenCV fails on TIFFs whose orientation tag transposes (5-8) and printed an ERROR
  block although Pillow then read the file right."""
  stored = np.zeros((4, 6, 3), np.uint8)
  stored[0, :, 0] = 255  # The stored top row, red.
  Image.fromarray(stored).save(tmp_path / 'turned.tif', tiffinfo={274: 6})
  image = image_io.read_image(str(tmp_path / 'turned.tif'))
  assert image.shape == (6, 4, 3) and image[:, -1, 0].min() == 255  # Turned: right column.
  assert capfd.readouterr().err == ''


def test_a_file_name_that_is_no_utf8_is_read_and_written(tmp_path):
  """OpenCV crashed (a segmentation fault, the whole run lost) on such names."""
  path = os.path.join(str(tmp_path), os.fsdecode(b'caf\xe9.png'))
  image = np.arange(4 * 6 * 3, dtype=np.uint8).reshape(4, 6, 3)
  assert image_io.write_with_opencv(path, image[..., ::-1])
  np.testing.assert_array_equal(image_io.read_image(path), image)
