"""Tests for the unmix tool (mixstereo_tf.unmixing and the unmix binary)."""

import io
import logging
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


class _Terminal(io.StringIO):
  """A stream that says it is a terminal, so progress is drawn on it."""

  def isatty(self):
    return True


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
  terminal = _Terminal()
  report = unmixing.unmix_inputs(setup, str(folder), str(tmp_path / 'out'), 'sbs_half',
                                 progress_stream=terminal)
  assert report.processed == 2 and report.frames == 2
  assert '[##########] 3/3' in terminal.getvalue() and terminal.getvalue().endswith('\n')
  assert [os.path.basename(p) for p, _ in report.failures] == ['b.png']
  assert 'b.png' in report.failures[0][1]
  assert unmixing.failure_message(report) == (
      f'error: 1 of 3 input(s) failed: {folder / "b.png"}')
  assert media.read_image(str(tmp_path / 'out' / 'c_sbs_half.png')).shape == (33, 47, 3)
  assert not os.path.exists(tmp_path / 'out' / 'b_disparity.npy')
  # Nothing readable: the report asks for a non-zero exit.
  os.remove(folder / 'a.png')
  os.remove(folder / 'c.jpg')
  report = unmixing.unmix_inputs(setup, str(folder), str(tmp_path / 'out2'))
  assert report.processed == 0 and len(report.failures) == 1
  assert '1 of 1 input(s) failed' in unmixing.failure_message(report)


def test_video(setup, tmp_path):
  path = str(tmp_path / 'clip.avi')
  with media.VideoWriter(path, fps=10.0) as writer:
    for seed in range(3):
      writer.write(np.random.RandomState(seed).randint(0, 256, (64, 96, 3)).astype(np.uint8))
  terminal = _Terminal()
  report = unmixing.unmix_inputs(setup, path, str(tmp_path / 'out'), 'tb',
                                 progress_stream=terminal)
  assert (report.processed, report.frames) == (1, 3) and report.frames_per_second > 0
  # One video: only its frame bar, whose total is the container's frame count.
  assert terminal.getvalue().startswith('\rclip.avi  [###') and terminal.getvalue().endswith('\n')
  assert 'clip.avi  [##########] 3/3  ' in terminal.getvalue()
  for name, shape in (('clip_tb.mp4', (128, 96, 3)), ('clip_disparity.mp4', (64, 96, 3))):
    fps, _, frames = media.video_frames(str(tmp_path / 'out' / name))
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
  # The broken file is named, the good one still unmixed, and the run ends non-zero.
  assert result.returncode == 1, result.stderr[-3000:]
  assert 'broken.jpg' in result.stderr and 'frames/s' in result.stderr
  assert 'error: 1 of 2 input(s) failed' in result.stderr
  assert sorted(os.listdir(out)) == ['a_disparity.npy', 'a_disparity.png',
                                     'a_disparity16.png', 'a_sbs.png']
  left_half = media.read_image(str(out / 'a_sbs.png'))[:, :41]
  mixture = media.read_image(str(folder / 'a.png'))
  np.testing.assert_array_equal(left_half[..., 0], mixture[..., 0])  # Colour restored.
  colour = media.read_image(str(out / 'a_disparity.png'))
  np.testing.assert_array_equal(
      colour, media.colorize_disparity(np.load(out / 'a_disparity.npy'), 4.0))


def test_inputs_sharing_a_stem_keep_their_own_outputs(setup, tmp_path):
  folder = tmp_path / 'in'
  folder.mkdir()
  _image(folder / 'a.png', seed=1)
  _image(folder / 'a.jpg', seed=2)
  out = tmp_path / 'out'
  report = unmixing.unmix_inputs(setup, str(folder / 'a.*'), str(out))
  assert report.processed == 2 and not report.failures
  assert sorted(os.listdir(out)) == sorted(
      f'a_{ext}_{suffix}' for ext in ('png', 'jpg') for suffix in (
          'left.png', 'right.png', 'disparity.png', 'disparity16.png', 'disparity.npy'))
  for ext in ('png', 'jpg'):
    expected = setup.fn(media.read_image(str(folder / f'a.{ext}')))['disparity_left']
    np.testing.assert_allclose(np.load(out / f'a_{ext}_disparity.npy'), expected, atol=1e-5)


def test_tensorflow_and_file_system_errors_skip_only_their_input(tmp_path):
  def unmix(image):
    value = int(image[0, 0, 0])
    if value == 10:
      raise tf.errors.ResourceExhaustedError(None, None, 'OOM when allocating\n  (trace)')
    if value == 20:
      raise OSError(28, 'No space left on device')
    if value == 40:
      raise KeyError('a bug, not a bad input')
    return {'left': image, 'right': image,
            'disparity_left': np.zeros(image.shape[:2], np.float32)}

  folder = tmp_path / 'in'
  folder.mkdir()
  for name, value in (('a', 10), ('b', 20), ('c', 30)):
    media.write_image(str(folder / f'{name}.png'), np.full((8, 8, 3), value, np.uint8))
  report = unmixing.unmix_inputs(unmixing.Unmixing(unmix, 'anaglyph', 8.0), str(folder),
                                 str(tmp_path / 'out'))
  assert report.processed == 1 and os.path.exists(tmp_path / 'out' / 'c_left.png')
  assert report.failures == [
      (str(folder / 'a.png'), 'ResourceExhaustedError: OOM when allocating'),
      (str(folder / 'b.png'), 'OSError: [Errno 28] No space left on device')]
  assert unmixing.failure_message(report).startswith('error: 2 of 3 input(s) failed: ')
  # Anything else is a bug and stops the run rather than being reported as a bad input.
  media.write_image(str(folder / 'd.png'), np.full((8, 8, 3), 40, np.uint8))
  with pytest.raises(KeyError):
    unmixing.unmix_inputs(unmixing.Unmixing(unmix, 'anaglyph', 8.0), str(folder),
                          str(tmp_path / 'out2'))


@pytest.mark.parametrize('args, line', [
    ((3, 10, 2.5), '[###.......] 3/10  1.2 frames/s  ETA 6 s'),
    ((0, 10, 0.0), '[..........] 0/10  0.0 frames/s  ETA ?'),
    ((10, 10, 4.0), '[##########] 10/10  2.5 frames/s  ETA 0 s'),
    ((12, 10, 6.0), '[##########] 12/10  2.0 frames/s  ETA 0 s'),  # A wrong frame count.
    ((1, 100, 2.0), '[..........] 1/100  0.5 frames/s  ETA 3 min 18 s'),
    ((2, 4, 10.0, 50, 'clip.mp4'), 'clip.mp4  [#####.....] 2/4  5.0 frames/s  ETA 10 s'),
    ((37, None, 10.0), '37 done  3.7 frames/s'),
])
def test_format_progress(args, line):
  assert unmixing.format_progress(*args) == line


def _clock(*times):
  return iter(times).__next__


def test_progress_bar_redraws_a_terminal_line():
  terminal = _Terminal()
  bar = unmixing.ProgressBar(3, stream=terminal, clock=_clock(0.0, 30.0, 30.1, 31.0))
  bar.update(1)  # t = 30: shown.
  bar.update(2)  # t = 30.1: within the redraw interval, skipped.
  bar.update(3)  # t = 31: the last one is always shown.
  bar.close()
  first = '[###.......] 1/3  0.0 frames/s  ETA 1 min 00 s'
  last = '[##########] 3/3  0.1 frames/s  ETA 0 s'
  # The shorter last line is padded so nothing of the first one remains.
  assert terminal.getvalue() == '\r' + first + '\r' + last.ljust(len(first)) + '\n'
  terminal = _Terminal()
  bar = unmixing.ProgressBar(None, 'v.mp4', terminal, clock=_clock(0.0, 1.0, 2.0))
  bar.update(4)
  bar.clear()  # Before a log message: the line is blanked and the next update redraws.
  bar.update(4)
  line = 'v.mp4  4 done  4.0 frames/s'
  assert terminal.getvalue() == (f'\r{line}\r{" " * len(line)}\r'
                                 f'\rv.mp4  4 done  2.0 frames/s')


def test_progress_bar_logs_lines_when_not_a_terminal(caplog):
  stream = io.StringIO()
  bar = unmixing.ProgressBar(3, stream=stream, clock=_clock(0.0, 1.0, 5.0, 12.0),
                             log_seconds=10.0)
  with caplog.at_level(logging.INFO, logger='absl'):
    for done in (1, 2, 3):
      bar.update(done)
    bar.close()
  assert stream.getvalue() == ''
  assert [r.getMessage() for r in caplog.records] == [
      '[###.......] 1/3  1.0 frames/s  ETA 2 s', '[##########] 3/3  0.2 frames/s  ETA 0 s']


def test_failure_message_names_at_most_five_inputs():
  assert unmixing.failure_message(unmixing.UnmixReport(processed=3)) is None
  report = unmixing.UnmixReport(processed=1, failures=[(f'{i}.png', 'bad') for i in range(7)])
  assert unmixing.failure_message(report) == (
      'error: 7 of 8 input(s) failed: 0.png, 1.png, 2.png, 3.png, 4.png, ...')
