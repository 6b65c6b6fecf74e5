"""Tests of colour_sets: the colour sets of the anaglyph encodings (detection's step 2)."""

import numpy as np
import pytest

from mixstereo_tf.core import mixtures
from mixstereo_tf.unmixing import colour_sets
from mixstereo_tf.unmixing import detection


def test_needed_share_follows_the_sets_volume():
  config = detection.DetectConfig()
  # A thinner set is likelier per sample, so it may leave more samples outside.
  red_cyan, green_magenta = (colour_sets.needed_share(n, config)
                             for n in ('half_color', 'green_magenta_half'))
  assert 0.9 < red_cyan < green_magenta < 1.0
  gain = -np.log(0.299)
  assert red_cyan == pytest.approx(1 - gain / (gain + config.outside_penalty), rel=1e-2)
  assert colour_sets.needed_share('gray', config) == config.singular_share


def test_gray_tolerance_is_noise_or_a_share_of_the_displacement_detail():
  config = detection.DetectConfig()
  flat = np.zeros((10, 10), np.float32)
  assert colour_sets.gray_tolerance(flat, config) == pytest.approx(255 * config.noise / 2)
  detail = np.arange(100, dtype=np.float32).reshape(10, 10)  # 90 % quantile: 89.1.
  assert colour_sets.gray_tolerance(detail, config) == pytest.approx(
      config.gray_relative * 89.1)


def test_a_gray_encoding_explains_channels_equal_up_to_that_tolerance():
  config = detection.DetectConfig(gray_blur=1)
  small = np.zeros((40, 60, 3), np.float32)
  small[..., 0] = np.where(np.arange(60) % 2, 255.0, 0.0)  # Odd-eye detail: 127.5 ...
  small[..., 1] = small[..., 2] = 100.0
  small[:, :30, 2] += 20.0  # ... so G - B = 20 on half the pixels is within 0.35 x 127 ...
  assert colour_sets.explained_share(small, None, 'gray', config) == 1.0
  small[:, :30, 2] += 30.0  # ... and 50 is not.
  assert colour_sets.explained_share(small, None, 'gray', config) == pytest.approx(0.5)
  small[..., 0] = 128.0  # Without detail the tolerance is noise / 2.
  small[:, :30, 2] = 104.0
  assert colour_sets.explained_share(small, None, 'gray', config) == pytest.approx(0.5)


@pytest.mark.parametrize('name', ['anaglyph', 'half_color', 'optimized'])
def test_each_encoding_explains_its_own_colours(name):
  rng = np.random.default_rng(1)
  matrix = (np.asarray(mixtures.get_mixture(name).left_matrix) +
            np.asarray(mixtures.get_mixture(name).right_matrix))
  obs = np.clip(rng.uniform(0, 1, (500, 3)) @ matrix.T, 0, 1)
  assert colour_sets.residuals(obs, name).max() < 1e-4
  assert colour_sets.size(name)[0] == (2 if name == 'optimized' else 3)
