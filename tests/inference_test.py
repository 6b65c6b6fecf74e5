"""Tests for mixstereo_tf.inference: run loading, padding, the Unmixer."""

import json
import os
import shutil

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf import inference
from mixstereo_tf import models
from mixstereo_tf.data import pipeline
from mixstereo_tf.training import config as train_config

# Tiny architecture: forward passes take milliseconds; size multiple 32.
TINY = models.ModelConfig(separation_widths=(4, 4, 4, 4, 4, 4), stereo_features=2,
                          stereo_residual_blocks=0, stereo_3d_widths=(2,), max_disparity=4)


def make_run_dir(path, mixture='anaglyph', seed=1):
  """A run directory as training writes it: config.json and a model+optimizer checkpoint."""
  tf.keras.utils.set_random_seed(seed)
  model = models.build_model(TINY)
  os.makedirs(path, exist_ok=True)
  with open(os.path.join(path, 'config.json'), 'w') as f:
    f.write(train_config.to_json(
        model=TINY, pipeline=pipeline.PipelineConfig(mixture=mixture, crop_height=64,
                                                     crop_width=128)))
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
  padded = inference.pad_to_multiple(image, 4).numpy()
  expected = np.array([[0, 1, 2, 2], [3, 4, 5, 5], [3, 4, 5, 5], [3, 4, 5, 5]])
  np.testing.assert_array_equal(padded[..., 0], expected)
  np.testing.assert_array_equal(inference.crop_to(padded, 2, 3), image)
  batched = inference.pad_to_multiple(np.zeros((2, 32, 33, 3), np.uint8), 32)
  assert batched.shape == (2, 32, 64, 3) and batched.dtype == tf.uint8
  with pytest.raises(ValueError):
    inference.pad_to_multiple(image, 0)


def test_load_run_restores_the_weights(run):
  path, model, prefix = run
  for source in (path, prefix):
    loaded, info = inference.load_run(source)
    assert info == inference.RunInfo('anaglyph', 64, 128, TINY)
    for saved, restored in zip(model.variables, loaded.variables):
      np.testing.assert_array_equal(saved.numpy(), restored.numpy())


def test_load_run_errors(tmp_path, run):
  path, model, prefix = run
  with pytest.raises(ValueError, match='No checkpoint'):
    inference.load_run(str(tmp_path))
  with pytest.raises(ValueError, match='Checkpoint not found'):
    inference.load_run(prefix + '-nope')
  no_config = tmp_path / 'no_config'
  shutil.copytree(path, no_config)
  os.remove(no_config / 'config.json')
  with pytest.raises(ValueError, match='config.json'):
    inference.load_run(str(no_config))
  broken = tmp_path / 'broken'
  shutil.copytree(path, broken)
  (broken / 'config.json').write_text(json.dumps({'model': TINY.to_dict()}))
  with pytest.raises(ValueError, match='pipeline'):
    inference.load_run(str(broken))
  # A checkpoint with only the separation network's weights cannot restore the model.
  partial = tmp_path / 'partial'
  partial.mkdir()
  shutil.copy(os.path.join(path, 'config.json'), partial)
  part = tf.train.Checkpoint(model=tf.train.Checkpoint(separation=model.separation))
  with pytest.raises(ValueError, match='weights'):
    inference.load_run(part.write(str(partial / 'ckpt-1')))


def test_unmixer_odd_size_equals_padded_model_output(run):
  _, model, _ = run
  info = inference.RunInfo('anaglyph', 64, 128, TINY)
  unmixer = inference.Unmixer.from_model(model, info, restore_colour=False)
  image = np.random.RandomState(0).randint(0, 256, (97, 131, 3)).astype(np.uint8)
  out = unmixer(image)
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


def test_unmixer_restores_the_anaglyph_channels(run):
  _, model, _ = run
  info = inference.RunInfo('anaglyph', 64, 128, TINY)
  unmixer = inference.Unmixer.from_model(model, info)
  assert unmixer.restore_colour  # Default on for channel anaglyphs.
  image = np.random.RandomState(1).randint(0, 256, (40, 50, 3)).astype(np.uint8)
  out = unmixer(image)
  raw = inference.Unmixer.from_model(model, info, restore_colour=False)(image)
  # Red-cyan: the left view's red and the right view's green and blue are the mixture's.
  np.testing.assert_array_equal(out['left'][..., 0], image[..., 0])
  np.testing.assert_array_equal(out['right'][..., 1:], image[..., 1:])
  assert not np.array_equal(raw['left'][..., 0], image[..., 0])
  np.testing.assert_array_equal(out['disparity_left'], raw['disparity_left'])
  # Diplopia keeps no channel: restoration is off by default.
  assert not inference.Unmixer.from_model(
      model, inference.RunInfo('diplopia', 64, 128, TINY)).restore_colour
  with pytest.raises(ValueError, match='uint8'):
    unmixer(image.astype(np.float32))
