"""Matching on a reduced copy: the factor, the copy's range and prior, the way back, and a
double image whose echo only the reduced copy finds."""

import cv2
import numpy as np
import pytest

from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import working_scale


@pytest.mark.parametrize('width, max_width, want', [
    (1280, 1280, 1), (1281, 1280, 2), (1920, 1280, 2), (4000, 1280, 4), (4000, 0, 1),
    (2561, 1280, 3)])
def test_the_factor_brings_the_width_within_the_limit(width, max_width, want):
  assert working_scale.factor(width, max_width) == want
  assert -(-width // want) <= max_width or max_width == 0


def test_the_copy_maps_the_range_and_the_prior_into_its_pixels():
  image = np.random.default_rng(0).uniform(0, 1, (30, 81, 3)).astype(np.float32)
  prior = np.full((30, 81), 12.0, np.float32)
  prior[:, :10] = np.nan
  copy = working_scale.reduce(image, 4, (3, 50), prior)
  assert copy.image.shape == (8, 21, 3)  # Sizes rounded up.
  assert copy.scale == pytest.approx(81 / 21)
  assert copy.search == (1, 13)  # floor(3 / 3.86) raised to 1, ceil(50 / 3.86).
  assert copy.prior.shape == (8, 21) and np.isnan(copy.prior[:, 0]).all()
  np.testing.assert_allclose(copy.prior[:, -1], 12.0 * 21 / 81, rtol=1e-6)
  same = working_scale.reduce(image, 1, (3, 50), prior)
  assert same.image is image and same.prior is prior and same.search == (3, 50)


def test_enlarging_scales_the_values_and_keeps_a_full_size_map():
  small = np.full((8, 21), 3.0, np.float32)
  big = working_scale.enlarge(small, (30, 81), 81 / 21)
  assert big.shape == (30, 81) and big.dtype == np.float32
  np.testing.assert_allclose(big, 3.0 * 81 / 21, rtol=1e-6)
  assert working_scale.enlarge(big, (30, 81), 5.0) is big


def test_a_coarse_wide_echo_is_found_on_the_reduced_copy_only():
  # Texture four times coarser than the 15 x 15 ZNCC window expects and a 40 px echo, as a
  # photograph four times wider than the frames the matcher was tuned on shows them: at
  # full size the windows see too little, on the copy reduced to 160 px they do not.
  rng = np.random.default_rng(1)
  lag, height, width = 40, 96, 640
  texture = cv2.GaussianBlur(rng.uniform(0, 255, (height, width + lag)).astype(np.float32),
                             (0, 0), 4.0)
  texture = (texture - texture.mean()) * (40 / texture.std()) + 128
  left, right = texture[:, lag:], texture[:, :width]  # Left x matches right x - 40.
  double = np.clip((left + right) / 2 + rng.normal(0, 3, left.shape), 0, 255)
  image = np.repeat(double.astype(np.uint8)[..., None], 3, axis=-1)

  def unmixed(max_width):
    return diplopia.unmix_diplopia(image, (1, 80), diplopia.DiplopiaConfig(max_width=max_width))

  def found(out):
    return np.mean(np.abs(out['disparity_left'][:, 100:] - lag) <= 2)

  full, reduced = unmixed(0), unmixed(160)
  assert found(full) < 0.9  # 0.82 on 2 cores.
  assert found(reduced) > 0.98  # 1.0: the copy is 160 px wide, the echo 10 px there.
  assert reduced['left'].shape == image.shape and reduced['disparity_right'].shape == (96, 640)
  assert reduced['disparity_range'] == (1, 80)  # Reported in full pixels.


def test_a_video_prior_reaches_the_reduced_copy_in_its_pixels():
  # A 1080p-like frame of a shot: the previous frame's full-size disparity (NaN where it
  # failed) is the prior; the copy searches around it in its own pixels.
  rng = np.random.default_rng(2)
  lag, height, width = 24, 64, 400
  texture = cv2.GaussianBlur(rng.uniform(0, 255, (height, width + lag)).astype(np.float32),
                             (0, 0), 2.0)
  double = (texture[:, lag:] + texture[:, :width]) / 2
  image = np.repeat(np.clip(double, 0, 255).astype(np.uint8)[..., None], 3, axis=-1)
  prior = np.full((height, width), float(lag), np.float32)
  prior[:, :40] = np.nan
  config = diplopia.DiplopiaConfig(max_width=200)  # Reduced twice: the echo at 12 px.
  out = diplopia.unmix_diplopia(image, (1, 60), config, prior=prior, prior_window=(1, 2))
  assert out['disparity_left'].shape == (height, width) and out['left'].shape == image.shape
  assert np.mean(np.abs(out['disparity_left'][:, 80:] - lag) <= 2) > 0.95
