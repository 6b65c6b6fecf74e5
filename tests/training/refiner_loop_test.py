"""Tests for mixstereo_tf.training.refiner_loop: the loss, the batches, resumable training."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.models import refiner
from mixstereo_tf.training import refiner_data
from mixstereo_tf.training import refiner_loop

EXAMPLES = refiner_data.ExampleConfig(mixtures='anaglyph', height=32, width=64,
                                      max_disparity=16, degrade=False)
TINY = refiner.RefinerConfig(view_widths=(4, 4), disparity_features=4, dilations=(1,))


def test_loss_in_pixels_and_unit_range():
  zeros = tf.zeros([1, 2, 2, 1])
  outputs = {'disparity_left': zeros + 2.0, 'disparity_right': zeros,
             'left': tf.zeros([1, 2, 2, 3]) + 0.5, 'right': tf.zeros([1, 2, 2, 3])}
  batch = {'disparity_left': zeros, 'disparity_right': zeros + 1.0,
           'left': tf.zeros([1, 2, 2, 3]), 'right': tf.zeros([1, 2, 2, 3])}
  losses = refiner_loop.refiner_loss(outputs, batch, view_weight=10.0, disparity_clip=5.0)
  assert float(losses['disparity']) == pytest.approx(3.0)
  clipped = refiner_loop.refiner_loss(outputs, batch, view_weight=0.0, disparity_clip=1.5)
  assert float(clipped['loss']) == pytest.approx(1.5 + 1.0)
  # 0.5 on [-1, 1] is 0.25 on [0, 1], in one view of two.
  assert float(losses['views']) == pytest.approx(0.125)
  assert float(losses['loss']) == pytest.approx(3.0 + 1.25)


def _config(path, steps):
  return refiner_loop.RefinerTrainConfig(model_dir=path, num_shards=1, shard_size=3,
                                         crop_height=16, crop_width=32, batch_size=2,
                                         num_steps=steps, checkpoint_every=2, log_every=1)


def test_batches_depend_only_on_seed_and_step(tmp_path):
  config = _config(str(tmp_path), 1)
  refiner_data.build_shard(str(tmp_path / 'examples'), 0, 3, EXAMPLES)
  data = refiner_data.load_shards(str(tmp_path / 'examples'), 1)
  first, again = (refiner_loop.draw_batch(data, config, 5) for _ in range(2))
  other = refiner_loop.draw_batch(data, config, 6)
  assert first['inputs'].shape == (2, 16, 32, 11)
  np.testing.assert_array_equal(first['inputs'], again['inputs'])
  assert not np.array_equal(first['inputs'], other['inputs'])


def test_interrupted_training_resumes_to_the_same_weights(tmp_path):
  straight = refiner_loop.train(_config(str(tmp_path / 'a'), 4), EXAMPLES, TINY)
  refiner_loop.train(_config(str(tmp_path / 'b'), 2), EXAMPLES, TINY)
  resumed = refiner_loop.train(_config(str(tmp_path / 'b'), 4), EXAMPLES, TINY)
  assert straight.endswith('ckpt-4') and resumed.endswith('ckpt-4')
  weights = []
  for prefix in (straight, resumed):
    model = refiner.build_refiner(TINY)
    tf.train.Checkpoint(model=model).read(prefix).expect_partial()
    weights.append(model.get_weights())
  for a, b in zip(*weights):
    np.testing.assert_allclose(a, b, rtol=1e-5, atol=1e-6)
  assert any(np.abs(w).max() > 0 for w in weights[0][-2:])  # The heads have moved.
