"""Known-answer tests of the local linear colour transfer."""

import cv2
import numpy as np
import pytest

from mixstereo_tf.restoration import colour_transfer


def test_an_affine_channel_is_recovered():
  rng = np.random.default_rng(1)
  guide = rng.uniform(0.2, 0.8, (24, 24, 1))
  target = 0.5 * guide + 0.1
  train = rng.uniform(size=(24, 24)) < 0.5
  predicted = colour_transfer.local_linear_transfer(guide, target, train, radius=3, eps=1e-6)
  np.testing.assert_allclose(predicted, target, atol=2e-3)


def test_two_guide_channels_recover_their_mixture():
  rng = np.random.default_rng(2)
  guide = rng.uniform(0.1, 0.6, (20, 30, 2))
  target = np.stack([0.3 * guide[..., 0] + 0.6 * guide[..., 1],
                     0.8 * guide[..., 1] + 0.05], axis=-1)
  train = rng.uniform(size=(20, 30)) < 0.7
  predicted = colour_transfer.local_linear_transfer(guide, target, train, radius=3, eps=1e-7)
  np.testing.assert_allclose(predicted, target, atol=3e-3)


def test_no_training_pixel_gives_the_guide_mean():
  guide = np.full((8, 8, 2), [0.2, 0.6], np.float32)
  predicted = colour_transfer.local_linear_transfer(guide, np.zeros((8, 8, 3)),
                                                    np.zeros((8, 8), bool))
  np.testing.assert_allclose(predicted, 0.4)


def test_three_guide_channels_are_refused():
  with pytest.raises(ValueError, match='1 or 2 guide channels'):
    colour_transfer.local_linear_transfer(np.zeros((8, 8, 3)), np.zeros((8, 8, 3)),
                                          np.ones((8, 8), bool))


def test_the_subsampled_fit_recovers_an_affine_channel_and_stays_close_to_the_exact_one():
  rng = np.random.default_rng(3)
  guide = cv2.GaussianBlur(rng.uniform(0.1, 0.9, (60, 90, 1)).astype(np.float32), (0, 0), 2)
  guide = guide[..., None]
  target = np.concatenate([0.5 * guide + 0.2, 0.9 - 0.7 * guide], axis=-1)
  train = rng.uniform(size=(60, 90)) < 0.6
  fast = colour_transfer.local_linear_transfer(guide, target, train, radius=4, eps=1e-6,
                                               subsample=2)
  np.testing.assert_allclose(fast, target, atol=5e-3)
  with pytest.raises(ValueError, match='subsample'):
    colour_transfer.local_linear_transfer(guide, target, train, subsample=0)
