"""Tiny models and batches shared by the training tests."""

import numpy as np
import tensorflow as tf

from mixstereo_tf import models
from mixstereo_tf.core import mixtures

TINY = models.ModelConfig(separation_widths=(4, 4, 8, 8, 8, 8), stereo_features=4,
                          stereo_residual_blocks=1, stereo_3d_widths=(4, 4, 4, 8),
                          max_disparity=32)
# The smallest model with every kind of layer (one U-Net level, one 3D level, one residual
# block): XLA compile time on CPU grows with the number of layers.
MINI = models.ModelConfig(separation_widths=(4, 4), stereo_features=4,
                          stereo_residual_blocks=1, stereo_3d_widths=(4,), max_disparity=8)


def stereo_batch(batch_size=1, height=32, width=64, shift=3, seed=0, mixture='anaglyph'):
  """A textured pair with a constant disparity `shift` and its mixture, in [-1, 1]."""
  rng = np.random.default_rng(seed)
  texture = rng.uniform(-1, 1, (batch_size, height, width + shift, 3)).astype(np.float32)
  left = texture[:, :, shift:]
  right = texture[:, :, :width]  # The left pixel x is the right pixel x - shift.
  left, right = tf.constant(left), tf.constant(right)
  return {'left': left, 'right': right, 'mixture': mixtures.mix(mixture, left, right)}


def dataset_fn(batch_size=1, nan_from_step=None, **kwargs):
  """Returns a function building an endless dataset of one batch (NaNs from a step on)
  from batch `start` on (`loop.train`'s dataset_fn)."""
  batch = stereo_batch(batch_size, **kwargs)

  def build(start=0):
    dataset = tf.data.Dataset.from_tensors(batch).repeat()
    if nan_from_step is None:
      return dataset

    def poison(index, element):
      element = dict(element)
      element['left'] = tf.where(index + 1 >= nan_from_step,
                                 tf.fill(tf.shape(element['left']), np.nan), element['left'])
      return element
    return dataset.enumerate().skip(start).map(poison)
  return build
