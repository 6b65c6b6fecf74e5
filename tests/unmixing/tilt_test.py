"""Tilted anaglyphs turned level where the matcher gains, their outputs turned back."""

import cv2
import numpy as np
import pytest
import skimage.data

from mixstereo_tf.unmixing import predictors
from mixstereo_tf.unmixing import tilt
from tests.unmixing import detection_test


def _anaglyph(angle: float):
  """Motorcycle's colour anaglyph at half size, turned by `angle` degrees, and its truth
  turned alike (nearest; NaN unknown)."""
  left, right, truth = skimage.data.stereo_motorcycle()
  half = lambda x: cv2.resize(x, (370, 250), interpolation=cv2.INTER_AREA)
  image = detection_test._ours('anaglyph', half(left), half(right))  # pylint: disable=protected-access
  truth = cv2.resize(np.float32(truth), (370, 250), interpolation=cv2.INTER_NEAREST) / 2
  turn = cv2.getRotationMatrix2D((185, 125), angle, 1.0)
  warp = lambda x, how: cv2.warpAffine(x, turn, (370, 250), flags=how,
                                       borderMode=cv2.BORDER_REFLECT)
  return warp(image, cv2.INTER_LINEAR), warp(truth, cv2.INTER_NEAREST)


def test_a_level_anaglyph_is_left_alone_and_off_does_nothing():
  image, _ = _anaglyph(0.0)
  same, deep, back, info = tilt.level(image, None, 'anaglyph', tilt.AUTO)
  assert same is image and deep is None and info == {}
  outputs = {'left': image}
  assert back(outputs) is outputs
  assert tilt.level(image, None, 'anaglyph', tilt.OFF)[0] is image


def test_a_turned_anaglyph_is_turned_level_and_its_outputs_back():
  """Turned by 4 degrees, the classical method with rectify='auto' finds the turn (info
  'tilt'), matches most pixels right where 'off' does not, gives outputs the input's
  size, and copies the encoding's own channels into the views unresampled."""
  image, truth = _anaglyph(4.0)
  inner = (slice(30, -30), slice(40, -40))
  bad = {}
  for setting in ('off', 'auto'):
    out = predictors.build_unmixer(predictors.PredictorConfig(
        'classical', mixture='anaglyph', rectify=setting))(image)
    assert out['left'].shape == image.shape and out['disparity_right'].shape == (250, 370)
    known = np.isfinite(truth)[inner]
    bad[setting] = np.mean(np.abs(out['disparity_left'] - truth)[inner][known] > 1)
    if setting == 'auto':
      assert out['info']['tilt'][0] == pytest.approx(-4.0, abs=1.2)  # The estimate's bias.
      np.testing.assert_array_equal(out['left'][..., 0], image[..., 0])  # R: the left eye.
      np.testing.assert_array_equal(out['right'][..., 1:], image[..., 1:])
    else:
      assert 'tilt' not in out['info']
  assert bad['auto'] < 0.75 * bad['off'], bad


def test_a_shots_turn_is_applied_as_given_and_bad_settings_are_refused():
  image, _ = _anaglyph(4.0)
  turned, _, back, info = tilt.level(image, None, 'anaglyph', (-4.0, 0.0))
  assert info == {'tilt': [-4.0, 0.0]} and turned.shape[0] > image.shape[0]
  outputs = back({'left': turned, 'consistent_left': np.ones(turned.shape[:2], bool),
                  'info': {'x': 1}})
  assert outputs['left'].shape == image.shape and outputs['info'] == {'x': 1}
  assert outputs['consistent_left'].dtype == bool
  with pytest.raises(ValueError, match="PredictorConfig.rectify must be 'auto' or 'off'"):
    predictors.PredictorConfig(rectify='yes')
