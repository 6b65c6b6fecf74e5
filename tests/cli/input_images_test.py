"""Tests for mixstereo_tf.cli.input_images: reading input images upright, their headers."""

import logging

import cv2
import numpy as np
from PIL import Image
import pillow_heif
import pytest

from mixstereo_tf.cli import input_images
from mixstereo_tf.cli import input_listing
from mixstereo_tf.cli import mpo
from mixstereo_tf.data import image_io


def test_gif_images_are_inputs_and_animated_ones_are_refused(tmp_path):
  rng = np.random.default_rng(0)
  frames = [rng.integers(0, 256, (12, 16, 3), dtype=np.uint8) for _ in range(2)]
  Image.fromarray(frames[0]).save(tmp_path / 'still.gif')
  Image.fromarray(frames[0]).save(tmp_path / 'wiggle.gif', save_all=True,
                                  append_images=[Image.fromarray(frames[1])], loop=0)
  items = list(input_listing.iter_inputs(str(tmp_path)))
  assert [i.name for i in items] == ['still', 'wiggle']
  expected = np.asarray(Image.open(tmp_path / 'still.gif').convert('RGB'))
  np.testing.assert_array_equal(input_images.read_image(str(tmp_path / 'still.gif')), expected)
  with pytest.raises(ValueError, match=r'wiggle\.gif is an animated image \(2 frames\)'):
    input_images.read_image(str(tmp_path / 'wiggle.gif'))


@pytest.mark.parametrize('orientation, stored', [(6, Image.ROTATE_90), (8, Image.ROTATE_270),
                                                  (3, Image.ROTATE_180),
                                                  (2, Image.FLIP_LEFT_RIGHT)])
def test_rotated_tiff_reads_upright(tmp_path, orientation, stored):
  # TIFF decoders apply the orientation tag themselves; OpenCV 5.0 cannot decode the
  # tags that transpose (6, 8), which Pillow then reads. The tag is applied once.
  upright = np.random.default_rng(orientation).integers(0, 256, (12, 16, 3), dtype=np.uint8)
  for name in (f'phone_{orientation}.tiff', f'misnamed_{orientation}.jpg'):
    path = str(tmp_path / name)  # By its format, not its extension.
    Image.fromarray(upright).transpose(stored).save(path, format='TIFF',
                                                    tiffinfo={0x0112: orientation})
    image, found, _ = input_images.read_upright(path)
    assert found == orientation
    np.testing.assert_array_equal(image, upright)


@pytest.mark.parametrize('orientation', range(1, 9))
def test_read_upright_applies_the_exif_orientation_as_opencv_does(tmp_path, orientation):
  """OpenCV's colour reader applies EXIF orientation itself: an independent reference."""
  stored = np.zeros((12, 20, 3), np.uint8)
  stored[:4, :4] = 255  # A corner mark: every turn and mirror moves it.
  stored[:, 10:, 1] = 120
  exif = Image.Exif()
  exif[0x0112] = orientation
  path = str(tmp_path / 'phone.jpg')
  Image.fromarray(stored).save(path, exif=exif, quality=100)
  image, found, _ = input_images.read_upright(path)
  reference = cv2.imread(path, cv2.IMREAD_COLOR)[..., ::-1]
  assert found == orientation and image.shape == reference.shape
  assert image.shape[:2] == ((20, 12) if orientation >= 5 else (12, 20))
  assert np.abs(image.astype(int) - reference).max() <= 2


def test_truncated_jpeg_is_told_apart(tmp_path):
  image = np.random.default_rng(0).integers(0, 256, (64, 64, 3), dtype=np.uint8)
  whole = str(tmp_path / 'whole.jpg')
  cv2.imwrite(whole, image)
  data = open(whole, 'rb').read()
  (tmp_path / 'padded.jpg').write_bytes(data + b'\x00' * 10)
  (tmp_path / 'cut.jpg').write_bytes(data[:len(data) * 2 // 3])
  assert not input_images.truncated_jpeg(whole)
  assert not input_images.truncated_jpeg(str(tmp_path / 'padded.jpg'))
  assert input_images.truncated_jpeg(str(tmp_path / 'cut.jpg'))
  assert input_images.read_image(str(tmp_path / 'cut.jpg')).shape == (64, 64, 3)  # Still read.
  cv2.imwrite(str(tmp_path / 'a.png'), np.full((8, 10, 3), 10, np.uint8))
  assert not input_images.truncated_jpeg(str(tmp_path / 'a.png'))


def test_errors_about_a_cut_jpeg_say_that_it_was_cut(tmp_path):
  """A JPEG cut short decodes with gray rows, which detection crops as a border: its error
  ('needs an image of at least 16x16 px ... got 320x12') did not say the file was cut."""
  image = np.random.default_rng(0).integers(0, 256, (64, 64, 3), dtype=np.uint8)
  whole = str(tmp_path / 'whole.jpg')
  cv2.imwrite(whole, image)
  (tmp_path / 'cut.jpg').write_bytes(open(whole, 'rb').read()[:400])
  cut = str(tmp_path / 'cut.jpg')
  with pytest.raises(ValueError, match=r'^too small\. .*cut\.jpg may be the cause: the JPEG '
                     r'file ends before its end marker'):
    with input_images.blaming_truncation(cut):
      raise ValueError('too small.')
  with pytest.raises(ValueError, match=r'^too small\.$'):  # A whole file: as it was.
    with input_images.blaming_truncation(whole):
      raise ValueError('too small.')
  with pytest.raises(KeyError):  # Not a file's fault: passed on.
    with input_images.blaming_truncation(cut):
      raise KeyError('left')


def test_read_image_gray_to_rgb(tmp_path):
  path = str(tmp_path / 'gray.png')
  cv2.imwrite(path, np.full((5, 6), 77, np.uint8))
  image = input_images.read_image(path)
  assert image.shape == (5, 6, 3) and np.all(image == 77)


def test_only_rgb_colour_profiles_are_kept_for_the_rgb_outputs(tmp_path):
  """A gray (or CMYK) profile describes channels the RGB outputs do not have: it was
  embedded in them (libpng: 'Gray color space not permitted on RGB PNG')."""
  from PIL import ImageCms  # pylint: disable=import-outside-toplevel
  rgb = ImageCms.ImageCmsProfile(ImageCms.createProfile('sRGB')).tobytes()
  assert rgb[16:20] == b'RGB '
  gray = rgb[:16] + b'GRAY' + rgb[20:]  # The header's colour space field.
  image = np.full((8, 8), 128, np.uint8)
  for name, profile, kept in (('rgb.png', rgb, rgb), ('gray.png', gray, None),
                              ('none.png', None, None)):
    Image.fromarray(image).save(tmp_path / name, icc_profile=profile)
    assert input_images.header(str(tmp_path / name)).icc_profile == kept, name


def _picture(seed, shape=(24, 32, 3)):
  return Image.fromarray(np.random.default_rng(seed).integers(0, 256, shape, dtype=np.uint8))


def test_an_animated_png_is_refused_like_a_gif(tmp_path):
  """An APNG's later frames were dropped silently (only GIF and WebP were checked)."""
  path = str(tmp_path / 'wiggle.png')
  _picture(0).save(path, save_all=True, append_images=[_picture(1)])
  with pytest.raises(ValueError, match=r'wiggle\.png is an animated image \(2 frames\)'):
    input_images.read_image(path)
  misnamed = str(tmp_path / 'wiggle.jpg')  # The format, not the extension, decides.
  _picture(0).save(misnamed, format='GIF', save_all=True, append_images=[_picture(1)])
  with pytest.raises(ValueError, match=r'wiggle\.jpg is an animated image \(2 frames\)'):
    input_images.read_image(misnamed)
  _picture(0).save(tmp_path / 'still.png')
  assert input_images.read_image(str(tmp_path / 'still.png')).shape == (24, 32, 3)


def test_an_mpo_stereo_pair_is_refused_and_a_camera_jpeg_with_a_preview_is_read(tmp_path):
  """A 3D camera's MPO holds both views: its first was unmixed as if it were a mixture."""
  views = [np.full((24, 32, 3), colour, np.uint8) for colour in ((60, 120, 180), (200, 40, 90))]
  pair = tmp_path / 'DSCF0001.MPO'
  pair.write_bytes(mpo.encode(views, 90))  # Typed as views, as a Fujifilm W3 writes.
  assert input_images.header(str(pair)).stereo_views == 2
  with pytest.raises(ValueError, match=r'DSCF0001\.MPO is an MPO stereo pair \(2 views\)'):
    input_images.read_image(str(pair))
  untyped = str(tmp_path / 'pillow.mpo')  # Pillow's: 'Undefined', pictures of one size.
  _picture(0).save(untyped, 'MPO', save_all=True, append_images=[_picture(1)])
  assert input_images.header(untyped).stereo_views == 2
  # A camera's JPEG with a large preview: the second entry typed 0x010001.
  data = mpo.encode([views[0], views[0][:12, :16]], 90)
  first = data.index((mpo.DISPARITY_TYPE | mpo.REPRESENTATIVE).to_bytes(4, 'little'))
  second = first + 16
  assert data[second:second + 4] == mpo.DISPARITY_TYPE.to_bytes(4, 'little')
  data = (data[:first] + (0x030000).to_bytes(4, 'little') + data[first + 4:second] +
          (0x010001).to_bytes(4, 'little') + data[second + 4:])
  (tmp_path / 'camera.jpg').write_bytes(data)
  found = input_images.header(str(tmp_path / 'camera.jpg'))
  assert found.frames == 2 and found.stereo_views == 0
  read = input_images.read_image(str(tmp_path / 'camera.jpg')).astype(int)
  assert read.shape == views[0].shape
  assert np.abs(read - views[0]).max() <= 3  # The first picture.


def test_a_multi_page_tiff_unmixes_its_first_page_and_says_so(tmp_path, caplog):
  """A scanner's multi-page TIFF: pages 2.. were dropped silently."""
  path = str(tmp_path / 'scans.tif')
  _picture(0).save(path, save_all=True, append_images=[_picture(1), _picture(2)])
  caplog.set_level(logging.WARNING, logger='absl')
  image = input_images.read_image(path)
  np.testing.assert_array_equal(image, np.asarray(_picture(0)))
  assert input_images.header(path).pages == 3
  assert 'scans.tif holds 3 pages: only the first is unmixed' in caplog.text


def test_a_phone_heic_is_read_upright_and_a_burst_unmixes_its_primary_image(tmp_path, caplog):
  """pillow-heif turns a HEIC upright by its own transform (saved from EXIF orientation 6)
  and its EXIF then says 1: the picture is turned once, not twice. A HEIF holding several
  images (a burst) has its primary one unmixed, with a warning."""
  y, x = np.mgrid[:16, :24]
  upright = np.dstack([40 + x * 5, 40 + y * 8, 200 - x * 5]).astype(np.uint8)  # Not square.
  exif = Image.Exif()
  exif[0x0112] = 6  # Stored turned: a viewer turns it 90 degrees clockwise.
  Image.fromarray(np.ascontiguousarray(np.rot90(upright, 1))).save(
      tmp_path / 'portrait.heic', quality=100, exif=exif.tobytes())
  read = input_images.read_image(str(tmp_path / 'portrait.heic'))
  assert read.shape == upright.shape and input_images.header(
      str(tmp_path / 'portrait.heic')).orientation == 1
  assert np.abs(read.astype(int) - upright).mean() < 4
  burst = pillow_heif.from_bytes(mode='RGB', size=(24, 16), data=upright.tobytes())
  burst.add_frombytes(mode='RGB', size=(24, 16), data=upright[::-1].tobytes())
  burst.save(str(tmp_path / 'burst.heic'), quality=100)
  caplog.set_level(logging.WARNING, logger='absl')
  read = input_images.read_image(str(tmp_path / 'burst.heic'))
  assert np.abs(read.astype(int) - upright).mean() < 4  # The primary: the first added.
  assert 'burst.heic holds 2 images: only its primary image is unmixed' in caplog.text


def _stereo_group(entities=(1, 2)) -> bytes:
  """A 'grpl' box holding one 'ster' entity group (HEIF 23008-12 6.8.2) of `entities`."""
  ster = (b'\0\0\0\0' + (1).to_bytes(4, 'big') + len(entities).to_bytes(4, 'big') +
          b''.join(e.to_bytes(4, 'big') for e in entities))
  ster = (8 + len(ster)).to_bytes(4, 'big') + b'ster' + ster
  return (8 + len(ster)).to_bytes(4, 'big') + b'grpl' + ster


def test_a_heif_stereo_pair_is_refused_and_a_burst_is_not(tmp_path):
  """Two images linked by a 'ster' entity group (a phone's spatial photo) are a stereo
  pair: refused like an MPO; the same two images without the group are a burst."""
  picture = np.arange(16 * 24 * 3, dtype=np.uint8).reshape(16, 24, 3)
  pair = pillow_heif.from_bytes(mode='RGB', size=(24, 16), data=picture.tobytes())
  pair.add_frombytes(mode='RGB', size=(24, 16), data=picture[:, ::-1].tobytes())
  pair.save(str(tmp_path / 'burst.heic'), quality=90)
  # The group is appended as a top-level box: libheif reads the images as before.
  spatial = tmp_path / 'spatial.heic'
  spatial.write_bytes((tmp_path / 'burst.heic').read_bytes() + _stereo_group())
  assert image_io.heif_stereo_views(str(tmp_path / 'burst.heic')) == 0
  assert image_io.heif_stereo_views(str(spatial)) == 2
  found = input_images.header(str(spatial))
  assert found.stereo_views == 2 and found.pages == 2
  refused = r'spatial.heic is a HEIF stereo pair \(a spatial photo of 2 views\)'
  with pytest.raises(ValueError, match=refused):
    input_images.read_image(str(spatial))
  assert input_images.read_image(str(tmp_path / 'burst.heic')).shape == (16, 24, 3)
  # Named by what it holds, not by its extension (a renamed or mislabelled download).
  misnamed = tmp_path / 'spatial.jpg'
  misnamed.write_bytes(spatial.read_bytes())
  assert input_images.header(str(misnamed)).format == 'HEIF'
  with pytest.raises(ValueError, match=r'spatial.jpg is a HEIF stereo pair'):
    input_images.read_image(str(misnamed))


def test_reduced_resolution_tiff_pages_are_not_pages(tmp_path, caplog):
  path = str(tmp_path / 'with_thumbnail.tif')
  thumbnail = _picture(1, (6, 8, 3))
  thumbnail.encoderinfo = {}
  _picture(0).save(path, save_all=True, append_images=[thumbnail],
                   tiffinfo={254: 0})
  with Image.open(path) as image:
    image.seek(1)
    reduced = int(image.tag_v2.get(254, 0)) & 1
  caplog.set_level(logging.WARNING, logger='absl')
  found = input_images.header(path)
  assert found.frames == 2 and found.pages == (1 if reduced else 2)


def test_the_header_says_what_image_io_says_of_the_stored_colour(tmp_path):
  image = np.random.default_rng(0).integers(0, 256, (16, 16, 3), dtype=np.uint8)
  for name, params in (('420.jpg', []), ('444.jpg', [cv2.IMWRITE_JPEG_SAMPLING_FACTOR,
                                                     cv2.IMWRITE_JPEG_SAMPLING_FACTOR_444]),
                       ('a.png', []), ('lossy.webp', [cv2.IMWRITE_WEBP_QUALITY, 80])):
    path = str(tmp_path / name)
    cv2.imwrite(path, image, params)
    assert input_images.header(path).chroma_halved == image_io.chroma_halved(path), name
  assert input_images.header(str(tmp_path / '420.jpg')).chroma_halved
  assert not input_images.header(str(tmp_path / 'a.png')).chroma_halved


def test_a_16_bit_file_is_read_deep_on_request_and_a_loss_of_depth_is_said(tmp_path):
  """`deep`: uint16 RGB and 'bit_depth' not lost; views that came back at 8 bits (a double
  image's) are: `depth_lost`, then a note naming the file."""
  bgr = np.random.default_rng(2).integers(0, 65536, (6, 8, 3)).astype(np.uint16)
  path = str(tmp_path / 'scan.png')
  cv2.imwrite(path, bgr)
  deep, _, lost = input_images.read_upright(path, deep=True)
  assert deep.dtype == np.uint16 and lost == ()
  np.testing.assert_array_equal(deep, bgr[..., ::-1])
  shallow, _, lost = input_images.read_upright(path)
  assert shallow.dtype == np.uint8 and lost == ('bit_depth',)
  assert input_images.depth_lost(deep, deep) == ()
  assert input_images.depth_lost(deep, shallow) == ('bit_depth',)
  assert input_images.depth_lost(shallow, shallow) == ()
  notes = input_images.reading_notes(path, input_images.header(path), ('bit_depth',))
  assert notes['bit_depth'].startswith(path) and 'written at 8 bits' in notes['bit_depth']


def test_an_alpha_channel_is_kept_on_request_where_it_is_not_opaque(tmp_path):
  bgra = np.random.default_rng(3).integers(0, 256, (6, 8, 4)).astype(np.uint8)
  bgra[..., 3] = 255
  cv2.imwrite(str(tmp_path / 'opaque.png'), bgra)
  bgra[0, 0, 3] = 10
  cv2.imwrite(str(tmp_path / 'clear.png'), bgra)
  image, _, lost = input_images.read_upright(str(tmp_path / 'clear.png'), alpha=True)
  np.testing.assert_array_equal(image, bgra[..., [2, 1, 0, 3]])
  assert lost == ()
  assert input_images.read_upright(str(tmp_path / 'clear.png'))[2] == ('alpha',)
  opaque, _, lost = input_images.read_upright(str(tmp_path / 'opaque.png'), alpha=True)
  assert opaque.shape == (6, 8, 3) and lost == ()
