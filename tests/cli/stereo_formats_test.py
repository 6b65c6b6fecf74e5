"""Tests for mixstereo_tf.cli.stereo_formats: MPO, JPS, wiggle GIF and its synthesised views,
RGBD, anaglyphs."""

import dataclasses
import shutil
import struct
import subprocess

import numpy as np
import pytest
from PIL import Image
from PIL import ImageSequence
from PIL import MpoImagePlugin

from mixstereo_tf.cli import stereo_formats
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures


def _result(height=32, width=48):
  """Views easy to tell apart after JPEG: a red-ish left, a blue-ish right, textured."""
  y, x = np.mgrid[:height, :width]
  left = np.stack([200 + 0 * x, (x * 4) % 120, 40 + 0 * x], -1).astype(np.uint8)
  right = np.stack([30 + 0 * x, (y * 3) % 100, 210 + 0 * x], -1).astype(np.uint8)
  disparity = np.tile(np.linspace(0.0, 10.0, width, dtype=np.float32), (height, 1))
  colour = np.zeros((height, width, 3), np.uint8)
  return stereo_formats.StereoResult(left, right, disparity, colour, (0.0, 10.0), left)


def _close(a, b, tolerance=8.0):
  return float(np.abs(np.asarray(a, float) - np.asarray(b, float)).mean()) < tolerance


def test_mpo_holds_left_then_right_with_an_mp_index(tmp_path):
  result = _result()
  paths = stereo_formats.write_formats(result, str(tmp_path / 'scene'), ['mpo'])
  assert paths == [str(tmp_path / 'scene.mpo')]
  with Image.open(paths[0]) as image:
    assert isinstance(image, MpoImagePlugin.MpoImageFile)
    assert image.n_frames == 2 and len(image.mpinfo[0xB002]) == 2  # The MP entries.
    frames = [np.asarray(frame.convert('RGB')) for frame in ImageSequence.Iterator(image)]
  assert _close(frames[0], result.left) and _close(frames[1], result.right)
  assert not _close(frames[0], result.right)
  # A stereo pair for 3D cameras and TVs: both pictures typed multi-frame disparity, the
  # first representative, each with its MP attributes (number, base viewpoint 1).
  entries = image.mpinfo[0xB002]
  assert [e['Attribute']['MPType'] for e in entries] == ['Multi-Frame Image: (Disparity)'] * 2
  assert [e['Attribute']['RepresentativeImageFlag'] for e in entries] == [True, False]
  with open(paths[0], 'rb') as f:
    data = f.read()
  assert entries[0]['Size'] + entries[1]['Size'] == len(data)
  assert _mp_attributes(data) == [{0xB101: 1, 0xB204: 1}, {0xB101: 2, 0xB204: 1}]
  if shutil.which('exiftool') is None:
    print('exiftool not installed (apt-get install libimage-exiftool-perl): skipping its check')
    return
  text = subprocess.run(['exiftool', '-a', paths[0]], capture_output=True, text=True).stdout
  assert 'MPO' in text and 'Number Of Images                : 2' in text
  assert text.count('Multi-frame Disparity') == 2 and 'Base Viewpoint Num' in text


def _mp_attributes(data):
  """{MPIndividualNum, BaseViewpointNum} of each picture's MP attribute IFD (the IFD after
  the first picture's index; the only IFD of the others), read from the APP2 segments."""
  found, at = [], 0
  while (at := data.find(b'MPF\x00II*\x00', at)) >= 0:
    tiff = data[at + 4:]
    ifd = struct.unpack('<I', tiff[4:8])[0]
    count = struct.unpack('<H', tiff[ifd:ifd + 2])[0]
    tags = {struct.unpack('<H', tiff[ifd + 2 + 12 * i:ifd + 4 + 12 * i])[0]
            for i in range(count)}
    if 0xB001 in tags:  # The index IFD: its next IFD holds the attributes.
      ifd = struct.unpack('<I', tiff[ifd + 2 + 12 * count:ifd + 6 + 12 * count])[0]
      count = struct.unpack('<H', tiff[ifd:ifd + 2])[0]
    values = {}
    for i in range(count):
      tag, _, _, value = struct.unpack('<HHII', tiff[ifd + 2 + 12 * i:ifd + 14 + 12 * i])
      if tag in (0xB101, 0xB204):
        values[tag] = value
    found.append(values)
    at += 8
  return found


def test_jps_is_a_double_width_jpeg_with_the_right_view_first(tmp_path):
  result = _result()
  (path,) = stereo_formats.write_formats(result, str(tmp_path / 'scene'), ['jps'])
  assert path.endswith('scene.jps')
  with open(path, 'rb') as f:
    assert f.read(3) == b'\xff\xd8\xff'  # A JPEG.
  with Image.open(path) as image:
    assert image.format == 'JPEG' and image.size == (96, 32)
    pair = np.asarray(image.convert('RGB'))
  assert _close(pair[:, :48], result.right) and _close(pair[:, 48:], result.left)


def test_rgbd_puts_near_white_beside_the_left_view(tmp_path):
  result = _result()
  (path,) = stereo_formats.write_formats(result, str(tmp_path / 'scene'), ['rgbd'])
  image = np.asarray(Image.open(path).convert('RGB'))
  assert image.shape == (32, 96, 3)
  np.testing.assert_array_equal(image[:, :48], result.left)
  depth = image[:, 48:, 0]
  assert (depth[:, 0] == 0).all() and (depth[:, -1] == 255).all()  # 0 px far, 10 px near.
  assert (np.diff(depth.astype(int), axis=1) >= 0).all()
  np.testing.assert_array_equal(stereo_formats.depth_image(
      np.array([[-3.0, 5.0, 12.0, np.nan]]), 0.0, 10.0), [[0, 128, 255, 0]])


def test_anaglyph_reencodings_use_the_mixture_operators(tmp_path):
  result = _result()
  names = ['anaglyph_dubois', 'anaglyph_optimized', 'anaglyph_gray', 'anaglyph_colour']
  paths = stereo_formats.write_formats(result, str(tmp_path / 's'), names)
  assert [p.rsplit('/', 1)[1] for p in paths] == [f's_{n}.png' for n in names]
  colour = np.asarray(Image.open(paths[3]))
  np.testing.assert_array_equal(colour[..., 0], result.left[..., 0])
  np.testing.assert_array_equal(colour[..., 1:], result.right[..., 1:])
  dubois = mixtures.mix('dubois', image_range.u8_to_signed(result.left),
                        image_range.u8_to_signed(result.right))
  np.testing.assert_array_equal(np.asarray(Image.open(paths[0])),
                                image_range.signed_to_u8(dubois.numpy()))
  optimized = np.asarray(Image.open(paths[1]))
  expected_red = np.rint(0.7 * result.left[..., 1] + 0.3 * result.left[..., 2])
  assert np.abs(optimized[..., 0] - expected_red).max() <= 1
  gray = np.asarray(Image.open(paths[2]))
  np.testing.assert_array_equal(gray[..., 1], gray[..., 2])
  red_blue = np.asarray(Image.open(stereo_formats.write_formats(
      result, str(tmp_path / 't'), ['anaglyph_red_blue'])[0]))
  assert (red_blue[..., 1] == 0).all()  # For red-blue glasses: green black, not mid-gray.
  np.testing.assert_array_equal(red_blue[..., [0, 2]], gray[..., [0, 2]])


def test_wiggle_gif_loops_through_six_frames(tmp_path):
  result = _result()
  (path,) = stereo_formats.write_formats(result, str(tmp_path / 'scene'), ['wiggle'])
  with Image.open(path) as image:
    assert image.format == 'GIF' and image.n_frames == 6 and image.info['loop'] == 0
    frames = [np.asarray(f.convert('RGB')) for f in ImageSequence.Iterator(image)]
  assert _close(frames[0], result.left, 12) and _close(frames[3], result.right, 12)


def test_names_are_checked_and_videos_skip_still_formats():
  assert stereo_formats.check_formats(['mpo', 'rgbd']) == ('mpo', 'rgbd')
  with pytest.raises(ValueError, match="OutputOptions.formats: unknown output format 'gif'"):
    stereo_formats.check_formats(['gif'])
  with pytest.raises(ValueError, match="'jps' is asked for more than once"):
    stereo_formats.check_formats(['jps', 'jps'])
  drawn, skipped = stereo_formats.video_formats(['wiggle', 'rgbd', 'html', 'anaglyph_gray'])
  assert drawn == ('rgbd', 'anaglyph_gray')
  assert sorted(skipped) == ['html', 'wiggle'] and 'not viewable' in skipped['wiggle']
  result = dataclasses.replace(_result(), mixture=None)
  with pytest.raises(ValueError, match='viewer page needs the input image'):
    stereo_formats.write_formats(result, '/nonexistent/x', ['html'])


def _texture(height, width, seed=0):
  return np.random.RandomState(seed).randint(0, 256, (height, width, 3)).astype(np.uint8)


def _scene(t, height=24, width=40):
  """The view at viewpoint t of a background (disparity 2) behind a box (disparity 8),
  each a fixed texture shifted by t * d (a point at left x is at x - t d); and the left
  view's disparity."""
  background, box = _texture(height, width + 16, 1), _texture(10, 12, 2)
  shift = int(round(2 * t))
  image = background[:, 8 + shift:8 + shift + width].copy()
  x = 20 - int(round(8 * t))  # The box's left edge.
  image[7:17, x:x + 12] = box
  disparity = np.full((height, width), 2.0, np.float32)
  disparity[7:17, 20:32] = 8.0
  return image, disparity


def test_constant_disparity_is_a_shift_and_the_edge_comes_from_the_right_view():
  texture = _texture(12, 40)
  left, right = texture[:, :30], texture[:, 6:36]  # Right x shows left x + 6.
  disparity = np.full((12, 30), 6.0, np.float32)
  for t, shift in ((1 / 3, 2), (0.5, 3), (2 / 3, 4)):
    view = stereo_formats.synthesize_view(left, right, disparity, t)
    # Left x is seen at x - t d: the view shows the texture from column t d on; the last
    # columns, where no left pixel lands, are the right view's at x - (1 - t) d.
    np.testing.assert_array_equal(view, texture[:, shift:shift + 30])
  np.testing.assert_array_equal(stereo_formats.synthesize_view(left, right, disparity, 0.0), left)


def test_the_nearer_surface_wins_and_disocclusions_come_from_the_right_view():
  left, disparity = _scene(0.0)
  right, _ = _scene(1.0)
  view = stereo_formats.synthesize_view(left, right, disparity, 0.5)
  expected, _ = _scene(0.5)
  # The box moved 4 px over the background (1 px); the background it uncovered on its
  # right (columns 28-30) comes from the right view.
  np.testing.assert_array_equal(view, expected)
  hidden = stereo_formats.synthesize_view(left, np.zeros_like(right), disparity, 0.5)
  assert np.all(hidden[7:17, 28:31] == 0)  # Those pixels came from the right view.


def test_frames_go_left_right_and_back():
  left, disparity = _scene(0.0)
  right, _ = _scene(1.0)
  cycle = stereo_formats.wiggle_frames(left, right, disparity, between=2)
  assert len(cycle) == 6 and cycle[0] is left and cycle[3] is right
  np.testing.assert_array_equal(cycle[1], cycle[5])
  np.testing.assert_array_equal(cycle[2], cycle[4])
  assert np.any(cycle[1] != cycle[2])
