"""Tests for mixstereo_tf.cli.input_listing: input expansion, names and the output folder."""

import logging
import os

import cv2
import numpy as np
import pytest

from mixstereo_tf.cli import input_listing


def _write_png(path, value, shape=(8, 10, 3)):
  cv2.imwrite(str(path), np.full(shape, value, np.uint8))


def test_iter_inputs_folder_glob_single(tmp_path):
  _write_png(tmp_path / 'b.png', 10)
  _write_png(tmp_path / 'a.jpg', 20)
  (tmp_path / 'notes.txt').write_text('not an image')
  os.mkdir(tmp_path / 'sub.png')  # A folder with an image-like name is skipped.
  items = list(input_listing.iter_inputs(str(tmp_path)))
  assert [os.path.basename(i.path) for i in items] == ['a.jpg', 'b.png']
  assert [i.name for i in items] == ['a', 'b'] and not any(i.is_video for i in items)
  items = list(input_listing.iter_inputs(str(tmp_path / '*.png')))
  assert [os.path.basename(i.path) for i in items] == ['b.png']
  single = list(input_listing.iter_inputs(str(tmp_path / 'a.jpg')))
  assert len(single) == 1 and single[0].path == str(tmp_path / 'a.jpg')


def test_iter_inputs_glob_double_star_reaches_nested_folders(tmp_path):
  os.makedirs(tmp_path / 'scans' / '1950' / 'box2')
  _write_png(tmp_path / 'scans' / 'top.png', 10)
  _write_png(tmp_path / 'scans' / '1950' / 'box2' / 'deep.png', 20)
  items = list(input_listing.iter_inputs(str(tmp_path / 'scans' / '**' / '*.png')))
  assert sorted(os.path.basename(i.path) for i in items) == ['deep.png', 'top.png']


def test_output_names_keep_the_names_an_earlier_run_gave(tmp_path):
  old, new = str(tmp_path / 'b' / 'x.png'), str(tmp_path / 'a' / 'x.png')
  assert input_listing.output_names([new, old]) == ['x_png', 'x_png_2']  # Renamed by the list.
  earlier = {os.path.realpath(old): 'x', os.path.realpath(str(tmp_path / 'gone.png')): 'y'}
  # The earlier input keeps 'x'; no new input takes 'x' or the name of one not listed now.
  assert input_listing.output_names([new, old], earlier) == ['x_png', 'x']
  assert input_listing.output_names([str(tmp_path / 'y.png')], earlier) == ['y_2']


def test_iter_inputs_folder_lists_videos_too(tmp_path):
  _write_png(tmp_path / 'b.png', 10)
  (tmp_path / 'a.mp4').write_bytes(b'not decoded when listed')
  items = list(input_listing.iter_inputs(str(tmp_path)))
  assert [(os.path.basename(i.path), i.is_video) for i in items] == [('a.mp4', True),
                                                                      ('b.png', False)]


def _items(folder, *names):
  return [input_listing.MediaItem(str(folder / n), n.endswith('.mp4'), os.path.splitext(n)[0])
          for n in names]


def test_prepare_output_dir_refuses_to_overwrite_an_input(tmp_path):
  _write_png(tmp_path / 'pic.png', 10)
  _write_png(tmp_path / 'pic_left.png', 20)
  before = (tmp_path / 'pic_left.png').read_bytes()
  with pytest.raises(ValueError, match=r'pic_left\.png.*outputs of .*pic\.png'):
    input_listing.prepare_output_dir(_items(tmp_path, 'pic.png', 'pic_left.png'), str(tmp_path))
  assert (tmp_path / 'pic_left.png').read_bytes() == before
  # Case-insensitive file systems: PIC_left.png would be overwritten as well.
  with pytest.raises(ValueError, match='PIC_left'):
    input_listing.prepare_output_dir(_items(tmp_path, 'pic.png', 'PIC_left.png'), str(tmp_path))
  # Inputs whose names no output takes, or outputs in another folder, are fine.
  input_listing.prepare_output_dir(_items(tmp_path, 'pic.png', 'picture.png'), str(tmp_path))
  input_listing.prepare_output_dir(_items(tmp_path, 'pic.png', 'pic_left.png'),
                           str(tmp_path / 'out'))
  assert (tmp_path / 'out').is_dir()


def test_prepare_output_dir_names_an_existing_file(tmp_path):
  (tmp_path / 'target.png').write_bytes(b'x')
  with pytest.raises(ValueError, match=r'--output_dir=.*target\.png is an existing file'):
    input_listing.prepare_output_dir([], str(tmp_path / 'target.png'))
  with pytest.raises(ValueError, match=r"Cannot create the output folder "
                                       r"--output_dir='.*target\.png/sub': Not a directory"):
    input_listing.prepare_output_dir([], str(tmp_path / 'target.png' / 'sub'))
  with pytest.raises(ValueError, match="--output_dir='': No such file"):
    input_listing.prepare_output_dir([], '')


def test_prepare_output_dir_names_a_folder_nothing_can_be_written_into(tmp_path, monkeypatch):
  """A read-only or immutable folder failed only when each input's first file was
  written, after its unmixing, with no reason ('Cannot write image file')."""
  def refused(*args, **kwargs):
    raise OSError(30, 'Read-only file system')
  monkeypatch.setattr(input_listing.tempfile, 'TemporaryFile', refused)
  with pytest.raises(ValueError, match="Cannot write into the output folder "
                                       "--output_dir='.*out': Read-only file system"):
    input_listing.prepare_output_dir([], str(tmp_path / 'out'))


def test_output_names_are_unique_when_stems_collide():
  assert input_listing.output_names(['in/a.png', 'in/b.jpg']) == ['a', 'b']
  # Shared stem: the extension joins the name (its case kept).
  assert input_listing.output_names(['in/a.JPG', 'in/a.png', 'in/b.png']) == ['a_JPG', 'a_png', 'b']
  # Same file name in two folders of a glob: numbered in input order.
  assert input_listing.output_names(['x/a.png', 'y/a.png', 'z/a.png']) == ['a_png', 'a_png_2',
                                                                     'a_png_3']
  # A fallback equal to another input's stem, and names differing only in case, are
  # numbered too (case-insensitive file systems would merge them).
  assert input_listing.output_names(['a.jpg', 'a.png', 'a_png.bmp']) == [
      'a_jpg', 'a_png', 'a_png_2']
  assert input_listing.output_names(['A.png', 'a.png']) == ['A_png', 'a_png_2']
  # A numbered name never takes the plain name another input still wants.
  assert input_listing.output_names(['x/a.png', 'y/a.png', 'a_png_2.bmp']) == [
      'a_png', 'a_png_3', 'a_png_2']


def test_iter_inputs_names_collisions_in_a_folder(tmp_path):
  _write_png(tmp_path / 'a.png', 10)
  _write_png(tmp_path / 'a.jpg', 20)
  _write_png(tmp_path / 'b.png', 30)
  items = list(input_listing.iter_inputs(str(tmp_path)))
  assert [(os.path.basename(i.path), i.name) for i in items] == [
      ('a.jpg', 'a_jpg'), ('a.png', 'a_png'), ('b.png', 'b')]


def test_iter_inputs_errors(tmp_path):
  with pytest.raises(ValueError, match='not found'):
    list(input_listing.iter_inputs(str(tmp_path / 'missing.png')))
  with pytest.raises(ValueError, match='No images or videos'):
    list(input_listing.iter_inputs(str(tmp_path)))
  with pytest.raises(ValueError, match='match'):
    list(input_listing.iter_inputs(str(tmp_path / '*.png')))


def test_iter_inputs_marks_videos(tmp_path):
  (tmp_path / 'clip.mp4').write_bytes(b'')  # Only the name matters here.
  _write_png(tmp_path / 'still.png', 5)
  items = list(input_listing.iter_inputs(str(tmp_path / '*')))
  assert [(i.name, i.is_video) for i in items] == [('clip', True), ('still', False)]


def test_a_folder_notes_its_subfolders_and_skips_earlier_results(tmp_path, caplog):
  caplog.set_level(logging.INFO, logger='absl')
  (tmp_path / 'sub').mkdir()
  _write_png(tmp_path / 'sub' / 'deep.png', 10)
  with pytest.raises(ValueError, match=r"in folder .*; 1 subfolder\(s\) not searched: give "
                                       r"'.*\*\*/\*' to include them"):
    list(input_listing.iter_inputs(str(tmp_path)))
  _write_png(tmp_path / 'a.png', 10)
  _write_png(tmp_path / 'a_left.png', 20)
  assert [i.name for i in input_listing.iter_inputs(str(tmp_path))] == ['a', 'a_left']
  assert '1 subfolder(s) not searched' in caplog.text
  skip = {os.path.realpath(tmp_path / 'a_left.png')}
  assert [i.name for i in input_listing.iter_inputs(str(tmp_path), skip=skip)] == ['a']
  assert [i.name for i in input_listing.iter_inputs(str(tmp_path / 'a_left.png'), skip=skip)] == [
      'a_left']  # Named by itself: taken.
  with pytest.raises(ValueError, match='holds only results of earlier runs'):
    list(input_listing.iter_inputs(str(tmp_path / 'a_*.png'), skip=skip))


def test_a_link_to_a_parent_folder_lists_each_file_once(tmp_path):
  """`**` follows links: one to a parent folder made each file dozens of inputs and gave
  the real ones other names (scan_png_10)."""
  (tmp_path / 'scans' / 'box').mkdir(parents=True)
  for name in ('a.png', 'b.png'):
    (tmp_path / 'scans' / 'box' / name).write_bytes(b'x')
  os.symlink('..', tmp_path / 'scans' / 'box' / 'up')
  items = list(input_listing.iter_inputs(str(tmp_path / 'scans' / '**' / '*')))
  assert [(os.path.relpath(i.path, tmp_path), i.name) for i in items] == [
      (os.path.join('scans', 'box', 'a.png'), 'a'), (os.path.join('scans', 'box', 'b.png'), 'b')]


def test_brackets_in_a_folder_name_are_the_name_where_the_pattern_matches_nothing(tmp_path):
  (tmp_path / 'Box [1998]').mkdir()
  (tmp_path / 'Box [1998]' / 'a.png').write_bytes(b'x')
  items = list(input_listing.iter_inputs(str(tmp_path / 'Box [1998]' / '*.png')))
  assert [item.name for item in items] == ['a']
  (tmp_path / 'Box 1').mkdir()
  (tmp_path / 'Box 1' / 'b.png').write_bytes(b'x')  # A set that matches: glob's meaning.
  assert [i.name for i in input_listing.iter_inputs(str(tmp_path / 'Box [1]' / '*.png'))] == ['b']
