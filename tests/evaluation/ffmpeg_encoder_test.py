"""Tests of the independent encoder: FFmpeg's stereo3d against our matrices (mixtures)."""

import numpy as np
import pytest

from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.evaluation import ffmpeg_encoder

pytest.importorskip('imageio_ffmpeg')


def _views():
  rng = np.random.default_rng(0)
  return (rng.integers(0, 256, (24, 32, 3), dtype=np.uint8),
          rng.integers(0, 256, (24, 32, 3), dtype=np.uint8))


@pytest.mark.parametrize('name', sorted(ffmpeg_encoder.FFMPEG_MODES))
def test_ffmpeg_matches_our_operator(name):
  """FFmpeg's integer matrices equal ours to 1/65536 and floor: at most 1 level apart
  (Dubois: its own rounding of the clipped sums, at most 2)."""
  left, right = _views()
  theirs = ffmpeg_encoder.encode(left, right, name).astype(int)
  ours = image_range.signed_to_u8(mixtures.mix(
      name, image_range.u8_to_signed(left), image_range.u8_to_signed(right)).numpy())
  assert np.abs(theirs - ours.astype(int)).max() <= (2 if 'dubois' in name else 1)


def test_unknown_encoding_and_bad_views_are_refused():
  left, right = _views()
  with pytest.raises(ValueError, match='no .diplopia. anaglyph'):
    ffmpeg_encoder.encode(left, right, 'diplopia')
  with pytest.raises(ValueError, match='one size'):
    ffmpeg_encoder.encode(left, right[:, :10], 'anaglyph')


def _smooth_image():
  """A smooth colour image with one sharp red-cyan edge (colour detail at one pixel)."""
  yy, xx = np.mgrid[:64, :96]
  image = np.stack([80 + xx, 60 + yy, 140 + 0 * xx], -1).astype(np.uint8)
  image[:, 47:, 0] = 20  # At an odd column: inside a 2 x 2 chroma block.
  return image


@pytest.mark.parametrize('codec', ['jpeg', 'h264'])
def test_round_trip_keeps_smooth_colour_and_blurs_chroma_edges(codec):
  image = _smooth_image()
  stored = ffmpeg_encoder.round_trip(image, codec).astype(int)
  assert stored.shape == image.shape
  error = np.abs(stored - image)
  assert np.median(error) <= 2  # Smooth regions survive ...
  # ... but 4:2:0 chroma spreads the red edge over its neighbour columns.
  assert error[:, 45:49, 0].mean() > 4 * max(1.0, error[:, :40, 0].mean())


def test_round_trip_png_is_the_image_and_bad_requests_are_refused():
  image = _smooth_image()
  assert ffmpeg_encoder.round_trip(image, 'png') is image
  with pytest.raises(ValueError, match='webp'):
    ffmpeg_encoder.round_trip(image, 'webp')
  with pytest.raises(ValueError, match='even'):
    ffmpeg_encoder.round_trip(image[:63], 'h264')
