"""The numba self-matching volume against the NumPy transcription of its definition."""

import dataclasses

import cv2
import numpy as np
import pytest

from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import diplopia_costs
from mixstereo_tf.classical import sgm


def _reference(gray, config):
  """`diplopia_costs.self_matching_volume` written with OpenCV box filters, lag by lag."""
  matching = config.matching
  height, width = gray.shape
  high = (gray - cv2.GaussianBlur(gray, (0, 0), config.highpass_sigma)).astype(np.float32)
  window = (2 * config.window_radius + 1,) * 2
  energy = cv2.boxFilter(high * high, -1, window)
  lags = range(matching.min_disparity, min(matching.max_disparity, width - 1) + 1)
  volume = np.full((len(lags), height, width), config.cost_scale, np.float32)
  for i, d in enumerate(lags):
    product = np.zeros_like(high)
    product[:, d:] = high[:, d:] * high[:, :width - d]
    shifted = np.zeros_like(energy)
    shifted[:, d:] = energy[:, :width - d]
    zncc = cv2.boxFilter(product, -1, window) / np.sqrt(energy * shifted + 1e-6)
    volume[i, :, d:] = (1.0 - zncc[:, d:]) * config.cost_scale
  envelope = np.maximum.accumulate([volume[i, :, d:].mean() for i, d in enumerate(lags)])
  volume += (envelope.max() - envelope)[:, None, None]
  return np.clip(np.rint(volume), 0, 255).astype(np.uint8).transpose(1, 2, 0)


def test_the_kernel_equals_the_definition():
  rng = np.random.default_rng(0)
  texture = cv2.GaussianBlur(rng.uniform(0, 255, (48, 90)).astype(np.float32), (0, 0), 1.5)
  gray = (texture + np.roll(texture, 7, axis=1)) / 2  # An echo at lag 7.
  config = diplopia.DiplopiaConfig(matching=sgm.SgmConfig(min_disparity=2, max_disparity=30))
  got, want = diplopia_costs.self_matching_volume(gray, config), _reference(gray, config)
  assert got.shape == want.shape == (48, 90, 29)
  difference = np.abs(got.astype(int) - want)
  # float32 sums in another order: a rounding tie may go the other way.
  assert difference.max() <= 1 and np.mean(difference > 0) < 1e-3
  assert np.argmin(got[:, 40:].astype(int).sum(axis=(0, 1))) == 7 - 2


def test_lags_up_to_the_image_width_and_windows_wider_than_it():
  rng = np.random.default_rng(1)
  gray = rng.uniform(0, 255, (9, 12)).astype(np.float32)
  config = diplopia.DiplopiaConfig(window_radius=7,
                                   matching=sgm.SgmConfig(min_disparity=1, max_disparity=40))
  got, want = diplopia_costs.self_matching_volume(gray, config), _reference(gray, config)
  assert got.shape == want.shape == (9, 12, 11)  # Lags 1..11: the width minus one.
  assert np.abs(got.astype(int) - want).max() <= 1


def test_two_passes_give_the_stored_costs_volume_bit_for_bit():
  # Above max_float_mib no float volume is stored: the kernel runs twice (means, then
  # the uint8 volume). Both routes must quantise the same floats the same way.
  rng = np.random.default_rng(2)
  texture = cv2.GaussianBlur(rng.uniform(0, 255, (37, 83)).astype(np.float32), (0, 0), 1.2)
  gray = (texture + np.roll(texture, 5, axis=1)) / 2
  config = diplopia.DiplopiaConfig(matching=sgm.SgmConfig(min_disparity=1, max_disparity=40))
  stored = diplopia_costs.self_matching_volume(gray, config)
  twice = diplopia_costs.self_matching_volume(gray, dataclasses.replace(config, max_float_mib=0))
  assert stored.dtype == twice.dtype == np.uint8
  np.testing.assert_array_equal(twice, stored)
  assert np.abs(stored.astype(int) - _reference(gray, config)).max() <= 1


def test_a_negative_float_budget_is_refused():
  with pytest.raises(ValueError, match='max_float_mib'):
    diplopia.DiplopiaConfig(max_float_mib=-1)
