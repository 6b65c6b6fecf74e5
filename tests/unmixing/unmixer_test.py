"""Tests for mixstereo_tf.unmixing.unmixer: the input image and the config's checks."""

import numpy as np
import pytest

from mixstereo_tf.unmixing import unmixer


def test_as_rgb_takes_what_image_files_hold():
  rgb = np.arange(2 * 3 * 3, dtype=np.uint8).reshape(2, 3, 3)
  np.testing.assert_array_equal(unmixer.as_rgb(rgb), rgb)
  rgba = np.concatenate([rgb, np.full((2, 3, 1), 7, np.uint8)], axis=-1)
  np.testing.assert_array_equal(unmixer.as_rgb(rgba), rgb)  # Alpha dropped.
  gray = rgb[..., 0]
  for image in (gray, gray[..., None], np.stack([gray, gray * 0], -1)):  # + alpha.
    np.testing.assert_array_equal(unmixer.as_rgb(image), np.repeat(gray[..., None], 3, -1))
  with pytest.raises(ValueError, match='uint8'):
    unmixer.as_rgb(rgb.astype(np.float32))
  with pytest.raises(ValueError, match='RGBA'):
    unmixer.as_rgb(np.zeros((2, 3, 5), np.uint8))


def test_config_refuses_a_network_size_below_one_pixel():
  for bad in (0, 'big', 2.5):
    with pytest.raises(ValueError, match='max_network_pixels must be a whole number'):
      unmixer.PredictorConfig(max_network_pixels=bad)
  with pytest.raises(ValueError, match='restore_colour must be None, True or False'):
    unmixer.PredictorConfig(restore_colour='no')
  assert unmixer.PredictorConfig(max_network_pixels=None).max_network_pixels is None
