"""Tests for mixstereo_tf.unmixing.predictors: padding, the Unmixer and its registry of methods."""

import logging
import os

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf import models
from mixstereo_tf.artifacts import graphs
from mixstereo_tf.artifacts import runs
from mixstereo_tf.data import halftone_print
from mixstereo_tf.data import pipeline
from mixstereo_tf.unmixing import disparity_range
from mixstereo_tf.unmixing import predictors
from tests.classical import sgbm_test

# Tiny architecture: forward passes take milliseconds; size multiple 32.
TINY = models.ModelConfig(separation_widths=(4, 4, 4, 4, 4, 4), stereo_features=2,
                          stereo_residual_blocks=0, stereo_3d_widths=(2,), max_disparity=4)


def make_run_dir(path, mixture='anaglyph', seed=1, mode=None):
  """A run directory as training writes it: config.json (with a train section naming
  `mode` when given) and a model+optimizer checkpoint."""
  tf.keras.utils.set_random_seed(seed)
  model = models.build_model(TINY)
  os.makedirs(path, exist_ok=True)
  train = {'train': {'mode': mode}} if mode else {}
  with open(os.path.join(path, 'config.json'), 'w') as f:
    f.write(runs.to_json(
        model=TINY, pipeline=pipeline.PipelineConfig(mixture=mixture, crop_height=64,
                                                     crop_width=128), **train))
  checkpoint = tf.train.Checkpoint(model=model, optimizer=tf.keras.optimizers.RMSprop(1e-4))
  prefix = tf.train.CheckpointManager(checkpoint, path, max_to_keep=2).save(checkpoint_number=7)
  return model, prefix


@pytest.fixture(scope='module')
def run(tmp_path_factory):
  path = str(tmp_path_factory.mktemp('run'))
  model, prefix = make_run_dir(path)
  return path, model, prefix


def test_pad_to_multiple_replicates_edges_and_crop_inverts():
  image = np.arange(2 * 3 * 1).reshape(2, 3, 1)
  padded = graphs.pad_to_multiple(image, 4).numpy()
  expected = np.array([[0, 1, 2, 2], [3, 4, 5, 5], [3, 4, 5, 5], [3, 4, 5, 5]])
  np.testing.assert_array_equal(padded[..., 0], expected)
  np.testing.assert_array_equal(graphs.crop_to(padded, 2, 3), image)
  batched = graphs.pad_to_multiple(np.zeros((2, 32, 33, 3), np.uint8), 32)
  assert batched.shape == (2, 32, 64, 3) and batched.dtype == tf.uint8
  with pytest.raises(ValueError):
    graphs.pad_to_multiple(image, 0)


def test_unmixer_odd_size_equals_padded_model_output(run):
  path, model, _ = run
  # The network's own range (named, or given as [0, D - 1]): no shift, no scaling.
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      checkpoint=path, restore_colour=False, disparity_range=disparity_range.NETWORK))
  explicit = predictors.build_unmixer(predictors.PredictorConfig(
      checkpoint=path, restore_colour=False, disparity_range=(0, TINY.max_disparity - 1)))
  assert (unmixer.method, unmixer.mixture, unmixer.max_disparity) == ('model', 'anaglyph', 4)
  image = np.random.RandomState(0).randint(0, 256, (97, 131, 3)).astype(np.uint8)
  out = unmixer(image)
  np.testing.assert_array_equal(out['disparity_left'], explicit(image)['disparity_left'])
  assert out['info']['shift'] == 0 and out['info']['scale'] == 1.0
  assert out['info']['checkpoint'] == path  # Which network ran.
  assert out['left'].shape == out['right'].shape == (97, 131, 3)
  assert out['left'].dtype == np.uint8
  assert out['disparity_left'].shape == out['disparity_right'].shape == (97, 131)
  # Known answer: the model on the edge-padded 128 x 160 image, cropped back.
  padded = np.pad(image, ((0, 31), (0, 29), (0, 0)), mode='edge')
  direct = model(tf.constant(padded[None], tf.float32) / 127.5 - 1.0)
  np.testing.assert_allclose(out['disparity_left'], direct['disparity_left'][0, :97, :131, 0],
                             atol=1e-4)
  np.testing.assert_allclose(out['disparity_right'],
                             direct['disparity_right'][0, :97, :131, 0], atol=1e-4)
  left = np.clip(np.round((direct['left'][0, :97, :131].numpy() + 1) * 127.5), 0, 255)
  assert np.abs(out['left'].astype(float) - left).max() <= 1
  # Soft-argmin over levels 0 .. D - 1.
  assert 0 <= out['disparity_left'].min() <= out['disparity_left'].max() <= TINY.max_disparity - 1
  # A gray image is replicated to RGB.
  gray = unmixer(image[:, :, 0])
  np.testing.assert_array_equal(gray['left'], unmixer(np.repeat(image[:, :, :1], 3, 2))['left'])


def test_unmixer_restores_the_anaglyph_channels(run, tmp_path):
  path, _, _ = run
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(checkpoint=path))
  assert unmixer.restore_colour  # Default on for channel anaglyphs.
  image = np.random.RandomState(1).randint(0, 256, (40, 50, 3)).astype(np.uint8)
  out = unmixer(image)
  raw = predictors.build_unmixer(predictors.PredictorConfig(checkpoint=path,
                                                          restore_colour=False))(image)
  # Red-cyan: the left view's red and the right view's green and blue are the mixture's.
  np.testing.assert_array_equal(out['left'][..., 0], image[..., 0])
  np.testing.assert_array_equal(out['right'][..., 1:], image[..., 1:])
  assert not np.array_equal(raw['left'][..., 0], image[..., 0])
  np.testing.assert_array_equal(out['disparity_left'], raw['disparity_left'])
  # Diplopia keeps no channel: restoration is off by default.
  diplopia_run = str(tmp_path / 'diplopia')
  make_run_dir(diplopia_run, mixture='diplopia')
  assert not predictors.build_unmixer(
      predictors.PredictorConfig(checkpoint=diplopia_run)).restore_colour
  # Asked for where nothing can be restored: refused, not a silent no-op.
  with pytest.raises(ValueError, match="restore_colour=True .*'diplopia' mixtures have no"):
    predictors.build_unmixer(predictors.PredictorConfig(checkpoint=diplopia_run,
                                                        restore_colour=True))
  with pytest.raises(ValueError, match='uint8'):
    unmixer(image.astype(np.float32))


def test_build_unmixer_checks_its_arguments(tmp_path):
  build = lambda **kwargs: predictors.build_unmixer(predictors.PredictorConfig(**kwargs))
  with pytest.raises(ValueError, match='exactly one'):
    build(saved_model='a', checkpoint='b')
  with pytest.raises(ValueError, match='takes neither'):
    build(method='classical', saved_model='a', mixture='anaglyph')
  with pytest.raises(ValueError, match='needs PredictorConfig.mixture'):
    build(method='classical')
  with pytest.raises(ValueError, match=r"needs PredictorConfig.mixture \(an anaglyph encoding "
                     r"or 'auto'\)\.$"):
    build(method='sgbm')  # It said '(got None)', as if None were a wrong name.
  with pytest.raises(ValueError, match='monocular'):
    build(method='classical', mixture='monocular')
  with pytest.raises(ValueError, match='anaglyph'):
    build(checkpoint='x', mixture='no_such_mixture')
  with pytest.raises(ValueError, match="method 'model' only"):
    build(method='classical', mixture='anaglyph', restore_colour=True)
  with pytest.raises(ValueError, match='not to the shipped models'):
    build(restore_colour=False)  # The default: a shipped model, which always restores.
  with pytest.raises(ValueError, match="mixing_weight applies to double images; mixture 'gray'"):
    build(method='classical', mixture='gray', mixing_weight=0.3)
  assert build(method='classical', mixture='diplopia', mixing_weight=0.3).mixture == 'diplopia'
  with pytest.raises(ValueError, match='Unknown PredictorConfig.method'):
    build(method='magic')
  with pytest.raises(ValueError, match='needs PredictorConfig.checkpoint'):
    build(method='oracle', saved_model='x')
  run_dir = str(tmp_path / 'run')
  make_run_dir(run_dir, mixture='diplopia')
  with pytest.raises(ValueError, match="trained on 'diplopia'"):
    build(checkpoint=run_dir, mixture='anaglyph')
  unmixer = build(checkpoint=run_dir)
  assert unmixer.mixture == 'diplopia' and unmixer.max_disparity == TINY.max_disparity
  classical = build(method='classical', mixture='diplopia')
  assert (classical.method, classical.mixture, classical.takes_pair) == (
      'classical', 'diplopia', False)
  oracle = build(method='oracle', checkpoint=run_dir, mixture='anaglyph')
  assert oracle.takes_pair and oracle.mixture == 'anaglyph'


def test_pair_function_pads_runs_the_stereo_module_and_crops():
  tf.keras.utils.set_random_seed(0)
  config = models.ModelConfig(separation_widths=(4, 4), stereo_features=4,
                              stereo_residual_blocks=1, stereo_3d_widths=(4,),
                              max_disparity=8)
  model = models.build_model(config)
  predict = graphs.pair_function(model)
  rng = np.random.RandomState(1)
  left, right = (rng.randint(0, 256, (32, 64, 3)).astype(np.uint8) for _ in range(2))
  out = predict(left, right)
  direct = model.compute_disparity(tf.constant(left[None], tf.float32) / 127.5 - 1.0,
                                   tf.constant(right[None], tf.float32) / 127.5 - 1.0)
  np.testing.assert_allclose(out['disparity_left'], direct['disparity_left'][0, ..., 0],
                             atol=1e-5)
  cropped = predict(left[:30, :62], right[:30, :62])
  assert cropped['disparity_left'].shape == cropped['disparity_right'].shape == (30, 62)


def test_sgbm_method_is_registered_and_unmixes_an_anaglyph():
  assert 'sgbm' in predictors.METHODS
  build = lambda **kwargs: predictors.build_unmixer(
      predictors.PredictorConfig(method='sgbm', **kwargs))
  with pytest.raises(ValueError, match='anaglyph encoding'):
    build(mixture='diplopia')
  with pytest.raises(ValueError, match='anaglyph encoding'):
    build()
  with pytest.raises(ValueError, match='takes neither'):
    build(mixture='anaglyph', checkpoint='x')
  left, right = sgbm_test.shifted_pair(-4)
  image = sgbm_test.anaglyph_of(left, right)
  unmixer = build(mixture='anaglyph', disparity_range=(-10, 10))
  assert (unmixer.method, unmixer.mixture, unmixer.restore_colour) == (
      'sgbm', 'anaglyph', True)
  out = unmixer(image)
  assert out['left'].shape == out['right'].shape == image.shape
  assert out['left'].dtype == np.uint8
  assert out['info']['method'] == 'sgbm' and out['info']['disparity_range'] == [-10, 10]
  assert np.mean(np.abs(sgbm_test.inner(out['disparity_left']) + 4) <= 1) > 0.9
  # The views: the red channel is the left view's, green and blue the right view's.
  np.testing.assert_array_equal(out['left'][..., 0], image[..., 0])
  estimated = build(mixture='auto')(image)  # Detected encoding, range estimated.
  assert estimated['info']['disparity_range'][0] <= -4 <= estimated['info'][
      'disparity_range'][1]


def test_a_separation_only_run_warns_and_is_no_oracle(tmp_path, caplog):
  path = str(tmp_path / 'separation')
  make_run_dir(path, mode='separation_only')
  assert runs.read_run_info(path).mode == 'separation_only'
  caplog.set_level(logging.WARNING)
  predictors.build_unmixer(predictors.PredictorConfig(checkpoint=path))
  assert 'separation_only' in caplog.text and 'initial weights' in caplog.text
  with pytest.raises(ValueError, match='separation_only run .* never trained'):
    predictors.build_unmixer(predictors.PredictorConfig(method='oracle', checkpoint=path))
  assert runs.read_run_info(str(tmp_path / 'separation')).to_dict()['mode'] == (
      'separation_only')


def test_a_stereo_only_run_used_on_a_mixture_warns_and_names_the_oracle(tmp_path, caplog):
  path = str(tmp_path / 'stereo')
  make_run_dir(path, mode='stereo_only')
  caplog.set_level(logging.WARNING)
  predictors.build_unmixer(predictors.PredictorConfig(method='oracle', checkpoint=path))
  assert 'stereo_only' not in caplog.text
  predictors.build_unmixer(predictors.PredictorConfig(checkpoint=path))
  assert 'trained with mode stereo_only' in caplog.text and "method 'oracle'" in caplog.text



def test_weights_identity_changes_with_the_weights_at_a_path(tmp_path):
  path = str(tmp_path / 'run')
  make_run_dir(path, seed=1)
  first = predictors.weights_identity(predictors.PredictorConfig(checkpoint=path))
  assert first.startswith('ckpt-7.index sha256:') and len(first.split(':')[1]) == 16
  assert predictors.weights_identity(predictors.PredictorConfig(
      checkpoint=os.path.join(path, 'ckpt-7'))) == first  # The prefix names the same.
  make_run_dir(path, seed=2)  # Retrained: other weights under the same checkpoint name.
  assert predictors.weights_identity(predictors.PredictorConfig(checkpoint=path)) != first
  shipped = predictors.weights_identity(predictors.PredictorConfig(pretrained='anaglyph'))
  assert shipped.startswith('weights.npz sha256:') and shipped != predictors.weights_identity(
      predictors.PredictorConfig(pretrained='diplopia'))
  for config in (predictors.PredictorConfig(), predictors.PredictorConfig(
      method='classical', mixture='anaglyph')):
    assert predictors.weights_identity(config) is None  # No weights named.
  with pytest.raises(ValueError, match=r"PredictorConfig.checkpoint='.*nothing': .*neither"):
    predictors.weights_identity(predictors.PredictorConfig(checkpoint=str(tmp_path / 'nothing')))
  with pytest.raises(ValueError, match=r"PredictorConfig.saved_model='.*': cannot read "
                                       r'.*variables.index'):
    predictors.weights_identity(predictors.PredictorConfig(saved_model=str(tmp_path)))


def test_sides_beyond_opencvs_warps_and_thin_ranges_are_named():
  classical = predictors.build_unmixer(predictors.PredictorConfig('classical',
                                                                mixture='anaglyph'))
  with pytest.raises(ValueError, match=r"1x32767 image: sides of 32767 px or more are beyond "
                                       "OpenCV's image warps"):
    classical(np.zeros((1, 32767, 3), np.uint8))
  thin = np.random.default_rng(0).integers(0, 256, (6, 6400, 3), dtype=np.uint8)
  with pytest.raises(ValueError, match=r"6x6400 image is smaller than the matcher's census "
                                       r'window of 7x9 pixels'):
    classical(thin)
  # 60 x 6400 was too thin for the range's 320-px copy (3 px high); planned as a row of
  # 240-px frames (`planning_copies`) it is searched as it is over +-80 px.
  strip = np.random.default_rng(0).integers(0, 256, (60, 6400, 3), dtype=np.uint8)
  assert classical(strip)['disparity_left'].shape == (60, 6400)


def test_a_scanned_print_is_descreened_when_asked_and_the_paper_default_leaves_it():
  """A printed anaglyph (4-px cells would hide 14- and 9-px disparities): with
  descreen='auto' the screen is found and smoothed (info 'screen_period') and most
  disparities come right; PredictorConfig's default ('off', the paper's path) matches the
  dots, as does 'off'."""
  from tests.unmixing import detection_test  # pylint: disable=import-outside-toplevel
  left, right, truth = detection_test._pair(height=192, width=288)  # pylint: disable=protected-access
  printed = halftone_print.halftone_print(detection_test._ours('anaglyph', left, right), 4.0)  # pylint: disable=protected-access
  assert predictors.PredictorConfig().descreen == 'off'
  bad = {}
  for setting in ('off', 'auto', 4.0):
    out = predictors.build_unmixer(predictors.PredictorConfig(
        'classical', mixture='anaglyph', descreen=setting))(printed)
    bad[setting] = np.mean(np.abs(out['disparity_left'] - truth)[:, 30:] > 1)
    assert out['info'].get('screen_period') == (None if setting == 'off' else 4.0)
  assert bad['auto'] < 0.25 < 0.6 < bad['off'], bad
  with pytest.raises(ValueError, match="PredictorConfig.descreen: .*'auto', 'off'"):
    predictors.PredictorConfig(descreen='yes')
