"""Tests for mixstereo_tf.cli.media: layouts, disparity files, output options."""

import os

import cv2
import numpy as np
import pytest

from mixstereo_tf.cli import media
from mixstereo_tf.data import disparity_io
from mixstereo_tf.data import image_io


def _views(height=4, width=6):
  left = np.zeros((height, width, 3), np.uint8)
  left[..., 0] = 200
  right = np.zeros((height, width, 3), np.uint8)
  right[..., 2] = 100
  return left, right


def test_compose_layouts():
  left, right = _views()
  separate = media.compose(left, right, 'separate')
  assert separate[0] is left and separate[1] is right
  sbs = media.compose(left, right, 'sbs')
  assert sbs.shape == (4, 12, 3)
  np.testing.assert_array_equal(sbs[:, :6], left)
  np.testing.assert_array_equal(sbs[:, 6:], right)
  tb = media.compose(left, right, 'tb')
  assert tb.shape == (8, 6, 3)
  np.testing.assert_array_equal(tb[:4], left)
  np.testing.assert_array_equal(tb[4:], right)


def test_sbs_half_keeps_the_frame_size_and_squeezes_each_view():
  left, right = _views(4, 7)
  left[:, :, 1] = np.arange(7)[None, :] * 10  # A ramp: squeezing averages column pairs.
  half = media.compose(left, right, 'sbs_half')
  assert half.shape == (4, 7, 3)
  np.testing.assert_array_equal(half[:, 4:], right[:, :3])  # Constant view: unchanged.
  assert np.all(half[:, :4, 0] == 200)
  # The left ramp 0..60 squeezed to 4 columns stays increasing and spans 0..60.
  ramp = half[0, :4, 1].astype(int)
  assert np.all(np.diff(ramp) > 0) and ramp[0] < 15 and ramp[-1] > 45


def test_layout_images_names_and_unknown_layout():
  left, right = _views()
  assert [s for s, _ in media.layout_images(left, right, 'separate')] == ['left', 'right']
  assert [s for s, _ in media.layout_images(left, right, 'tb')] == ['tb']
  with pytest.raises(ValueError, match='sbs_half'):
    media.compose(left, right, 'diagonal')
  with pytest.raises(ValueError, match='shape'):
    media.compose(left, right[:, :5], 'sbs')


def test_png16_round_trip_kitti_convention(tmp_path):
  disparity = np.array([[0.0, 1.0, 10.5, 37.25],
                        [-3.0, np.nan, 300.0, 0.001]], np.float32)
  path = str(tmp_path / 'd.png')
  media.write_disparity_png16(path, disparity)
  raw = cv2.imread(path, cv2.IMREAD_UNCHANGED)
  assert raw.dtype == np.uint16
  # A zero disparity (a point at infinity) is valid: 1 / 256 px, not the invalid 0.
  np.testing.assert_array_equal(raw, [[1, 256, 2688, 9536], [0, 0, 65535, 1]])
  decoded, valid = disparity_io.read_disparity(path, scale=256.0)
  np.testing.assert_array_equal(valid, [[True, True, True, True], [False, False, True, True]])
  np.testing.assert_allclose(decoded[0], [0.0, 1.0, 10.5, 37.25], atol=1 / 256)


def test_output_options_reject_bad_layout_and_display_range():
  with pytest.raises(ValueError, match="Unknown layout 'sideways'"):
    media.OutputOptions('sideways')
  for bad in (0.0, -1.0, float('inf'), float('nan')):  # inf failed every input at run time.
    with pytest.raises(ValueError, match='max_display_disparity must be positive and finite'):
      media.OutputOptions(max_display_disparity=bad)


def test_output_options_formats_are_a_checked_tuple(tmp_path):
  assert media.OutputOptions().formats == ()
  assert media.OutputOptions(formats=['jps', 'rgbd']).formats == ('jps', 'rgbd')
  with pytest.raises(ValueError, match="OutputOptions.formats: unknown output format 'gif'"):
    media.OutputOptions(formats=('gif',))
  left, right = _views(6, 8)
  outputs = {'left': left, 'right': right, 'disparity_left': np.ones((6, 8), np.float32)}
  written = media.write_image_outputs(outputs, str(tmp_path), 'a', 'sbs', 4.0, ('jps',), left)
  assert written['files'][-1] == 'a.jps' and os.path.isfile(tmp_path / 'a.jps')




def test_16_bit_views_are_16_bit_pngs_with_the_inputs_colour_profile(tmp_path):
  from PIL import Image, ImageCms  # pylint: disable=import-outside-toplevel
  profile = ImageCms.ImageCmsProfile(ImageCms.createProfile('sRGB')).tobytes()
  view = np.random.default_rng(3).integers(0, 65536, (5, 7, 3)).astype(np.uint16)
  path = str(tmp_path / 'v.png')
  media.write_image(path, view, profile)
  np.testing.assert_array_equal(cv2.imread(path, cv2.IMREAD_UNCHANGED)[..., ::-1], view)
  with Image.open(path) as written:
    assert written.info['icc_profile'] == profile
  (tmp_path / 'v.jpg').write_bytes(b'\xff\xd8\xff\xd9')
  with pytest.raises(ValueError, match=r'v.jpg is no PNG'):
    image_io.add_png_icc(str(tmp_path / 'v.jpg'), profile)


def test_views_with_the_inputs_alpha_are_written_as_rgba_in_channel_order(tmp_path):
  from PIL import Image, ImageCms  # pylint: disable=import-outside-toplevel
  profile = ImageCms.ImageCmsProfile(ImageCms.createProfile('sRGB')).tobytes()
  view = np.zeros((3, 4, 3), np.uint8)
  view[..., 0] = 200  # Red.
  alpha16 = np.full((3, 4), 65535, np.uint16)
  alpha16[0, 0] = 0
  rgba = media.with_alpha(view, alpha16)  # A 16-bit input's alpha on 8-bit views.
  assert rgba.dtype == np.uint8 and rgba[0, 0].tolist() == [200, 0, 0, 0]
  deep = media.with_alpha(view.astype(np.uint16) * 257, np.full((3, 4), 128, np.uint8))
  assert deep.dtype == np.uint16 and deep[1, 1].tolist() == [51400, 0, 0, 32896]
  for name, icc in (('plain.png', None), ('profiled.png', profile), ('deep.png', profile)):
    media.write_image(str(tmp_path / name), deep if name == 'deep.png' else rgba, icc)
    with Image.open(tmp_path / name) as written:
      assert written.info.get('icc_profile') == icc
    back = cv2.imread(str(tmp_path / name), cv2.IMREAD_UNCHANGED)[..., [2, 1, 0, 3]]
    np.testing.assert_array_equal(back, deep if name == 'deep.png' else rgba)
