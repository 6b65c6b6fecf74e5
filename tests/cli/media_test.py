"""Tests for mixstereo_tf.cli.media: layouts, disparity files, input expansion."""

import logging
import os

import cv2
import numpy as np
from PIL import Image
import pytest

from mixstereo_tf.cli import input_images
from mixstereo_tf.cli import media
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
  decoded, valid = image_io.read_disparity(path, scale=256.0)
  np.testing.assert_array_equal(valid, [[True, True, True, True], [False, False, True, True]])
  np.testing.assert_allclose(decoded[0], [0.0, 1.0, 10.5, 37.25], atol=1 / 256)


def _write_png(path, value, shape=(8, 10, 3)):
  cv2.imwrite(str(path), np.full(shape, value, np.uint8))


def test_iter_inputs_folder_glob_single(tmp_path):
  _write_png(tmp_path / 'b.png', 10)
  _write_png(tmp_path / 'a.jpg', 20)
  (tmp_path / 'notes.txt').write_text('not an image')
  os.mkdir(tmp_path / 'sub.png')  # A folder with an image-like name is skipped.
  items = list(media.iter_inputs(str(tmp_path)))
  assert [os.path.basename(i.path) for i in items] == ['a.jpg', 'b.png']
  assert [i.name for i in items] == ['a', 'b'] and not any(i.is_video for i in items)
  items = list(media.iter_inputs(str(tmp_path / '*.png')))
  assert [os.path.basename(i.path) for i in items] == ['b.png']
  single = list(media.iter_inputs(str(tmp_path / 'a.jpg')))
  assert len(single) == 1 and single[0].path == str(tmp_path / 'a.jpg')


def test_iter_inputs_glob_double_star_reaches_nested_folders(tmp_path):
  os.makedirs(tmp_path / 'scans' / '1950' / 'box2')
  _write_png(tmp_path / 'scans' / 'top.png', 10)
  _write_png(tmp_path / 'scans' / '1950' / 'box2' / 'deep.png', 20)
  items = list(media.iter_inputs(str(tmp_path / 'scans' / '**' / '*.png')))
  assert sorted(os.path.basename(i.path) for i in items) == ['deep.png', 'top.png']


def test_output_names_keep_the_names_an_earlier_run_gave(tmp_path):
  old, new = str(tmp_path / 'b' / 'x.png'), str(tmp_path / 'a' / 'x.png')
  assert media.output_names([new, old]) == ['x_png', 'x_png_2']  # Renamed by the list.
  earlier = {os.path.realpath(old): 'x', os.path.realpath(str(tmp_path / 'gone.png')): 'y'}
  # The earlier input keeps 'x'; no new input takes 'x' or the name of one not listed now.
  assert media.output_names([new, old], earlier) == ['x_png', 'x']
  assert media.output_names([str(tmp_path / 'y.png')], earlier) == ['y_2']


def test_iter_inputs_folder_lists_videos_too(tmp_path):
  _write_png(tmp_path / 'b.png', 10)
  (tmp_path / 'a.mp4').write_bytes(b'not decoded when listed')
  items = list(media.iter_inputs(str(tmp_path)))
  assert [(os.path.basename(i.path), i.is_video) for i in items] == [('a.mp4', True),
                                                                      ('b.png', False)]


def _items(folder, *names):
  return [media.MediaItem(str(folder / n), n.endswith('.mp4'), os.path.splitext(n)[0])
          for n in names]


def test_prepare_output_dir_refuses_to_overwrite_an_input(tmp_path):
  _write_png(tmp_path / 'pic.png', 10)
  _write_png(tmp_path / 'pic_left.png', 20)
  before = (tmp_path / 'pic_left.png').read_bytes()
  with pytest.raises(ValueError, match=r'pic_left\.png.*outputs of .*pic\.png'):
    media.prepare_output_dir(_items(tmp_path, 'pic.png', 'pic_left.png'), str(tmp_path))
  assert (tmp_path / 'pic_left.png').read_bytes() == before
  # Case-insensitive file systems: PIC_left.png would be overwritten as well.
  with pytest.raises(ValueError, match='PIC_left'):
    media.prepare_output_dir(_items(tmp_path, 'pic.png', 'PIC_left.png'), str(tmp_path))
  # Inputs whose names no output takes, or outputs in another folder, are fine.
  media.prepare_output_dir(_items(tmp_path, 'pic.png', 'picture.png'), str(tmp_path))
  media.prepare_output_dir(_items(tmp_path, 'pic.png', 'pic_left.png'),
                           str(tmp_path / 'out'))
  assert (tmp_path / 'out').is_dir()


def test_prepare_output_dir_names_an_existing_file(tmp_path):
  (tmp_path / 'target.png').write_bytes(b'x')
  with pytest.raises(ValueError, match=r'--output_dir=.*target\.png is an existing file'):
    media.prepare_output_dir([], str(tmp_path / 'target.png'))
  with pytest.raises(ValueError, match=r"Cannot create the output folder "
                                       r"--output_dir='.*target\.png/sub': Not a directory"):
    media.prepare_output_dir([], str(tmp_path / 'target.png' / 'sub'))
  with pytest.raises(ValueError, match="--output_dir='': No such file"):
    media.prepare_output_dir([], '')


def test_prepare_output_dir_names_a_folder_nothing_can_be_written_into(tmp_path, monkeypatch):
  """A read-only or immutable folder failed only when each input's first file was
  written, after its unmixing, with no reason ('Cannot write image file')."""
  def refused(*args, **kwargs):
    raise OSError(30, 'Read-only file system')
  monkeypatch.setattr(media.tempfile, 'TemporaryFile', refused)
  with pytest.raises(ValueError, match="Cannot write into the output folder "
                                       "--output_dir='.*out': Read-only file system"):
    media.prepare_output_dir([], str(tmp_path / 'out'))


def test_output_names_are_unique_when_stems_collide():
  assert media.output_names(['in/a.png', 'in/b.jpg']) == ['a', 'b']
  # Shared stem: the extension joins the name (its case kept).
  assert media.output_names(['in/a.JPG', 'in/a.png', 'in/b.png']) == ['a_JPG', 'a_png', 'b']
  # Same file name in two folders of a glob: numbered in input order.
  assert media.output_names(['x/a.png', 'y/a.png', 'z/a.png']) == ['a_png', 'a_png_2',
                                                                     'a_png_3']
  # A fallback equal to another input's stem, and names differing only in case, are
  # numbered too (case-insensitive file systems would merge them).
  assert media.output_names(['a.jpg', 'a.png', 'a_png.bmp']) == ['a_jpg', 'a_png', 'a_png_2']
  assert media.output_names(['A.png', 'a.png']) == ['A_png', 'a_png_2']
  # A numbered name never takes the plain name another input still wants.
  assert media.output_names(['x/a.png', 'y/a.png', 'a_png_2.bmp']) == [
      'a_png', 'a_png_3', 'a_png_2']


def test_iter_inputs_names_collisions_in_a_folder(tmp_path):
  _write_png(tmp_path / 'a.png', 10)
  _write_png(tmp_path / 'a.jpg', 20)
  _write_png(tmp_path / 'b.png', 30)
  items = list(media.iter_inputs(str(tmp_path)))
  assert [(os.path.basename(i.path), i.name) for i in items] == [
      ('a.jpg', 'a_jpg'), ('a.png', 'a_png'), ('b.png', 'b')]


def test_iter_inputs_errors(tmp_path):
  with pytest.raises(ValueError, match='not found'):
    list(media.iter_inputs(str(tmp_path / 'missing.png')))
  with pytest.raises(ValueError, match='No images or videos'):
    list(media.iter_inputs(str(tmp_path)))
  with pytest.raises(ValueError, match='match'):
    list(media.iter_inputs(str(tmp_path / '*.png')))


def test_iter_inputs_marks_videos(tmp_path):
  (tmp_path / 'clip.mp4').write_bytes(b'')  # Only the name matters here.
  _write_png(tmp_path / 'still.png', 5)
  items = list(media.iter_inputs(str(tmp_path / '*')))
  assert [(i.name, i.is_video) for i in items] == [('clip', True), ('still', False)]


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


def test_a_folder_notes_its_subfolders_and_skips_earlier_results(tmp_path, caplog):
  caplog.set_level(logging.INFO, logger='absl')
  (tmp_path / 'sub').mkdir()
  _write_png(tmp_path / 'sub' / 'deep.png', 10)
  with pytest.raises(ValueError, match=r"in folder .*; 1 subfolder\(s\) not searched: give "
                                       r"'.*\*\*/\*' to include them"):
    list(media.iter_inputs(str(tmp_path)))
  _write_png(tmp_path / 'a.png', 10)
  _write_png(tmp_path / 'a_left.png', 20)
  assert [i.name for i in media.iter_inputs(str(tmp_path))] == ['a', 'a_left']
  assert '1 subfolder(s) not searched' in caplog.text
  skip = {os.path.realpath(tmp_path / 'a_left.png')}
  assert [i.name for i in media.iter_inputs(str(tmp_path), skip=skip)] == ['a']
  assert [i.name for i in media.iter_inputs(str(tmp_path / 'a_left.png'), skip=skip)] == [
      'a_left']  # Named by itself: taken.
  with pytest.raises(ValueError, match='holds only results of earlier runs'):
    list(media.iter_inputs(str(tmp_path / 'a_*.png'), skip=skip))


def test_a_link_to_a_parent_folder_lists_each_file_once(tmp_path):
  """`**` follows links: one to a parent folder made each file dozens of inputs and gave
  the real ones other names (scan_png_10)."""
  (tmp_path / 'scans' / 'box').mkdir(parents=True)
  for name in ('a.png', 'b.png'):
    (tmp_path / 'scans' / 'box' / name).write_bytes(b'x')
  os.symlink('..', tmp_path / 'scans' / 'box' / 'up')
  items = list(media.iter_inputs(str(tmp_path / 'scans' / '**' / '*')))
  assert [(os.path.relpath(i.path, tmp_path), i.name) for i in items] == [
      (os.path.join('scans', 'box', 'a.png'), 'a'), (os.path.join('scans', 'box', 'b.png'), 'b')]


def test_brackets_in_a_folder_name_are_the_name_where_the_pattern_matches_nothing(tmp_path):
  (tmp_path / 'Box [1998]').mkdir()
  (tmp_path / 'Box [1998]' / 'a.png').write_bytes(b'x')
  items = list(media.iter_inputs(str(tmp_path / 'Box [1998]' / '*.png')))
  assert [item.name for item in items] == ['a']
  (tmp_path / 'Box 1').mkdir()
  (tmp_path / 'Box 1' / 'b.png').write_bytes(b'x')  # A set that matches: glob's meaning.
  assert [i.name for i in media.iter_inputs(str(tmp_path / 'Box [1]' / '*.png'))] == ['b']
