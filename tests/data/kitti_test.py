"""Tests for mixstereo_tf.data.kitti on tiny KITTI-layout folders written into tmp_path."""

import dataclasses
import logging
import os

import cv2
import numpy as np
import pytest

from mixstereo_tf.data import kitti
from mixstereo_tf.data import sources

_DRIVE = '2011_09_26/2011_09_26_drive_0002_sync'


def _image(path, value=0, shape=(8, 12)):
  os.makedirs(os.path.dirname(path), exist_ok=True)
  assert cv2.imwrite(str(path), np.full(shape + (3,), value, np.uint8))
  return str(path)


def _raw_frame(data_dir, frame, ext='.png'):
  for camera in ('image_02', 'image_03'):
    _image(os.path.join(data_dir, _DRIVE, camera, 'data', frame + ext))


def _list(tmp_path, text):
  path = tmp_path / 'files.txt'
  path.write_text(text)
  return str(path)


def _entry(frame, ext='.jpg'):
  return ' '.join(f'{_DRIVE}/{camera}/data/{frame}{ext}' for camera in ('image_02', 'image_03'))


def test_split_list_resolves_png_and_attaches_name_calib_source(tmp_path):
  data_dir = str(tmp_path / 'raw')
  _raw_frame(data_dir, '0000000069')
  list_path = _list(tmp_path, f'# monodepth list\n\n{_entry("0000000069")}\n')
  split = kitti.read_split_list(list_path, data_dir)
  assert split.skipped == [] and len(split.samples) == 1
  sample = split.samples[0]
  assert sample.name == '2011_09_26_drive_0002_sync/0000000069'
  assert sample.left == os.path.join(data_dir, _DRIVE, 'image_02', 'data', '0000000069.png')
  assert sample.right == os.path.join(data_dir, _DRIVE, 'image_03', 'data', '0000000069.png')
  assert sample.calib == os.path.join(data_dir, '2011_09_26')
  assert sample.source == f'{list_path}:3'
  assert sources.load_sample(sample)['left'].shape == (8, 12, 3)


def test_velodyne_path():
  left = f'/data/{_DRIVE}/image_02/data/0000000069.jpg'
  assert kitti.velodyne_path(left) == f'/data/{_DRIVE}/velodyne_points/data/0000000069.bin'
  with pytest.raises(ValueError, match='image_2/000000_10.png'):
    kitti.velodyne_path('training/image_2/000000_10.png')


def test_stereo_list_names_by_stem_without_calib(tmp_path):
  _image(tmp_path / 'training' / 'image_2' / '000003_10.png')
  _image(tmp_path / 'training' / 'image_3' / '000003_10.png')
  list_path = _list(tmp_path, 'training/image_2/000003_10.jpg training/image_3/000003_10.jpg\n')
  sample, = kitti.read_split_list(list_path, str(tmp_path)).samples
  assert sample.name == '000003_10' and sample.calib is None


def test_malformed_line_names_list_and_line(tmp_path):
  list_path = _list(tmp_path, f'{_entry("0000000001")}\nonly_one_field.jpg\n')
  with pytest.raises(ValueError, match=r"files\.txt:2: expected 'left right'.*only_one"):
    kitti.read_split_list(list_path, str(tmp_path), check_files=False)


def test_missing_file_names_list_line_and_path(tmp_path):
  data_dir = str(tmp_path / 'raw')
  _raw_frame(data_dir, '0000000001')
  list_path = _list(tmp_path, f'{_entry("0000000001")}\n{_entry("0000000002")}\n')
  with pytest.raises(ValueError, match=r'files\.txt:2: .*image_02/data/0000000002\.jpg'):
    kitti.read_split_list(list_path, data_dir)


def test_skip_bad_pairs_counts_skips(tmp_path):
  data_dir = str(tmp_path / 'raw')
  _raw_frame(data_dir, '0000000001')
  _raw_frame(data_dir, '0000000003', ext='.jpg')
  lines = [_entry(f'000000000{i}') for i in (1, 2, 3, 4)]
  split = kitti.read_split_list(_list(tmp_path, '\n'.join(lines)), data_dir,
                                skip_bad_pairs=True)
  assert [s.name[-1] for s in split.samples] == ['1', '3']
  assert len(split.skipped) == 2 and split.skipped_lines == [2, 4]
  assert 'files.txt:2' in split.skipped[0] and 'files.txt:4' in split.skipped[1]


def test_list_samples_reports_skipped_pairs(tmp_path, caplog):
  data_dir = str(tmp_path / 'raw')
  for frame in ('0000000001', '0000000004'):
    _raw_frame(data_dir, frame)
  list_path = _list(tmp_path, '\n'.join(['# header'] + [_entry(f'000000000{i}')
                                                         for i in (1, 2, 3, 4)]))
  config = sources.DataConfig(dataset='kitti_raw', data_dir=data_dir, split_list=list_path,
                              skip_bad_pairs=True)
  caplog.set_level(logging.WARNING)
  samples = sources.list_samples(config)
  assert [s.name[-1] for s in samples] == ['1', '4']
  summary = [r.getMessage() for r in caplog.records if 'skipped 2 of 4 pairs' in r.getMessage()]
  assert len(summary) == 1 and summary[0].endswith('at lines 3-4.'), caplog.text
  assert list_path in summary[0]
  caplog.clear()
  sources.list_samples(dataclasses.replace(config, split_list=_list(tmp_path, _entry(
      '0000000001'))))
  assert 'skipped' not in caplog.text


def test_check_files_false_keeps_paths_as_written(tmp_path):
  split = kitti.read_split_list(_list(tmp_path, _entry('0000000009')), str(tmp_path),
                                check_files=False)
  assert split.samples[0].left.endswith('image_02/data/0000000009.jpg')


def test_empty_list_and_all_skipped(tmp_path):
  with pytest.raises(ValueError, match="no pairs; expected lines 'left right'"):
    kitti.read_split_list(_list(tmp_path, '# nothing\n\n'), str(tmp_path))
  with pytest.raises(ValueError, match='1 skipped'):
    kitti.read_split_list(_list(tmp_path, _entry('0000000009')), str(tmp_path),
                          skip_bad_pairs=True)
  with pytest.raises(ValueError, match='not found.*absent.txt'):
    kitti.read_split_list(str(tmp_path / 'absent.txt'), str(tmp_path))


def _stereo_folder(root, folders, disparity_px=4):
  left_dir, right_dir, occ_dir, noc_dir = folders
  for frame in ('000000', '000001'):
    for suffix in ('_10', '_11'):
      _image(os.path.join(root, left_dir, frame + suffix + '.png'), 10)
      _image(os.path.join(root, right_dir, frame + suffix + '.png'), 20)
    occ = np.full((8, 12), 256 * disparity_px, np.uint16)
    occ[:, :2] = 0
    noc = occ.copy()
    noc[:, 2:4] = 0  # Occluded: GT in disp_occ only.
    for folder, array in ((occ_dir, occ), (noc_dir, noc)):
      os.makedirs(os.path.join(root, folder), exist_ok=True)
      assert cv2.imwrite(os.path.join(root, folder, frame + '_10.png'), array)


@pytest.mark.parametrize('version', ['2015', '2012'])
@pytest.mark.parametrize('give_split_folder', [False, True])
def test_kitti_stereo_samples(tmp_path, version, give_split_folder):
  folders = {'2015': ('image_2', 'image_3', 'disp_occ_0', 'disp_noc_0'),
             '2012': ('colored_0', 'colored_1', 'disp_occ', 'disp_noc')}[version]
  training = tmp_path / 'training'
  _stereo_folder(str(training), folders, disparity_px=4)
  data_dir = training if give_split_folder else tmp_path
  samples = kitti.kitti_stereo_samples(str(data_dir), version=version)
  assert [s.name for s in samples] == ['000000_10', '000001_10']
  assert samples[0].disparity_scale == 256
  loaded = sources.load_sample(samples[0])
  assert loaded['left'][0, 0, 0] == 10 and loaded['right'][0, 0, 0] == 20
  np.testing.assert_array_equal(loaded['disparity_left'][0], [0, 0] + [4] * 10)
  np.testing.assert_array_equal(loaded['valid_left'][0], [False] * 2 + [True] * 10)
  np.testing.assert_array_equal(loaded['nonocc_left'][0], [False] * 4 + [True] * 8)


def test_kitti_stereo_without_gt_and_bad_input(tmp_path):
  _image(tmp_path / 'testing' / 'image_2' / '000000_10.png')
  _image(tmp_path / 'testing' / 'image_3' / '000000_10.png')
  sample, = kitti.kitti_stereo_samples(str(tmp_path), split='testing')
  assert sample.disparity_left is None and sample.nonocc_left is None
  with pytest.raises(ValueError, match='image_2/\\*_10.png.*disp_occ_0'):
    kitti.kitti_stereo_samples(str(tmp_path / 'testing' / 'image_2'))
  with pytest.raises(ValueError, match='colored_0'):
    kitti.kitti_stereo_samples(str(tmp_path), version='2012')
  with pytest.raises(ValueError, match="'2013'"):
    kitti.kitti_stereo_samples(str(tmp_path), version='2013')
  os.remove(tmp_path / 'testing' / 'image_3' / '000000_10.png')
  with pytest.raises(ValueError, match='image_3/000000_10.png'):
    kitti.kitti_stereo_samples(str(tmp_path), split='testing')


def test_training_refuses_the_kitti2015_training_frames(tmp_path):
  from tests.evaluation import runner_test  # pylint: disable=g-import-not-at-top
  root = runner_test.make_kitti2015(tmp_path / 'kitti', frames=1)
  config = sources.DataConfig(dataset='kitti2015', data_dir=root)
  with pytest.raises(ValueError, match='KITTI 2015 training frames.*allow_evaluation_scenes'):
    sources.list_samples(config, split='train')
  assert len(sources.list_samples(config, split='heldout')) == 1
  assert len(sources.list_samples(dataclasses.replace(config, allow_evaluation_scenes=True),
                                  split='train')) == 1


def test_shipped_split_list_resolves_from_any_directory(tmp_path, monkeypatch):
  # The KITTI flagfiles name 'data_lists/kitti/...'; it resolves outside the repository root.
  data_dir = str(tmp_path / 'raw')
  _raw_frame(data_dir, '0000000069')
  monkeypatch.chdir(tmp_path)
  config = sources.DataConfig(dataset='kitti_raw', data_dir=data_dir,
                              split_list='data_lists/kitti/eigen_test_files.txt',
                              skip_bad_pairs=True)
  samples = sources.list_samples(config)
  assert [s.name for s in samples] == ['2011_09_26_drive_0002_sync/0000000069']
  assert samples[0].source.endswith(os.path.join('kitti', 'eigen_test_files.txt:1'))


@pytest.mark.parametrize('numbers, text', [([2, 3, 4, 7], '2-4, 7'), ([5], '5'),
                                           ([1, 3, 4], '1, 3-4'), ([], '')])
def test_line_ranges(numbers, text):
  assert kitti.line_ranges(numbers) == text


@pytest.mark.parametrize('given', ['data_dir', 'split_list'])
def test_files_for_the_generated_dataset_are_refused(given):
  # The default dataset ('sample') would ignore them and train on procedural scenes.
  with pytest.raises(ValueError, match=rf"DataConfig.{given} is given but dataset 'sample' "
                                       r'is generated .*kitti_raw, kitti2015'):
    sources.DataConfig(max_disparity=8, **{given: 'x'})
