"""Tests for mixstereo_tf.unmixing.tiling: tiles with enough overlap give the whole-image result."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.unmixing import tiling


def _box5(batch):
  """A 5x5 box filter (receptive radius 2) with edge replication: a stand-in network."""
  padded = tf.pad(tf.constant(batch), [[0, 0], [2, 2], [2, 2], [0, 0]], 'SYMMETRIC')
  kernel = tf.ones([5, 5, batch.shape[-1], 1]) / 25.0
  return {'out': tf.nn.depthwise_conv2d(padded, kernel, [1, 1, 1, 1], 'VALID'),
          'copy': tf.constant(batch[..., :1])}


def test_tiles_equal_one_pass_when_the_overlap_covers_the_receptive_radius():
  image = np.random.default_rng(0).uniform(size=(37, 53, 2)).astype(np.float32)
  whole = tiling.apply(_box5, image, multiple=1, tile=10 ** 4)
  tiled = tiling.apply(_box5, image, multiple=4, tile=16, overlap=4)
  assert tiled['out'].shape == (37, 53, 2) and tiled['copy'].shape == (37, 53, 1)
  np.testing.assert_allclose(tiled['copy'][..., 0], image[..., 0])
  # Inside the image the tiles agree with one pass; rows / columns within 2 px of the
  # image border see padding in the last tiles, as in one padded pass.
  np.testing.assert_allclose(tiled['out'][:35, :51], whole['out'][:35, :51], atol=1e-6)


def test_an_image_within_the_tile_area_runs_in_one_pass_even_when_wider_than_a_tile():
  image = np.random.default_rng(1).uniform(size=(11, 50, 2)).astype(np.float32)
  calls = []

  def network(batch):
    calls.append(batch.shape)
    return _box5(batch)

  out = tiling.apply(network, image, multiple=4, tile=24, overlap=4)  # 550 <= 24 x 24.
  assert calls == [(1, 12, 52, 2)]  # Padded to the multiple, one call.
  np.testing.assert_allclose(out['out'][:9, :48], _box5(image[None])['out'][0, :9, :48],
                             atol=1e-6)
  assert out['out'].shape == (11, 50, 2)
  tiling.apply(network, image, multiple=4, tile=23, overlap=4)  # 550 > 23 x 23: tiles.
  assert len(calls) > 2


def test_tile_must_exceed_the_overlap():
  with pytest.raises(ValueError, match='twice the overlap'):
    tiling.apply(_box5, np.zeros((4, 4, 1), np.float32), 1, tile=8, overlap=4)
