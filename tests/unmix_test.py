"""Tests for the unmix tool (mixstereo_tf.unmixing and the unmix binary)."""

import os
import subprocess
import sys

import cv2
import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf import inference
from mixstereo_tf import media
from mixstereo_tf import models
from mixstereo_tf import serving
from mixstereo_tf import unmixing
from tests import inference_test

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
INFO = inference.RunInfo('anaglyph', 64, 128, inference_test.TINY)


@pytest.fixture(scope='module')
def model():
  tf.keras.utils.set_random_seed(5)
  return models.build_model(inference_test.TINY)


@pytest.fixture(scope='module')
def setup(model):
  unmixer = inference.Unmixer.from_model(model, INFO)
  return unmixing.Unmixing(unmixer, 'anaglyph', 8.0)


def _image(path, shape=(40, 50, 3), seed=0):
  image = np.random.RandomState(seed).randint(0, 256, shape).astype(np.uint8)
  media.write_image(str(path), image)
  return image


def test_every_layout_for_one_image(setup, tmp_path):
  _image(tmp_path / 'scene.png')
  expected = {'separate': ['scene_left.png', 'scene_right.png'], 'sbs': ['scene_sbs.png'],
              'sbs_half': ['scene_sbs_half.png'], 'tb': ['scene_tb.png']}
  shapes = {'scene_left.png': (40, 50, 3), 'scene_right.png': (40, 50, 3),
            'scene_sbs.png': (40, 100, 3), 'scene_sbs_half.png': (40, 50, 3),
            'scene_tb.png': (80, 50, 3)}
  for layout, names in expected.items():
    out = tmp_path / layout
    report = unmixing.unmix_inputs(setup, str(tmp_path / 'scene.png'), str(out), layout)
    assert (report.processed, report.frames, report.failures) == (1, 1, [])
    common = ['scene_disparity.png', 'scene_disparity16.png', 'scene_disparity.npy']
    assert sorted(os.listdir(out)) == sorted(names + common)
    for name in names:
      assert media.read_image(str(out / name)).shape == shapes[name]
  # The three disparity files agree with each other and with the unmixer.
  disparity = np.load(tmp_path / 'tb' / 'scene_disparity.npy')
  direct = setup.fn(media.read_image(str(tmp_path / 'scene.png')))['disparity_left']
  np.testing.assert_allclose(disparity, direct, atol=1e-5)
  raw = cv2.imread(str(tmp_path / 'tb' / 'scene_disparity16.png'), cv2.IMREAD_UNCHANGED)
  assert raw.dtype == np.uint16
  np.testing.assert_allclose(raw / 256.0, disparity, atol=1 / 512 + 1e-6)
  colour = media.read_image(str(tmp_path / 'tb' / 'scene_disparity.png'))
  np.testing.assert_array_equal(colour, media.colorize_disparity(disparity, 8.0))


def test_folder_with_a_corrupt_file_and_a_gray_image(setup, tmp_path):
  folder = tmp_path / 'in'
  folder.mkdir()
  _image(folder / 'a.png')
  (folder / 'b.png').write_bytes(b'\x89PNG\r\n\x1a\n truncated')
  cv2.imwrite(str(folder / 'c.jpg'), np.full((33, 47), 90, np.uint8))  # Gray.
  report = unmixing.unmix_inputs(setup, str(folder), str(tmp_path / 'out'), 'sbs_half')
  assert report.processed == 2 and report.frames == 2
  assert [os.path.basename(p) for p, _ in report.failures] == ['b.png']
  assert 'b.png' in report.failures[0][1]
  assert unmixing.failure_message(report) is None
  assert media.read_image(str(tmp_path / 'out' / 'c_sbs_half.png')).shape == (33, 47, 3)
  assert not os.path.exists(tmp_path / 'out' / 'b_disparity.npy')
  # Nothing readable: the report asks for a non-zero exit.
  os.remove(folder / 'a.png')
  os.remove(folder / 'c.jpg')
  report = unmixing.unmix_inputs(setup, str(folder), str(tmp_path / 'out2'))
  assert report.processed == 0 and len(report.failures) == 1
  assert 'all 1 input(s) failed' in unmixing.failure_message(report)


def test_video(setup, tmp_path):
  path = str(tmp_path / 'clip.avi')
  with media.VideoWriter(path, fps=10.0) as writer:
    for seed in range(3):
      writer.write(np.random.RandomState(seed).randint(0, 256, (64, 96, 3)).astype(np.uint8))
  report = unmixing.unmix_inputs(setup, path, str(tmp_path / 'out'), 'tb')
  assert (report.processed, report.frames) == (1, 3) and report.frames_per_second > 0
  for name, shape in (('clip_tb.mp4', (128, 96, 3)), ('clip_disparity.mp4', (64, 96, 3))):
    fps, frames = media.video_frames(str(tmp_path / 'out' / name))
    frames = list(frames)
    assert len(frames) == 3 and frames[0].shape == shape and fps == pytest.approx(10.0)


def test_make_unmixing_checks_its_arguments(tmp_path):
  with pytest.raises(ValueError, match='exactly one'):
    unmixing.make_unmixing('model')
  with pytest.raises(ValueError, match='exactly one'):
    unmixing.make_unmixing('model', saved_model='a', checkpoint='b')
  with pytest.raises(ValueError, match='classical'):
    unmixing.make_unmixing('classical', saved_model='a', mixture='anaglyph')
  with pytest.raises(ValueError, match='--mixture'):
    unmixing.make_unmixing('classical')
  with pytest.raises(ValueError, match='anaglyph'):
    unmixing.make_unmixing('model', checkpoint='x', mixture='no_such_mixture')
  run_dir = str(tmp_path / 'run')
  inference_test.make_run_dir(run_dir, mixture='diplopia')
  with pytest.raises(ValueError, match="trained on 'diplopia'"):
    unmixing.make_unmixing('model', checkpoint=run_dir, mixture='anaglyph')
  setup = unmixing.make_unmixing('model', checkpoint=run_dir)
  assert setup.mixture == 'diplopia'
  assert setup.default_max_disparity == inference_test.TINY.max_disparity


def test_classical_method(tmp_path):
  with pytest.raises(ValueError, match='monocular'):
    unmixing.make_unmixing('classical', mixture='monocular')
  setup = unmixing.make_unmixing('classical', mixture='anaglyph')
  mixture = _image(tmp_path / 'x.png', (30, 44, 3))
  report = unmixing.unmix_inputs(setup, str(tmp_path / 'x.png'), str(tmp_path / 'out'))
  assert report.processed == 1 and not report.failures
  left = media.read_image(str(tmp_path / 'out' / 'x_left.png'))
  right = media.read_image(str(tmp_path / 'out' / 'x_right.png'))
  np.testing.assert_array_equal(left[..., 0], mixture[..., 0])  # Red-cyan channels kept.
  np.testing.assert_array_equal(right[..., 1:], mixture[..., 1:])
  assert np.load(tmp_path / 'out' / 'x_disparity.npy').shape == (30, 44)


def test_unmix_binary_on_a_saved_model(model, tmp_path):
  export_dir = str(tmp_path / 'export')
  serving.export_saved_model(model, INFO, export_dir)
  folder = tmp_path / 'in'
  folder.mkdir()
  _image(folder / 'a.png', (37, 41, 3))
  (folder / 'broken.jpg').write_bytes(b'garbage')
  out = tmp_path / 'out'
  env = dict(os.environ, TF_CPP_MIN_LOG_LEVEL='2')
  result = subprocess.run(
      [sys.executable, '-m', 'mixstereo_tf.unmix', f'--saved_model={export_dir}',
       '--mixture=anaglyph', f'--input={folder}/*', f'--output_dir={out}', '--layout=sbs',
       '--max_display_disparity=4'], capture_output=True, text=True, env=env, cwd=REPO,
      timeout=300, check=False)
  assert result.returncode == 0, result.stderr[-3000:]
  assert 'broken.jpg' in result.stderr and 'frames/s' in result.stderr
  assert sorted(os.listdir(out)) == ['a_disparity.npy', 'a_disparity.png',
                                     'a_disparity16.png', 'a_sbs.png']
  left_half = media.read_image(str(out / 'a_sbs.png'))[:, :41]
  mixture = media.read_image(str(folder / 'a.png'))
  np.testing.assert_array_equal(left_half[..., 0], mixture[..., 0])  # Colour restored.
  colour = media.read_image(str(out / 'a_disparity.png'))
  np.testing.assert_array_equal(
      colour, media.colorize_disparity(np.load(out / 'a_disparity.npy'), 4.0))
