"""Tests of the embedded `sample` source: records, virtual loading, Motorcycle, preview CLI."""

import os
import subprocess
import sys

import cv2
import numpy as np
import pytest
import skimage.data

from mixstereo_tf.data import records
from mixstereo_tf.data import sample
from mixstereo_tf.data import sources
from mixstereo_tf.ops import warp

_TINY = dict(height=32, width=64, max_disparity=16)
REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def test_train_records_are_unique_virtual_and_deterministic():
  train = sample.sample_records('train', num_scenes=5, **_TINY)
  assert len(train) == 5 and len({s.name for s in train}) == 5
  assert all(s.is_virtual and s.left != s.right for s in train)
  assert train == sample.sample_records('train', num_scenes=5, **_TINY)
  assert len(sample.sample_records('train', max_disparity=16)) == sample.DEFAULT_TRAIN_SCENES


def test_heldout_has_fixed_scenes_then_motorcycle():
  heldout = sample.sample_records('heldout', **_TINY)
  assert len(heldout) == sample.HELDOUT_SCENES + 1
  assert heldout[-1].name == 'motorcycle_div4'  # 59.9 px / 4 <= 15 < 59.9 px / 3.
  assert heldout[-1].left.startswith(sample.MOTORCYCLE_URI)
  train_names = {s.name for s in sample.sample_records('train', num_scenes=50, **_TINY)}
  assert not train_names & {s.name for s in heldout}


def test_seed_ranges_are_disjoint():
  assert sample.scene_seed('train', 0) == 0
  assert sample.scene_seed('train', 2**31 - 1) < sample.scene_seed('heldout', 0) == 2**31
  with pytest.raises(ValueError, match='outside'):
    sample.scene_seed('train', 2**31)


def test_load_virtual_returns_loaded_keys_and_renders_deterministically():
  first, heldout = (sample.sample_records(split, num_scenes=1, **_TINY)[0]
                    for split in ('train', 'heldout'))
  loaded = sources.load_sample(first)  # Dispatches virtual URIs to sample.load_virtual.
  assert set(loaded) == set(records.LOADED_KEYS)
  for key, dtype in records.LOADED_KEYS.items():
    assert loaded[key].dtype == dtype, key
    assert loaded[key].shape[:2] == (32, 64), key
  assert loaded['valid_left'].all() and loaded['valid_right'].all()
  assert 0.5 < loaded['nonocc_left'].mean() < 1.0
  assert not loaded['disc_left'].any()  # No discontinuity mask: nothing selected.
  assert (loaded['disparity_left'] > 0).all() and loaded['disparity_left'].max() < 15
  again = sample.load_virtual(first)
  for key in loaded:
    np.testing.assert_array_equal(loaded[key], again[key])
  assert not np.array_equal(loaded['left'], sample.load_virtual(heldout)['left'])


@pytest.mark.parametrize('uri', ['synthetic://test/0?h=32&w=64&d=16#left',
                                 'synthetic://train/x?h=32&w=64&d=16#left',
                                 'synthetic://train/0?h=32&w=64#left',
                                 'skimage://astronaut?factor=1#left',
                                 'synthetic://train/0?h=32&w=sixty&d=16#left'])
def test_bad_uris_name_the_record(uri):
  bad = records.StereoSample(name='bad', left=uri, right=uri, source='list.txt:3')
  with pytest.raises(ValueError, match='list.txt:3'):
    sample.load_virtual(bad)


def test_motorcycle_factor_is_smallest_fitting_integer():
  raw = skimage.data.stereo_motorcycle()[2]
  largest = float(raw[np.isfinite(raw)].max())
  for max_disparity in (96, 61, 60, 48, 32, 16, 8):
    factor = sample.motorcycle_factor(max_disparity)
    assert largest / factor <= max_disparity - 1
    assert factor == 1 or largest / (factor - 1) > max_disparity - 1
  assert sample.motorcycle_factor(96) == 1 and sample.motorcycle_factor(32) == 2


def test_motorcycle_downscale_keeps_left_referenced_geometry():
  left, _, raw = skimage.data.stereo_motorcycle()
  record = sample.sample_records('heldout', **dict(_TINY, max_disparity=32))[-1]
  loaded = sources.load_sample(record)
  assert record.name == 'motorcycle_div2' and loaded['left'].shape == (250, 370, 3)
  assert set(loaded) == set(records.LOADED_KEYS)
  assert not loaded['valid_right'].any() and not loaded['disparity_right'].any()
  assert not loaded['disc_left'].any()
  # A fully known 2x2 block: mean disparity / 2; blocks with an unknown pixel are unknown.
  blocks = raw[:500, :740].reshape(250, 2, 370, 2)
  known = np.isfinite(blocks).all(axis=(1, 3))
  np.testing.assert_array_equal(loaded['valid_left'], known)
  np.testing.assert_allclose(loaded['disparity_left'][known],
                             blocks.mean(axis=(1, 3))[known] / 2, rtol=1e-5)
  np.testing.assert_array_equal(loaded['left'][10, 20], np.rint(
      left[20:22, 40:42].reshape(4, 3).mean(0)).astype(np.uint8))
  assert loaded['disparity_left'].max() <= 31
  # Photometric check of the sign: the left pixel x matches the right pixel x - d.
  mask = loaded['nonocc_left']
  assert mask.mean() > 0.6 and not (mask & ~loaded['valid_left']).any()
  image = loaded['right'][None].astype(np.float32)
  disparity = loaded['disparity_left'][None, ..., None]
  correct = np.abs(warp.reconstruct_left(image, disparity).numpy()[0] - loaded['left'])[mask]
  flipped = np.abs(warp.reconstruct_right(image, disparity).numpy()[0] - loaded['left'])[mask]
  assert correct.mean() < 12.0 and correct.mean() < 0.5 * flipped.mean()


def test_occlusion_from_disparity_known_answer():
  # Background 2 px, a nearer 3-pixel strip of 6 px at x = 8..10: it covers right columns
  # 2..4, which background left pixels 4..6 would match; columns 0, 1 match outside.
  disparity = np.full((1, 16), 2.0, np.float32)
  disparity[0, 8:11] = 6.0
  occluded = sample.occlusion_from_disparity(disparity, np.ones_like(disparity, bool))
  np.testing.assert_array_equal(np.where(occluded[0])[0], [0, 1, 4, 5, 6])
  # Unknown pixels never occlude.
  valid = np.ones_like(occluded)
  valid[0, 8:11] = False
  occluded = sample.occlusion_from_disparity(disparity, valid)
  np.testing.assert_array_equal(np.where(occluded[0])[0], [0, 1])


def test_occlusion_rule_agrees_with_rendered_occlusions():
  record = sample.sample_records('train', num_scenes=1, height=64, width=128,
                                 max_disparity=32)[0]
  loaded = sample.load_virtual(record)
  occluded = sample.occlusion_from_disparity(loaded['disparity_left'], loaded['valid_left'])
  # Away from the right border (objects seen only by the right camera are invisible to the
  # left-only rule) the two masks differ only on a few depth-edge pixels.
  columns = slice(0, 128 - 26)
  assert (~loaded['nonocc_left'][:, columns]).any()
  assert np.mean(occluded[:, columns] == ~loaded['nonocc_left'][:, columns]) > 0.97


def test_preview_cli_writes_pngs(tmp_path):
  # A subprocess, like the other binaries' tests: absl flags are process-global.
  env = dict(os.environ, TF_CPP_MIN_LOG_LEVEL='3', CUDA_VISIBLE_DEVICES='',
             PYTHONPATH=REPO + os.pathsep + os.environ.get('PYTHONPATH', ''))
  result = subprocess.run(
      [sys.executable, '-m', 'mixstereo_tf.cli.preview', f'--output_dir={tmp_path}',
       '--mixture=anaglyph', '--num=2', '--height=32', '--width=64', '--max_disparity=16'],
      capture_output=True, text=True, env=env, cwd=REPO, timeout=300, check=False)
  assert result.returncode == 0, result.stderr[-2000:]
  names = sorted(os.listdir(tmp_path))
  assert len(names) == 10
  read = lambda key: cv2.imread(str(tmp_path / f'synthetic_train_00000_{key}.png'))[..., ::-1]
  left, right, mixture = read('left'), read('right'), read('mixture')
  # Anaglyph: red from the left view, green and blue from the right view.
  np.testing.assert_array_equal(mixture[..., 0], left[..., 0])
  np.testing.assert_array_equal(mixture[..., 1:], right[..., 1:])
  loaded = sample.load_virtual(sample.sample_records('train', num_scenes=1, **_TINY)[0])
  np.testing.assert_array_equal(left, loaded['left'])
  np.testing.assert_array_equal(read('disparity_left')[..., 0],
                                np.rint(loaded['disparity_left'] * 255 / 16).astype(np.uint8))
