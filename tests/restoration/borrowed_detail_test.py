"""Tests of the borrowed channels' finest detail (restoration/borrowed_detail.py)."""

import cv2
import numpy as np
import pytest

from mixstereo_tf.core import mixtures
from mixstereo_tf.restoration import borrowed_detail

SIGMA = 0.7


def _noise(seed, shape=(96, 128), scale=0.05):
  return np.random.default_rng(seed).normal(0, scale, shape).astype(np.float32)


@pytest.mark.parametrize('name, pair', [('anaglyph', (1, 2)), ('amber_blue', (0, 1)),
                                        ('green_magenta', None), ('gray', None),
                                        ('dubois', None)])
def test_own_pair_is_the_eye_keeping_two_channels_green_one(name, pair):
  assert borrowed_detail.own_pair(mixtures.get_mixture(name)) == pair


def test_fine_band_adds_up():
  channel = 0.5 + _noise(0)
  coarse, fine = borrowed_detail.fine_band(channel, SIGMA)
  np.testing.assert_allclose(coarse + fine, channel, atol=1e-6)
  assert fine.std() > 0.5 * channel.std()  # White noise is mostly fine detail.


def _smooth(seed, shape=(96, 128), scale=0.1):
  """Detail with most of its power at coarse scales, as a photograph's."""
  return cv2.GaussianBlur(_noise(seed, shape, 1.0), (0, 0), 2.0) * np.float32(scale / 0.14)


def _powers(part, sigma=SIGMA):
  """(fine, reference) band powers of a component, the bands `shared_share` compares."""
  blur = lambda s: cv2.GaussianBlur(part, (0, 0), s, borderType=cv2.BORDER_REFLECT)
  return np.var(part - blur(sigma)), np.var(blur(2 * sigma) - blur(4 * sigma))


@pytest.mark.parametrize('noise_scale', [0.0, 0.01, 0.03])
def test_shared_share_is_the_fine_bands_shared_power_over_the_references(noise_scale):
  """Shared detail s plus independent noise n per channel: the correlation of a band is
  P_s / (P_s + P_n) in it; k is the fine band's over the reference band's, computed here
  from the parts, which the function never sees apart."""
  shared = 0.5 + _smooth(1)
  noise = [_noise(seed, scale=noise_scale) for seed in (2, 3, 4)]
  mixture = np.stack([shared + n for n in noise], -1)
  (s_fine, s_ref), (n_fine, n_ref) = _powers(shared), _powers(noise[1])
  expected = (s_fine / (s_fine + n_fine)) / (s_ref / (s_ref + n_ref))
  k = borrowed_detail.shared_share(mixture, (1, 2), SIGMA)
  assert k == pytest.approx(expected, abs=0.03)
  if noise_scale:
    assert k < 0.95


def test_colour_detail_at_every_scale_is_kept():
  """Channels that differ at every scale alike (a colourful scene, no noise): k = 1."""
  shared = 0.5 + _smooth(1)
  mixture = np.stack([shared + _smooth(seed) for seed in (5, 6, 7)], -1)
  assert borrowed_detail.shared_share(mixture, (1, 2), SIGMA) > 0.95
  apart = np.stack([0.5 + _smooth(seed) for seed in (5, 6, 7)], -1)  # Nothing shared.
  assert borrowed_detail.shared_share(apart, (1, 2), SIGMA) == 1.0


def test_shared_share_of_flat_channels_is_one():
  assert borrowed_detail.shared_share(np.full((8, 8, 3), 0.5, np.float32), (1, 2), SIGMA) == 1.0


def _colour_case(noise_scale):
  """A colour anaglyph's true views with zero disparity: each camera = shared detail +
  its own noise per channel; the restored views as warping gives them (borrowed channels
  are the other camera's)."""
  shared = 0.5 + _smooth(10)
  left_true = np.stack([shared + _noise(20 + c, scale=noise_scale) for c in range(3)], -1)
  right_true = np.stack([shared + _noise(30 + c, scale=noise_scale) for c in range(3)], -1)
  mixture = np.concatenate([left_true[..., :1], right_true[..., 1:]], -1)
  left = np.concatenate([left_true[..., :1], right_true[..., 1:]], -1)  # G, B borrowed.
  right = np.concatenate([left_true[..., :1], right_true[..., 1:]], -1)  # R borrowed.
  return mixture, (left, right), (left_true, right_true)


def test_scaling_brings_noisy_borrowed_channels_nearer_the_truth():
  mixture, restored, truth = _colour_case(0.03)
  spec = mixtures.get_mixture('anaglyph')
  left, right, k = borrowed_detail.scale_borrowed(mixture, spec, *restored, SIGMA)
  assert k < 0.7
  np.testing.assert_array_equal(left[..., 0], restored[0][..., 0])  # The mixture's own.
  np.testing.assert_array_equal(right[..., 1:], restored[1][..., 1:])
  for before, after, true in zip(restored, (left, right), truth):
    error = lambda view: np.mean((view - true) ** 2)
    assert error(after) < 0.85 * error(before)


def test_noise_free_cameras_keep_their_detail():
  mixture, restored, _ = _colour_case(0.0)
  left, right, k = borrowed_detail.scale_borrowed(mixture, mixtures.get_mixture('anaglyph'),
                                                  *restored, SIGMA)
  assert k == pytest.approx(1.0, abs=1e-4)
  np.testing.assert_allclose(left, restored[0], atol=1e-4)
  np.testing.assert_allclose(right, restored[1], atol=1e-4)


def test_off_and_no_eye_with_two_channels_change_nothing():
  mixture, restored, _ = _colour_case(0.03)
  for name, sigma in (('anaglyph', 0.0), ('gray', SIGMA)):
    left, right, k = borrowed_detail.scale_borrowed(mixture, mixtures.get_mixture(name),
                                                    *restored, sigma)
    assert k == 1.0 and left is restored[0] and right is restored[1]
