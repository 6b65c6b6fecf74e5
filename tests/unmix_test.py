"""Tests for the unmix binary (mixstereo_tf.unmix)."""

import json
import os
import subprocess
import sys

import cv2
import numpy as np
import pytest
import skimage.data
import tensorflow as tf

from mixstereo_tf import models
from mixstereo_tf.artifacts import graphs
from mixstereo_tf.artifacts import runs
from mixstereo_tf.artifacts import serving
from mixstereo_tf.cli import input_images
from mixstereo_tf.cli import media
from mixstereo_tf.core import colormap
from mixstereo_tf.core import mixtures
from tests.unmixing import detection_test
from tests.unmixing import predictors_test

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
INFO = runs.RunInfo('anaglyph', 64, 128, predictors_test.TINY)


@pytest.fixture(scope='module')
def model():
  tf.keras.utils.set_random_seed(5)
  return models.build_model(predictors_test.TINY)


def _image(path, shape, seed=0):
  image = np.random.RandomState(seed).randint(0, 256, shape).astype(np.uint8)
  media.write_image(str(path), image)
  return image


def test_unmix_binary_on_a_saved_model(model, tmp_path):
  export_dir = str(tmp_path / 'export')
  serving.export_saved_model(graphs.serving_function(model), model.variables, INFO,
                             export_dir)
  folder = tmp_path / 'in'
  folder.mkdir()
  _image(folder / 'a.png', (37, 41, 3))
  (folder / 'broken.jpg').write_bytes(b'garbage')
  out = tmp_path / 'out'
  env = dict(os.environ, TF_CPP_MIN_LOG_LEVEL='2')
  result = subprocess.run(
      [sys.executable, '-m', 'mixstereo_tf.unmix', f'--saved_model={export_dir}',
       '--mixture=anaglyph', f'--input={folder}/*', f'--output_dir={out}', '--layout=sbs',
       '--max_display_disparity=4', '--disparity_range=0,7'], capture_output=True, text=True, env=env, cwd=REPO,
      timeout=300, check=False)
  # The broken file is named, the good one still unmixed, and the run ends non-zero.
  assert result.returncode == 1, result.stderr[-3000:]
  assert 'broken.jpg' in result.stderr and 'frames/s' in result.stderr
  assert 'error: 1 of 2 input(s) failed' in result.stderr
  assert sorted(os.listdir(out)) == ['a_disparity.npy', 'a_disparity.png',
                                     'a_disparity16.png', 'a_info.json', 'a_sbs.png']
  left_half = input_images.read_image(str(out / 'a_sbs.png'))[:, :41]
  mixture = input_images.read_image(str(folder / 'a.png'))
  np.testing.assert_array_equal(left_half[..., 0], mixture[..., 0])  # Colour restored.
  colour = input_images.read_image(str(out / 'a_disparity.png'))
  np.testing.assert_array_equal(
      colour, colormap.colorize(np.load(out / 'a_disparity.npy'), 4.0))


def _cli(args, tmp_path):
  env = dict(os.environ, TF_CPP_MIN_LOG_LEVEL='2')
  return subprocess.run([sys.executable, '-m', 'mixstereo_tf.unmix', *args,
                         f'--output_dir={tmp_path / "out"}'], capture_output=True, text=True,
                        env=env, cwd=REPO, timeout=300, check=False)


def test_bad_input_is_named(tmp_path):
  """A plain photo with --mixture=auto, a wrong explicit mixture, MIN >= MAX."""
  left, right, _ = detection_test._pair()  # pylint: disable=protected-access
  media.write_image(str(tmp_path / 'photo.png'), left)
  result = _cli(['--method=classical', '--mixture=auto', f'--input={tmp_path}/photo.png'],
                tmp_path)
  assert result.returncode == 1 and 'photo.png' in result.stderr
  assert 'does not look like an anaglyph' in result.stderr
  gray = detection_test._ours('gray', left, right)  # pylint: disable=protected-access
  media.write_image(str(tmp_path / 'gray.png'), gray)
  result = _cli(['--method=classical', '--mixture=anaglyph', f'--input={tmp_path}/gray.png'],
                tmp_path)
  assert result.returncode == 0 and "given as 'anaglyph', but the detector reads it as 'gray'" in result.stderr
  result = _cli(['--method=classical', '--mixture=anaglyph', '--disparity_range=5,5',
                 f'--input={tmp_path}/gray.png'], tmp_path)
  assert result.returncode != 0
  assert '--disparity_range: disparity range needs MIN < MAX' in result.stderr
  # The message alone, not under the whole help text (absl's usage printout).
  assert 'Separates mixture images' not in result.stderr
  assert '(--help shows the usage)' in result.stderr


def test_unmix_with_no_model_flag_uses_the_shipped_model(tmp_path):
  """`mixstereo-unmix --input --output_dir` alone: the shipped anaglyph model, detected
  encoding; `--pretrained=list` names the shipped models and their recipes."""
  left, right, truth = skimage.data.stereo_motorcycle()
  left, right = (cv2.resize(v, (185, 125), interpolation=cv2.INTER_AREA) for v in (left, right))
  image = mixtures.mix('gray', left / 127.5 - 1.0, right / 127.5 - 1.0).numpy()
  image = np.round((image + 1.0) * 127.5).astype(np.uint8)  # A gray anaglyph.
  media.write_image(str(tmp_path / 'photo.png'), image)
  env = dict(os.environ, TF_CPP_MIN_LOG_LEVEL='2')
  run = lambda *args: subprocess.run([sys.executable, '-m', 'mixstereo_tf.unmix', *args],
                                     capture_output=True, text=True, env=env,
                                     cwd=str(tmp_path), timeout=300, check=False)
  result = run('--input=photo.png', '--output_dir=out')
  assert result.returncode == 0, result.stderr[-3000:]
  info = json.loads((tmp_path / 'out' / 'photo_info.json').read_text())
  assert info['method'] == 'model' and info['mixture'] == 'gray'
  disparity = np.load(tmp_path / 'out' / 'photo_disparity.npy')
  expected = np.median(truth[np.isfinite(truth)]) / 4  # Ground truth at 1/4 size.
  assert np.median(disparity) == pytest.approx(expected, abs=1.5)
  listing = run('--pretrained=list')
  assert listing.returncode == 0
  assert 'anaglyph: refiner model for anaglyph' in listing.stdout
  assert 'diplopia' in listing.stdout and 'recipe: python -m mixstereo_tf.train' in listing.stdout


def test_mixing_weight_of_double_images(tmp_path):
  """--mixture=diplopia separates with a = 1/2 unless --mixing_weight says otherwise (a
  number, or 'auto': estimated); the info JSON records the a used; a bad value is named.
  (This fine texture has no isolated edges, so 'auto' finds no clear echo and stays near
  1/2: the estimate's accuracy is tested in classical/diplopia_layers_test.py.)"""
  left, right, _ = detection_test._pair()  # pylint: disable=protected-access
  image = np.rint(0.35 * left.astype(np.float64) + 0.65 * right).astype(np.uint8)
  media.write_image(str(tmp_path / 'double.png'), image)
  args = ['--method=classical', '--mixture=diplopia', f'--input={tmp_path}/double.png']
  found = {}
  for weight in (None, '0.35', 'auto'):
    result = _cli(args + ([f'--mixing_weight={weight}'] if weight else []), tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    info = json.loads((tmp_path / 'out' / 'double_info.json').read_text())
    found[weight] = info['mixing_weight']
  assert found[None] == 0.5 and found['0.35'] == 0.35
  assert 0.05 <= found['auto'] <= 0.95
  result = _cli(args + ['--mixing_weight=1.5'], tmp_path)
  assert result.returncode != 0 and '--mixing_weight' in result.stderr
