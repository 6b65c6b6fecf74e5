"""Halftone screens: found on prints at their period, not on photographs, and smoothed."""

import numpy as np
import pytest
import skimage.data

from mixstereo_tf.classical import halftone
from mixstereo_tf.data import halftone_print


@pytest.fixture(scope='module')
def picture():
  return skimage.data.astronaut()[:256, :320]


@pytest.mark.parametrize('period', [3.0, 5.0, 7.5])
def test_a_print_shows_its_screen_and_loses_it_once_smoothed(picture, period):
  printed = halftone_print.halftone_print(picture, period)
  found = halftone.find_screen(printed)
  assert found is not None and found.period == pytest.approx(period, rel=0.03), found
  assert found.share >= halftone.HalftoneConfig().min_share
  smooth = halftone.descreen(printed, found.period)
  assert smooth.dtype == np.uint8 and smooth.shape == printed.shape
  assert halftone.find_screen(smooth) is None
  error = lambda x: np.abs(x.astype(float) - picture).mean()
  assert error(smooth) < 0.5 * error(printed), (error(smooth), error(printed))


def test_photographs_and_regular_textures_show_no_screen(picture):
  brick = np.dstack([skimage.data.brick()] * 3)  # A periodic texture, 9 px bricks.
  assert halftone.strongest_peak(brick)[1] > halftone.HalftoneConfig().min_peak
  for image in (picture, brick, skimage.data.coffee(), np.full((200, 200, 3), 90, np.uint8)):
    assert halftone.find_screen(image) is None
  # A flat image with a faint dither: a tall peak over almost no power.
  dither = np.full((256, 256, 3), 100, np.uint8)
  dither[::4, ::4] += 1
  period, peak = halftone.strongest_peak(dither)
  assert peak > 1e4 and halftone.coverage(dither, period) == 0.0
  assert halftone.find_screen(dither) is None


def test_sixteen_bit_prints_and_small_images():
  printed = halftone_print.halftone_print(skimage.data.chelsea()[:200, :300], 4.0)
  deep = printed.astype(np.uint16) * 257
  found = halftone.find_screen(deep)
  assert found is not None and found.period == pytest.approx(4.0, rel=0.03)
  assert halftone.descreen(deep, 4.0).dtype == np.uint16
  assert halftone.find_screen(printed[:100, :100]) is None  # Less than two tiles a side.


def test_resolve_follows_the_setting(picture):
  printed = halftone_print.halftone_print(picture, 4.0)
  same, info = halftone.resolve(printed, halftone.OFF)
  assert same is printed and info == {}
  smooth, info = halftone.resolve(printed, halftone.AUTO)
  assert info['screen_period'] == pytest.approx(4.0, rel=0.03)
  np.testing.assert_array_equal(smooth, halftone.descreen(printed, info['screen_period']))
  assert halftone.resolve(picture, halftone.AUTO)[1] == {}
  assert halftone.resolve(picture, 6)[1] == {'screen_period': 6.0}
  for bad in ('dots', 0.5, True, float('nan')):
    with pytest.raises(ValueError, match="'auto', 'off' or a number of pixels above 1"):
      halftone.resolve(picture, bad)
