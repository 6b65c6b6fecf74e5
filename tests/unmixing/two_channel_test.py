"""Red-blue and red-green anaglyphs: found by their empty channel, unmixed as gray ones."""

import cv2
import numpy as np
import skimage.data

import mixstereo_tf
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.unmixing import detection
from mixstereo_tf.unmixing import two_channel


def _pair():
  """Motorcycle's views at a third of their size (uint8 RGB)."""
  left, right, _ = skimage.data.stereo_motorcycle()
  third = lambda x: cv2.resize(x, (247, 167), interpolation=cv2.INTER_AREA)
  return third(left), third(right)


def _mixed(name, left, right):
  return image_range.signed_to_u8(mixtures.mix(
      name, image_range.u8_to_signed(left), image_range.u8_to_signed(right)).numpy())


def test_the_empty_channel_is_found_only_beside_two_pictures():
  left, right = _pair()
  assert two_channel.empty_channel(np.float32(_mixed('red_blue', left, right))) == 1
  assert two_channel.empty_channel(np.float32(_mixed('red_green', left, right))) == 2
  assert two_channel.empty_channel(np.float32(_mixed('gray', left, right))) is None
  assert two_channel.empty_channel(np.float32(left)) is None
  black = np.float32(_mixed('red_blue', left, right))
  black[..., 2] = 3.0  # Two channels empty: no anaglyph of two eyes.
  assert two_channel.empty_channel(black) is None


def test_two_channel_anaglyphs_are_detected_even_as_jpegs_and_a_photo_is_refused():
  left, right = _pair()
  for name in ('red_blue', 'red_green'):
    image = _mixed(name, left, right)
    _, data = cv2.imencode('.jpg', image[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, 75])
    for stored in (image, cv2.imdecode(data, cv2.IMREAD_COLOR)[..., ::-1]):
      found = detection.detect(stored)
      assert found.name == name and found.confidence > 0.9, found
  flat = np.dstack([left[..., 0], np.zeros_like(left[..., 0]), left[..., 2]])
  found = detection.detect(flat)  # One view's red and blue: aligned, G empty.
  assert found.name is None and 'not displaced' in found.reason, found


def test_a_red_blue_anaglyph_is_unmixed_as_the_gray_one_and_says_so():
  """The served image equals the gray red-cyan anaglyph (`mixtures.served`), so are the
  outputs; the info names both."""
  left, right = _pair()
  image, gray = _mixed('red_blue', left, right), _mixed('gray', left, right)
  served = mixtures.served(image, 'red_blue')
  assert np.abs(served.astype(int) - gray).max() <= 1  # Two roundings of the same lumas.
  gray = served
  ours = mixstereo_tf.unmix(image, method='classical')
  theirs = mixstereo_tf.unmix(gray, mixture='gray', method='classical')
  assert ours.info['mixture'] == 'red_blue' and ours.info['unmixed_as'] == 'gray'
  np.testing.assert_array_equal(ours.disparity, theirs.disparity)
  np.testing.assert_array_equal(ours.left, theirs.left)
  assert 'unmixed_as' not in theirs.info
  assert mixtures.parse_names('anaglyphs') == tuple(
      n for n in mixtures.ANAGLYPH_NAMES if n not in ('red_blue', 'red_green'))


def _print(left, right, odd, lumas=None):
  """Two inks on white paper, an eye each (red-blue: the left view in blue ink, the right in
  red ink): the channel `odd` is dark wherever either ink is, the other two's product."""
  lumas = lumas or [cv2.cvtColor(v, cv2.COLOR_RGB2GRAY).astype(np.float64)
                    for v in (left, right)]
  eyes = [c for c in range(3) if c != odd]
  image = np.empty(left.shape, np.float64)
  image[..., eyes[0]], image[..., eyes[1]] = lumas
  image[..., odd] = lumas[0] * lumas[1] / 255.0
  noise = np.random.default_rng(0).normal(0.0, 1.5, image.shape)
  return np.uint8(np.clip(np.rint(0.92 * image + 8 + noise), 0, 255))


def test_a_two_ink_print_is_found_by_its_ink_channel_and_a_gray_anaglyph_is_not():
  left, right = _pair()
  for name, odd in (('red_blue', 1), ('red_green', 2)):
    printed = _print(left, right, odd)
    assert two_channel.empty_channel(np.float32(printed)) is None  # Paper: nothing empty.
    assert two_channel.ink_channel(np.float32(printed)) == odd
    found = detection.detect(printed)
    assert found.name == name and 'product' in found.reason, found
  for name in ('gray', 'anaglyph', 'half_color'):  # G is B, or the right eye's own green.
    assert two_channel.ink_channel(np.float32(_mixed(name, left, right))) is None


def test_a_photograph_whose_green_is_its_red_times_blue_is_refused_as_before():
  """R and B of one view, aligned: the ink channel stands for nothing, the families decide;
  the same view in both inks is no print of two (its square explains the product)."""
  left, _ = _pair()
  assert two_channel.ink_channel(np.float32(_print(left, left, 1))) is None
  own = [left[..., c].astype(np.float64) for c in (0, 2)]  # One view's red and blue.
  printed = _print(left, left, 1, own)
  assert two_channel.ink_channel(np.float32(printed)) == 1
  assert two_channel.detect(np.float32(printed), 0.25, 0.08, 0.02) is None
  found = detection.detect(printed)
  assert found.name is None and 'no colour channel is displaced' in found.reason, found
