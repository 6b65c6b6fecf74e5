"""Tests of unmixing.mixture_choice: the encoding asked for or detected, and its warnings."""

from absl import logging
import numpy as np
import pytest

from mixstereo_tf.core import mixtures
from mixstereo_tf.unmixing import detection
from mixstereo_tf.unmixing import mixture_choice
from tests.unmixing import detection_test


def _anaglyph(name='anaglyph'):
  left, right, disparity = detection_test._pair()  # pylint: disable=protected-access
  return detection_test._ours(name, left, right), disparity  # pylint: disable=protected-access

def test_auto_takes_the_detected_encoding():
  image, _ = _anaglyph('gray')
  name, info = mixture_choice.resolve_mixture(image, 'auto', mixtures.ANAGLYPH_NAMES)
  assert name == 'gray' and info['detected'] == 'gray' and info['confidence'] > 0.9


def test_auto_on_a_half_colour_anaglyph_records_and_warns_that_colour_fits_too(monkeypatch):
  warnings = []
  monkeypatch.setattr(logging, 'warning', lambda msg, *args: warnings.append(msg % args))
  name, info = mixture_choice.resolve_mixture(_anaglyph('half_color')[0], 'auto',
                                           mixtures.ANAGLYPH_NAMES)
  assert name == 'half_color' and info['also_fits'] == 'anaglyph'
  assert len(warnings) == 1 and 'anaglyph fits it as well' in warnings[0]
  assert ("reading anaglyph as half_color lost about 13 dB of the views' PSNR, reading "
          'half_color as anaglyph about 6 dB.') in warnings[0]
  warnings.clear()
  _, info = mixture_choice.resolve_mixture(_anaglyph('anaglyph')[0], 'auto',
                                        mixtures.ANAGLYPH_NAMES)
  assert 'also_fits' not in info and not warnings


def test_auto_records_and_warns_a_doubtful_detection(monkeypatch):
  warnings = []
  monkeypatch.setattr(logging, 'warning', lambda msg, *args: warnings.append(msg % args))
  image = detection_test._weakly_displaced(18)  # pylint: disable=protected-access
  name, info = mixture_choice.resolve_mixture(image, 'auto', mixtures.ANAGLYPH_NAMES)
  assert name == 'amber_blue' and 'displaced only weakly' in info['detection_doubt']
  assert len(warnings) == 1 and 'if the image is no anaglyph' in warnings[0]
  _, info = mixture_choice.resolve_mixture(image, 'amber_blue', mixtures.ANAGLYPH_NAMES)
  assert 'detection_doubt' not in info  # Named: the user knows.


def test_auto_refuses_a_plain_photo_with_a_clear_message():
  left, _, _ = detection_test._pair()  # pylint: disable=protected-access
  with pytest.raises(mixture_choice.NoAnaglyphError,
                     match='does not look like an anaglyph.*if it is a double image, name it'):
    mixture_choice.resolve_mixture(left, 'auto', mixtures.ANAGLYPH_NAMES)


def test_auto_reads_a_frame_without_an_anaglyph_as_the_videos_encoding():
  left, _, _ = detection_test._pair()  # pylint: disable=protected-access
  for frame in (left, np.zeros_like(left), np.zeros((4, 4, 3), np.uint8)):  # Too small.
    name, info = mixture_choice.resolve_mixture(frame, 'auto', mixtures.ANAGLYPH_NAMES,
                                       fallback='dubois')
    assert name == 'dubois' and info['detected'] is None and 'dubois' in info['read_as']
  image, _ = _anaglyph('gray')  # A frame that shows its own encoding keeps it.
  assert mixture_choice.resolve_mixture(image, 'auto', mixtures.ANAGLYPH_NAMES,
                               fallback='dubois')[0] == 'gray'
  with pytest.raises(mixture_choice.NoAnaglyphError, match='too small|at least'):
    mixture_choice.resolve_mixture(np.zeros((4, 4, 3), np.uint8), 'auto', mixtures.ANAGLYPH_NAMES)


def test_auto_reads_a_plain_image_as_the_double_image_a_predictor_expects():
  left, _, _ = detection_test._pair()  # pylint: disable=protected-access
  name, info = mixture_choice.resolve_mixture(left, 'auto', ('diplopia',))  # A diplopia model.
  assert name == 'diplopia' and 'only encoding' in info['read_as']
  both = mixtures.ANAGLYPH_NAMES + ('diplopia',)
  name, info = mixture_choice.resolve_mixture(left, 'auto', both, weighted=True)
  assert name == 'diplopia' and 'mixing weight' in info['read_as']
  with pytest.raises(ValueError, match='does not look like an anaglyph'):
    mixture_choice.resolve_mixture(left, 'auto', both)  # Anything else still has to be named.
  image, _ = _anaglyph('gray')
  assert mixture_choice.resolve_mixture(image, 'auto', both, weighted=True)[0] == 'gray'


def test_a_wrong_explicit_mixture_warns_with_the_detected_one(monkeypatch):
  warnings = []
  monkeypatch.setattr(logging, 'warning', lambda msg, *args: warnings.append(msg % args))
  image, _ = _anaglyph('gray')
  name, _ = mixture_choice.resolve_mixture(image, 'anaglyph', mixtures.ANAGLYPH_NAMES)
  assert name == 'anaglyph'  # The user's choice is kept...
  assert len(warnings) == 1 and "'anaglyph', but the detector reads it as 'gray'" in warnings[0]
  warnings.clear()
  mixture_choice.resolve_mixture(image, 'gray', mixtures.ANAGLYPH_NAMES)
  assert not warnings


def test_named_glasses_the_detector_contradicts_warn_below_the_encoding_threshold(
    monkeypatch):
  warnings = []
  monkeypatch.setattr(logging, 'warning', lambda msg, *args: warnings.append(msg % args))
  found = detection.Detection('anaglyph', 0.87, 'red_cyan channels', {})
  monkeypatch.setattr(detection, 'detect', lambda image: found)
  image = np.zeros((32, 32, 3), np.uint8)
  # Same glasses: kept.
  mixture_choice.resolve_mixture(image, 'half_color', mixtures.ANAGLYPH_NAMES)
  assert not warnings
  for named in ('green_magenta', 'diplopia'):
    allowed = mixtures.ANAGLYPH_NAMES + ('diplopia',)
    assert mixture_choice.resolve_mixture(image, named, allowed)[0] == named
  assert len(warnings) == 2 and all("reads it as 'anaglyph' (confidence 0.87)" in w
                                    for w in warnings)
  warnings.clear()
  found = detection.Detection('green_magenta_half', 0.77, 'noise', {})  # A noise image's.
  mixture_choice.resolve_mixture(image, 'anaglyph', mixtures.ANAGLYPH_NAMES)
  assert not warnings


def test_a_named_double_image_says_its_confidence_is_that_it_is_no_anaglyph():
  rng = np.random.default_rng(1)
  gray = rng.integers(0, 256, (64, 96, 1), dtype=np.uint8)
  double = np.repeat((gray.astype(np.uint16) + np.roll(gray, 5, 1)) // 2, 3, 2)
  name, info = mixture_choice.resolve_mixture(double.astype(np.uint8), 'diplopia', ('diplopia',))
  assert name == 'diplopia' and info['detected'] is None and info['confidence'] > 0.5
  assert info['detection'].startswith('no anaglyph (')


def test_a_named_mixture_needs_no_detection_of_a_thin_image():
  """Detection needs 16 px rows (here: 12, at full size: a 48-px frame); a named encoding
  only warns from it."""
  thin = np.random.default_rng(0).integers(0, 256, (12, 4440, 3), dtype=np.uint8)
  name, info = mixture_choice.resolve_mixture(thin, 'anaglyph', mixtures.ANAGLYPH_NAMES)
  assert name == 'anaglyph' and info['detected'] is None and '16x16' in info['detection']
  with pytest.raises(ValueError, match=r'16x16 .* cannot be detected on it: name its mixture'):
    mixture_choice.resolve_mixture(thin, 'auto', mixtures.ANAGLYPH_NAMES)
  with pytest.raises(ValueError, match=r'this predictor unmixes .*: choose one that unmixes'):
    mixture_choice.resolve_mixture(thin, 'diplopia', mixtures.ANAGLYPH_NAMES)
