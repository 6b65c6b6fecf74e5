"""Tests for mixstereo_tf.classical.sgbm: OpenCV's SGBM on an anaglyph's eye channels."""

import cv2
import numpy as np
import pytest

from mixstereo_tf.classical import sgbm
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures


def shifted_pair(d, height=96, width=160, seed=0):
  """A textured colour pair whose left x matches right x - d everywhere (uint8)."""
  rng = np.random.RandomState(seed)
  margin = abs(d)
  texture = cv2.GaussianBlur(rng.uniform(0, 255, (height, width + 2 * margin)), (0, 0), 1.2)
  texture = (texture - texture.min()) / np.ptp(texture) * 200 + 25
  tint = 1.0 + 0.1 * rng.uniform(-1, 1, (height, width + 2 * margin, 3))
  base = np.clip(texture[..., None] * tint * (1.0, 0.9, 0.8), 0, 255).astype(np.uint8)
  left = base[:, margin:margin + width]
  right = base[:, margin + d:margin + d + width]  # right[x - d] == left[x].
  return left, right


def anaglyph_of(left, right, name='anaglyph'):
  mixed = mixtures.mix(name, image_range.u8_to_signed(left), image_range.u8_to_signed(right))
  return image_range.signed_to_u8(np.asarray(mixed))


def inner(array, border=24):
  return array[8:-8, border:-border]


@pytest.mark.parametrize('d, search, name', [(6, (0, 15), 'anaglyph'),
                                             (-5, (-12, 12), 'anaglyph'),
                                             (4, (-3, 20), 'green_magenta_half')])
def test_match_anaglyph_recovers_a_constant_shift(d, search, name):
  image = anaglyph_of(*shifted_pair(d), name)
  d_left, d_right = sgbm.match_anaglyph(image, name, *search)
  assert d_left.shape == d_right.shape == image.shape[:2]
  assert d_left.dtype == d_right.dtype == np.float32
  assert np.mean(np.abs(inner(d_left) - d) <= 1.0) > 0.9
  assert np.mean(np.abs(inner(d_right) - d) <= 1.0) > 0.9  # Same sign for the right view.


def test_answers_beyond_the_asked_range_are_not_kept():
  """[0, 20] runs 32 levels; a true shift of 26 px would be found at 26 without the cut."""
  left, right = shifted_pair(26)
  for d_map in sgbm.match_anaglyph(anaglyph_of(left, right), 'anaglyph', 0, 20):
    assert d_map.min() >= 0 and d_map.max() <= 20
  found, valid = sgbm.match(*sgbm.eye_pair(anaglyph_of(left, right), 'anaglyph'), 0, 31)
  assert np.mean(np.abs(inner(found) - 26) <= 1.0) > 0.9 and valid.mean() > 0.5


def test_eye_pair_is_the_mean_of_each_eyes_channels():
  image = np.zeros((2, 3, 3), np.uint8)
  image[..., 0], image[..., 1], image[..., 2] = 200, 10, 31
  left, right = sgbm.eye_pair(image, 'anaglyph')  # Red against mean(green, blue).
  assert left.dtype == right.dtype == np.uint8
  np.testing.assert_array_equal(left, 200)
  np.testing.assert_array_equal(right, 20)  # 20.5 rounds to even.


def test_sgbm_levels_round_up_to_multiples_of_16():
  assert sgbm.sgbm_levels(0, 15) == (0, 16)
  assert sgbm.sgbm_levels(-12, 12) == (-12, 32)
  assert sgbm.sgbm_levels(3, 40) == (3, 48)
  with pytest.raises(ValueError, match='min < max'):
    sgbm.sgbm_levels(5, 5)


def test_fill_from_left_takes_the_nearest_valid_pixel():
  disparity = np.array([[9, 1, 9, 9, 4, 9], [9, 9, 2, 9, 9, 9], [9, 9, 9, 9, 9, 9]],
                       np.float32)
  valid = np.array([[0, 1, 0, 0, 1, 0], [0, 0, 1, 0, 0, 0], [0, 0, 0, 0, 0, 0]], bool)
  filled = sgbm.fill_from_left(disparity, valid)
  np.testing.assert_array_equal(filled[0], [1, 1, 1, 1, 4, 4])
  np.testing.assert_array_equal(filled[1], [2, 2, 2, 2, 2, 2])
  np.testing.assert_array_equal(filled[2], 2.0)  # No valid pixel: the median of the valid.
