"""Tests of the channel matching under encoding detection: known shifts, sizes, ranges."""

import cv2
import numpy as np
import pytest

from mixstereo_tf.unmixing import channel_matching


def _anaglyph(shift=6, height=48, width=160):
  """Red of a texture seen `shift` px further right than its green and blue: the left
  pixel x matches the right pixel x - shift."""
  rng = np.random.default_rng(5)
  gray = cv2.GaussianBlur(rng.uniform(0, 1, (height, width + shift)).astype(np.float32),
                          (3, 3), 0)
  texture = (255 * gray[..., None] * [1.0, 0.9, 0.8]).astype(np.uint8)  # Channels agree.
  return np.dstack([texture[:, :width, 0], texture[:, shift:, 1:]])


def test_downsampled_scales_to_0_255_and_keeps_narrow_images():
  image = _anaglyph()
  small = channel_matching.downsampled(image, 80)
  assert small.shape == (24, 80, 3) and small.dtype == np.float32
  np.testing.assert_allclose(channel_matching.downsampled(image / 255.0, 500), image,
                             atol=1e-3)
  with pytest.raises(ValueError, match='RGB'):
    channel_matching.downsampled(image[..., 0], 80)


def test_eye_match_finds_the_shift_and_rescales_its_range():
  small = channel_matching.downsampled(_anaglyph(), 160)
  search = channel_matching.span(small, 0.2)
  assert search == (-32, 32)
  ys, xs, xr = channel_matching.eye_match(small, 0, search)
  assert ys.size > 0.5 * 48 * 160
  assert np.mean(xs - xr == 6) > 0.95
  low, high = channel_matching.rescaled_search((ys, xs, xr), search, 3.0, 480)
  assert low <= 18 <= high and high - low < 40  # 6 px at three times the width.
