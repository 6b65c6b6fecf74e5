"""Tests for mixstereo_tf.unmixing.chroma: anaglyphs stored with half-resolution colour."""

import io

import cv2
import numpy as np
from PIL import Image
import skimage.data

from mixstereo_tf.core import hints
from mixstereo_tf.unmixing import chroma
from mixstereo_tf.unmixing import predictors


def _jpeg_anaglyph():
  """A colour anaglyph of a real photo at constant disparity 6 px, saved as Pillow saves a
  JPEG by default (4:2:0, quality 90), and the lossless one."""
  photo = cv2.resize(skimage.data.astronaut(), (256, 256), interpolation=cv2.INTER_AREA)
  left, right = photo[:, 4:244], photo[:, 10:250]  # left(x) = right(x - 6).
  anaglyph = np.dstack([left[..., 0], right[..., 1], right[..., 2]])
  stored = io.BytesIO()
  Image.fromarray(anaglyph).save(stored, 'JPEG', quality=90)
  return np.asarray(Image.open(stored).convert('RGB')), anaglyph


def test_the_colour_resolution_copy_keeps_what_half_resolution_colour_stores():
  flat = np.full((8, 10, 3), 77, np.uint8)
  np.testing.assert_array_equal(chroma.colour_resolution_copy(flat), flat)
  stripes = np.zeros((8, 10, 3), np.uint8)
  stripes[:, ::2] = 200  # A 2-px period: above half resolution, averaged away.
  assert np.ptp(chroma.colour_resolution_copy(stripes)) <= 1


def test_a_4_2_0_jpeg_is_matched_without_the_luminance_detail_that_pulls_towards_zero():
  stored, lossless = _jpeg_anaglyph()
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='anaglyph', disparity_range=(-4, 16)))

  def shares(image, halved):
    out = unmixer(image, hint=hints.FrameHint(chroma_halved=halved))
    inner = out['disparity_left'][20:-20, 30:-30]
    return np.mean(np.abs(inner - 6) <= 1), np.mean(np.abs(inner) <= 1), out

  assert shares(lossless, False)[0] > 0.99
  right_plain, zero_plain, _ = shares(stored, False)
  right_halved, zero_halved, out = shares(stored, True)
  assert zero_plain > 0.04 and zero_halved < zero_plain / 3  # Measured: 6.4% -> 0.8%.
  assert right_halved > right_plain
  assert out['info']['matched_at_colour_resolution']
  # The views keep the stored image's own channel: the left eye's red.
  np.testing.assert_array_equal(out['left'][..., 0], stored[..., 0])



def test_the_views_are_restored_once_and_from_the_stored_image(monkeypatch):
  """The stage matches the copy and restores from the stored image itself: no second
  restoration replaces its views (classical method and the shipped default)."""
  from mixstereo_tf.restoration import views  # pylint: disable=g-import-not-at-top
  stored, _ = _jpeg_anaglyph()
  restored_from = []
  restore_views = views.restore_views

  def counting(mixture, *args, **kwargs):
    restored_from.append(np.asarray(mixture))
    return restore_views(mixture, *args, **kwargs)

  monkeypatch.setattr(views, 'restore_views', counting)
  for method in ('classical', 'model'):
    restored_from.clear()
    unmixer = predictors.build_unmixer(predictors.PredictorConfig(
        method, mixture='anaglyph', disparity_range=(-4, 16)))
    out = unmixer(stored, hint=hints.FrameHint(chroma_halved=True))
    assert len(restored_from) == 1, method
    np.testing.assert_allclose(restored_from[0] * 255, stored, atol=0.01)
    np.testing.assert_array_equal(out['left'][..., 0], stored[..., 0])
