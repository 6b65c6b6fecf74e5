"""Tests for mixstereo_tf.data.middlebury on tiny scene folders written into tmp_path."""

import dataclasses
import os

import cv2
import numpy as np
import pytest

from mixstereo_tf.data import middlebury
from mixstereo_tf.data import sources
from mixstereo_tf.data import split_lists
from tests import data_helpers

_SHAPE = (8, 12)


def _write(folder, name, array):
  os.makedirs(folder, exist_ok=True)
  path = os.path.join(folder, name)
  assert cv2.imwrite(path, array), path
  return path


def _views(folder, left_name, right_name):
  # PGM holds gray only; the reader copies gray to the three channels.
  channels = () if left_name.endswith('.pgm') else (3,)
  _write(folder, left_name, np.full(_SHAPE + channels, 10, np.uint8))
  _write(folder, right_name, np.full(_SHAPE + channels, 20, np.uint8))


def _tsukuba(folder, stored=80):
  _views(folder, 'scene1.row3.col3.ppm', 'scene1.row3.col4.ppm')
  _write(folder, 'truedisp.row3.col3.pgm', np.full(_SHAPE, stored, np.uint8))


def _classic(folder, stored=20, ext='.ppm'):
  _views(folder, 'im2' + ext, 'im6' + ext)
  _write(folder, 'disp2.pgm', np.full(_SHAPE, stored, np.uint8))
  _write(folder, 'disp6.png', np.full(_SHAPE, stored, np.uint8))


def _scene_2014(folder, disparity_name='disp0.pfm'):
  _views(folder, 'im0.png', 'im1.png')
  disparity = np.full(_SHAPE, 37.25, np.float32)
  disparity[0, 0] = np.inf
  data_helpers.write_pfm(os.path.join(folder, disparity_name), disparity)
  mask = np.full(_SHAPE, 255, np.uint8)
  mask[1, :3] = [128, 0, 255]
  _write(folder, 'mask0nocc.png', mask)
  with open(os.path.join(folder, 'calib.txt'), 'w') as f:
    f.write('cam0=[3979.911 0 1244.772; 0 3979.911 1019.507; 0 0 1]\n'
            'cam1=[3979.911 0 1369.115; 0 3979.911 1019.507; 0 0 1]\n'
            'doffs=124.343\nbaseline=193.001\nwidth=2964\nheight=1988\nndisp=270\n'
            'isint=0\nvmin=23\nvmax=245\ndyavg=-0.031\ndymax=0.320\n')


def test_tsukuba_scale_and_official_masks(tmp_path):
  folder = str(tmp_path / 'tsukuba')
  _tsukuba(folder, stored=80)
  all_mask = np.full(_SHAPE, 255, np.uint8)
  all_mask[:, 0] = 0
  nonocc = all_mask.copy()
  nonocc[:, 1] = 0
  _write(folder, 'all.png', all_mask)
  _write(folder, 'nonocc.png', nonocc)
  disc = np.zeros(_SHAPE, np.uint8)
  disc[:, :3] = 255  # Column 0 is outside all.png, so only columns 1-2 remain.
  disc[:, 3] = 128  # Gray (occluded or not near a discontinuity) is not evaluated.
  _write(folder, 'disc.png', disc)
  sample, = middlebury.middlebury_samples(str(tmp_path))
  assert sample.name == 'tsukuba' and sample.disparity_scale == 16
  assert sample.disc_left == os.path.join(folder, 'disc.png')
  loaded = sources.load_sample(sample)
  assert loaded['left'][0, 0, 0] == 10 and loaded['right'][0, 0, 0] == 20
  np.testing.assert_array_equal(loaded['disparity_left'][0], [0] + [5] * 11)
  np.testing.assert_array_equal(loaded['valid_left'][0], [False] + [True] * 11)
  np.testing.assert_array_equal(loaded['nonocc_left'][0], [False] * 2 + [True] * 10)
  np.testing.assert_array_equal(loaded['disc_left'],
                                np.broadcast_to([False, True, True] + [False] * 9, _SHAPE))
  assert not loaded['valid_right'].any()


@pytest.mark.parametrize('scene, pixels', [('Cones', 5.0), ('teddy', 5.0), ('Venus', 2.5),
                                           ('bull', 2.5), ('TSUKUBA', 1.25)])
def test_classic_scale_by_folder_name(tmp_path, scene, pixels):
  _classic(str(tmp_path / scene), stored=20)
  sample, = middlebury.middlebury_samples(str(tmp_path))
  loaded = sources.load_sample(sample)
  assert sample.name == scene
  np.testing.assert_allclose(loaded['disparity_left'], pixels)
  np.testing.assert_allclose(loaded['disparity_right'], pixels)
  assert loaded['nonocc_left'].all()  # No occlusion information: equals valid_left.
  assert sample.disc_left is None and not loaded['disc_left'].any()  # No disc.png.


@pytest.mark.parametrize('ext', ['.ppm', '.png', '.pgm'])
def test_classic_image_formats(tmp_path, ext):
  _classic(str(tmp_path / 'venus'), ext=ext)
  sample, = middlebury.middlebury_samples(str(tmp_path))
  assert sample.left.endswith('im2' + ext) and sample.right.endswith('im6' + ext)
  loaded = sources.load_sample(sample)
  assert loaded['left'].shape == _SHAPE + (3,)
  np.testing.assert_array_equal(loaded['left'][3, 4], [10, 10, 10])
  np.testing.assert_array_equal(loaded['right'][3, 4], [20, 20, 20])
  np.testing.assert_allclose(loaded['disparity_left'], 2.5)


def test_scale_overrides(tmp_path):
  _classic(str(tmp_path / 'Cones'))
  _classic(str(tmp_path / 'map'))
  samples = middlebury.middlebury_samples(str(tmp_path), scale_overrides={'MAP': 2})
  assert {s.name: s.disparity_scale for s in samples} == {'Cones': 4, 'map': 2}
  with pytest.raises(ValueError, match="not found.*'teddy'"):
    middlebury.middlebury_samples(str(tmp_path), scale_overrides={'teddy': 4})
  with pytest.raises(ValueError, match='positive'):
    middlebury.middlebury_samples(str(tmp_path), scale_overrides={'map': 0})


def test_nested_2014_scene(tmp_path):
  folder = str(tmp_path / '2014' / 'Motorcycle-perfect')
  _scene_2014(folder)
  os.makedirs(tmp_path / 'notes')  # Matches no layout: skipped.
  sample, = middlebury.middlebury_samples(str(tmp_path))
  assert sample.name == 'Motorcycle-perfect' and sample.disparity_scale == 1
  assert sample.calib == os.path.join(folder, 'calib.txt')
  loaded = sources.load_sample(sample)
  assert loaded['disparity_left'][0, 0] == 0 and not loaded['valid_left'][0, 0]
  assert loaded['disparity_left'][0, 1] == np.float32(37.25)
  np.testing.assert_array_equal(loaded['nonocc_left'][1, :4], [False, False, True, True])


def test_2014_scene_with_disp0gt(tmp_path):
  folder = str(tmp_path / 'Adirondack')
  _scene_2014(folder, disparity_name='disp0GT.pfm')
  sample, = middlebury.middlebury_samples(str(tmp_path))
  assert sample.disparity_left == os.path.join(folder, 'disp0GT.pfm')
  loaded = sources.load_sample(sample)
  assert loaded['disparity_left'][2, 5] == np.float32(37.25) and not loaded['valid_left'][0, 0]


def test_scale_overrides_are_validated():
  with pytest.raises(ValueError, match="DataConfig.middlebury_scales apply to dataset "
                                       "'middlebury' only"):
    sources.DataConfig(dataset='sample', max_disparity=8, middlebury_scales=(('venus', 8.0),))
  for pair in (('venus', -1.0), ('venus', 0.0), ('', 8.0), ('venus', float('inf'))):
    with pytest.raises(ValueError, match='DataConfig.middlebury_scales: expected'):
      sources.DataConfig(dataset='middlebury', data_dir='x', middlebury_scales=(pair,))
  with pytest.raises(ValueError, match="scene 'VENUS' is given twice"):
    sources.DataConfig(dataset='middlebury', data_dir='x',
                       middlebury_scales=(('venus', 8.0), ('VENUS', 4.0)))


def test_scale_override_reaches_the_loaded_sample(tmp_path):
  _classic(str(tmp_path / 'Cones'), stored=20)
  _classic(str(tmp_path / 'map'), stored=20)
  config = sources.DataConfig(dataset='middlebury', data_dir=str(tmp_path),
                              middlebury_scales=(('cones', 10.0),))
  samples = {s.name: s for s in sources.list_samples(config, split='heldout')}
  assert samples['Cones'].disparity_scale == 10 and samples['map'].disparity_scale == 8
  np.testing.assert_allclose(sources.load_sample(samples['Cones'])['disparity_left'], 2.0)


def test_data_dir_is_one_scene(tmp_path):
  _scene_2014(str(tmp_path / 'Piano'))
  sample, = middlebury.middlebury_samples(str(tmp_path / 'Piano') + os.sep)
  assert sample.name == 'Piano'


def test_duplicate_scene_names_use_relative_paths(tmp_path):
  _classic(str(tmp_path / '2001' / 'venus'))
  _classic(str(tmp_path / 'copy' / 'venus'))
  names = [s.name for s in middlebury.middlebury_samples(str(tmp_path))]
  assert names == ['2001/venus', 'copy/venus']


def test_no_scene_lists_layouts(tmp_path):
  os.makedirs(tmp_path / 'a' / 'b')
  _views(str(tmp_path / 'a'), 'im2.ppm', 'im3.ppm')  # im6 missing: not a scene.
  with pytest.raises(ValueError, match='No Middlebury scene.*im0.png.*scene1.row3.*im2'):
    middlebury.middlebury_samples(str(tmp_path))
  with pytest.raises(ValueError, match='not a folder'):
    middlebury.middlebury_samples(str(tmp_path / 'missing'))


def test_training_refuses_the_papers_evaluation_scenes(tmp_path):
  for name in ('Teddy', 'venus', 'Motorcycle-perfect', 'Art'):
    _classic(str(tmp_path / name))
  config = sources.DataConfig(dataset='middlebury', data_dir=str(tmp_path))
  with pytest.raises(ValueError, match=r'Middlebury scenes Motorcycle-perfect, Teddy, venus.*'
                                       r'DataConfig.allow_evaluation_scenes'):
    sources.list_samples(config, split='train')
  # Evaluation reads them, and an explicit override lets training read them too.
  assert len(sources.list_samples(config, split='heldout')) == 4
  allowed = sources.DataConfig(dataset='middlebury', data_dir=str(tmp_path),
                               allow_evaluation_scenes=True)
  assert len(sources.list_samples(allowed, split='train')) == 4
  assert [middlebury.is_evaluation_scene(n) for n in (
      'Aloe', 'cones', '2001/Tsukuba', 'MotorcycleE-imperfect', 'Art', 'Adirondack')] == [
          True, True, True, True, False, False]


def test_a_training_scene_deeper_than_the_levels_is_shrunk_to_fit(tmp_path):
  _scene_2014(str(tmp_path / 'Adirondack-perfect'))  # 8x12, 37.25 px, (0, 0) unknown.
  config = sources.DataConfig(dataset='middlebury', data_dir=str(tmp_path), max_disparity=8)
  train, = sources.list_samples(config, split='train')
  heldout, = sources.list_samples(config, split='heldout')
  assert train.fit_disparity == 8 and heldout.fit_disparity is None
  loaded = sources.load_sample(train)  # k = ceil(37.25 / 7) = 6: 1x2 blocks.
  assert loaded['left'].shape == (1, 2, 3) and loaded['left'][0, 0, 0] == 10
  np.testing.assert_array_equal(loaded['valid_left'], [[False, True]])
  np.testing.assert_allclose(loaded['disparity_left'], [[0, 37.25 / 6]], rtol=1e-6)
  # Evaluation reads the scene as stored, and so does training with fit_disparity off.
  assert sources.load_sample(heldout)['left'].shape == (8, 12, 3)
  unfit = dataclasses.replace(config, fit_disparity=False)
  assert sources.list_samples(unfit, split='train')[0].fit_disparity is None


def test_a_scene_list_selects_scenes_and_the_guard_still_refuses_evaluation_ones(tmp_path):
  for name in ('Adirondack-perfect', 'Adirondack-imperfect', 'Piano-perfect'):
    _scene_2014(str(tmp_path / name))
  _classic(str(tmp_path / 'Teddy'))
  listed = tmp_path / 'scenes.txt'
  listed.write_text('# training scenes\nadirondack\n\nbarn1  # 2001, not downloaded\n')
  config = sources.DataConfig(dataset='middlebury', data_dir=str(tmp_path),
                              split_list=str(listed))
  names = sorted(s.name for s in sources.list_samples(config, split='train'))
  assert names == ['Adirondack-imperfect', 'Adirondack-perfect']  # Teddy is not listed.
  _, missing = middlebury.select_scenes(middlebury.middlebury_samples(str(tmp_path)),
                                        middlebury.read_scene_list(str(listed)), 'list')
  assert missing == ['barn1']
  listed.write_text('Piano\nTeddy\n')
  with pytest.raises(ValueError, match='Middlebury scenes Teddy.*allow_evaluation_scenes'):
    sources.list_samples(config, split='train')
  listed.write_text('Vintage\n')
  with pytest.raises(ValueError, match='None of the 1 scenes of .*scenes.txt'):
    sources.list_samples(config, split='train')


def test_the_shipped_finetune_list_names_no_evaluation_scene():
  path = split_lists.resolve('data_lists/middlebury/finetune_scenes.txt')
  names = middlebury.read_scene_list(path)
  assert len(names) == 26 and 'Adirondack' in names and 'barn1' in names
  assert not [n for n in names if middlebury.is_evaluation_scene(n)]
