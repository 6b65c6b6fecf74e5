"""Tests for mixstereo_tf.data.image_io on tiny files written into tmp_path."""

import os
import struct
import subprocess
import sys
import zlib

import numpy as np
from PIL import Image
import pillow_heif
import pytest

from mixstereo_tf.data import image_io
from tests import data_helpers

_write = data_helpers.write_image
_rgb = data_helpers.random_rgb


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
           'lossless.webp': dict(lossless=True), 'plain.png': {},
           '420.heic': dict(quality=90), '444.heic': dict(quality=90, chroma=444),
           '420.avif': dict(quality=90, subsampling='4:2:0'),
           '444.avif': dict(quality=90, subsampling='4:4:4')}
  for name, options in saved.items():
    image.save(tmp_path / name, **options)
  (tmp_path / 'broken.jpg').write_bytes(b'\xff\xd8 not a jpeg')
  assert {name: image_io.chroma_halved(str(tmp_path / name))
          for name in list(saved) + ['broken.jpg']} == {
              '420.jpg': True, '422.jpg': True, '444.jpg': False, 'lossy.webp': True,
              'lossless.webp': False, 'plain.png': False, 'broken.jpg': False,
              '420.heic': True, '444.heic': False, '420.avif': True, '444.avif': False}


def test_an_avif_that_this_pillow_cannot_read_says_why(tmp_path, monkeypatch):
  Image.fromarray(np.zeros((8, 8, 3), np.uint8)).save(tmp_path / 'a.avif')
  monkeypatch.setattr(image_io.features, 'check', lambda name: False)
  monkeypatch.setattr(image_io, '_read_with_pillow', lambda path: None)
  monkeypatch.setattr(image_io.cv2, 'imread', lambda path, flags: None)
  with pytest.raises(ValueError, match=r'a\.avif \(neither this OpenCV nor this Pillow '
                     r'reads AVIF: newer versions of both do\)'):
    image_io.read_raw(str(tmp_path / 'a.avif'))


def test_heif_and_avif_photos_are_read_and_a_10_bit_heif_at_16_bits(tmp_path):
  """Phones' HEIC (pillow-heif) and AVIF (Pillow) are read as RGB; a 10-bit HEIF as uint16
  with its samples scaled to 0-65535 (1023 -> 65535), not shifted (1023 -> 65472)."""
  rgb = np.zeros((16, 24, 3), np.uint8)
  rgb[:, :12] = (200, 40, 90)
  rgb[:, 12:] = (30, 160, 220)
  for name in ('photo.heic', 'photo.avif'):
    Image.fromarray(rgb).save(tmp_path / name, quality=100)
    read = image_io.read_image(str(tmp_path / name)).astype(int)
    away = np.abs(read - rgb)[:, np.r_[2:9, 15:22]]  # From the colour edge (4:2:0).
    assert read.shape == rgb.shape and away.max() <= 6, (name, away.max())
  ramp = np.linspace(0.0, 1.0, 16 * 24 * 3).reshape(16, 24, 3)
  deep = np.rint(ramp * 65535).astype(np.uint16)
  pillow_heif.from_bytes(mode='RGB;16', size=(24, 16), data=deep.tobytes()).save(
      str(tmp_path / 'ten.heic'), quality=-1)  # Lossless in YUV, 10 bits.
  read = image_io.read_raw(str(tmp_path / 'ten.heic'))[..., ::-1]  # BGR, as cv2.imread.
  assert read.dtype == np.uint16 and read.max() == 65535
  assert np.abs(read.astype(float) - deep).max() <= 3 * 64  # 3 10-bit steps (via YUV).


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


@pytest.mark.parametrize('dtype, channels, alpha, expected', [
    (np.uint8, 3, None, ()), (np.uint8, 4, 255, ()), (np.uint8, 4, 254, ('alpha',)),
    (np.uint8, 2, 0, ('alpha',)), (np.uint16, 1, None, ('bit_depth',)),
    (np.uint16, 4, 65535, ('bit_depth',)), (np.uint16, 4, 65534, ('bit_depth', 'alpha'))])
def test_dropped_names_what_reading_at_8_bits_in_rgb_loses(dtype, channels, alpha,
                                                           expected):
  array = np.full((3, 4, channels), 7, dtype)
  if alpha is not None:
    array[..., -1] = np.iinfo(dtype).max
    array[1, 2, -1] = alpha  # One pixel decides: an opaque channel loses nothing.
  raw = array[..., 0] if channels == 1 else array
  assert image_io.dropped(raw) == expected
  assert image_io.as_rgb8(raw, 'x.png').shape == (3, 4, 3)


def test_reading_images_does_not_import_tensorflow():
  """The readers (and `core.image_range`'s 16-bit conversions they use) stay light."""
  code = ('import sys\nfrom mixstereo_tf.cli import input_images\n'
          'from mixstereo_tf.data import image_io\n'
          "print('tensorflow' in sys.modules)")
  result = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          timeout=120, check=True)
  assert result.stdout.strip() == 'False'
