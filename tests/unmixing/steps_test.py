"""Tests of unmixing.steps: ranges, the encoding's use (a mixing weight, signed disparities)
and bad input."""

from absl import logging
import numpy as np
import pytest

from mixstereo_tf.unmixing import predictors
from mixstereo_tf.unmixing import steps
from tests.unmixing import chroma_test
from tests.unmixing import detection_test


def _anaglyph(name='anaglyph'):
  left, right, disparity = detection_test._pair()  # pylint: disable=protected-access
  return detection_test._ours(name, left, right), disparity  # pylint: disable=protected-access


def test_a_mixing_weight_on_a_detected_anaglyph_is_reported_unused():
  image, _ = _anaglyph('gray')
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='auto', mixing_weight=0.3, disparity_range=(0, 16)))
  info = unmixer(image)['info']
  assert info['mixture'] == 'gray' and info['mixing_weight_unused'] == 0.3


def test_classical_auto_recovers_signed_disparities():
  """The pair's disparities are 4..14 px; window-shifted by 9 px they straddle zero."""
  image, _ = _anaglyph()
  shifted = np.concatenate([image[:, 9:, :1], image[:, :-9, 1:]], axis=-1)  # d - 9.
  unmixer = predictors.build_unmixer(predictors.PredictorConfig('classical', mixture='auto'))
  out = unmixer(shifted)
  low, high = out['info']['disparity_range']
  assert low <= -5 and high >= 5 and out['info']['mixture'] == 'anaglyph'
  d = out['disparity_left'][20:-20, 30:-30]
  assert (d < -2).mean() > 0.2 and (d > 2).mean() > 0.2


def test_a_range_with_min_not_below_max_is_refused():
  with pytest.raises(ValueError, match='MIN < MAX'):
    predictors.build_unmixer(predictors.PredictorConfig('classical', mixture='anaglyph',
                                                      disparity_range=(5, 5)))


def test_a_requested_range_beyond_the_image_is_clipped_and_said(caplog):
  image = np.zeros((8, 40, 3), np.uint8)
  assert steps.estimate_range(image, 'anaglyph', (-5, 7), (0, 9)) == (-5, 7)
  with caplog.at_level('WARNING'):
    assert steps.estimate_range(image, 'anaglyph', (-2000, 2000), (0, 9)) == (-39, 39)
  assert 'searching [-39, 39]' in caplog.text
  with pytest.raises(ValueError, match=r'\[100, 200\] holds no disparity of an image 40 px'):
    steps.estimate_range(image, 'anaglyph', (100, 200), (0, 9))


def test_a_given_range_the_scene_reaches_past_is_warned_about(monkeypatch):
  warnings = []
  monkeypatch.setattr(logging, 'warning', lambda msg, *args: warnings.append(msg % args))
  _, lossless = chroma_test._jpeg_anaglyph()  # pylint: disable=protected-access
  for search in ((-4, 16), (0, 3)):
    predictors.build_unmixer(predictors.PredictorConfig(
        'classical', mixture='anaglyph', disparity_range=search))(lossless)
  assert len(warnings) == 1 and 'at the high limit of the range given, [0, 3]' in warnings[0]
