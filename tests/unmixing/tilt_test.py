"""Tilted anaglyphs turned level where the matcher gains, their outputs turned back."""

import cv2
import numpy as np
import pytest
import skimage.data

from mixstereo_tf.core import hints
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.unmixing import tilt
from tests.unmixing import detection_test


def _anaglyph(angle: float):
  """Motorcycle's colour anaglyph at half size, turned by `angle` degrees, and its truth
  turned alike (nearest; NaN unknown)."""
  left, right, truth = skimage.data.stereo_motorcycle()
  half = lambda x: cv2.resize(x, (370, 250), interpolation=cv2.INTER_AREA)
  ours = detection_test._ours  # pylint: disable=protected-access
  image = ours('anaglyph', half(left), half(right))
  truth = cv2.resize(np.float32(truth), (370, 250), interpolation=cv2.INTER_NEAREST) / 2
  turn = cv2.getRotationMatrix2D((185, 125), angle, 1.0)
  warp = lambda x, how: cv2.warpAffine(x, turn, (370, 250), flags=how,
                                       borderMode=cv2.BORDER_REFLECT)
  return warp(image, cv2.INTER_LINEAR), warp(truth, cv2.INTER_NEAREST)


def test_a_level_anaglyph_is_left_alone_and_off_does_nothing():
  image, _ = _anaglyph(0.0)
  hint = hints.FrameHint()
  same, deep, same_hint, back, info = tilt.level(image, None, 'anaglyph', tilt.AUTO, hint)
  assert same is image and deep is None and same_hint is hint and info == {}
  outputs = {'left': image}
  assert back(outputs) is outputs
  assert tilt.level(image, None, 'anaglyph', tilt.OFF, hint)[0] is image


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
  turned, _, _, back, info = tilt.level(image, None, 'anaglyph', (-4.0, 0.0),
                                        hints.FrameHint())
  assert info == {'tilt': [-4.0, 0.0]} and turned.shape[0] > image.shape[0]
  outputs = back({'left': turned, 'consistent_left': np.ones(turned.shape[:2], bool),
                  'info': {'x': 1}})
  assert outputs['left'].shape == image.shape and outputs['info'] == {'x': 1}
  assert outputs['consistent_left'].dtype == bool
  with pytest.raises(ValueError, match="PredictorConfig.rectify must be 'auto' or 'off'"):
    predictors.PredictorConfig(rectify='yes')


def test_a_video_frame_of_a_turned_shot_takes_its_prior_and_gives_its_maps_in_its_frame():
  """A shot's later frame: its prior (the previous frame's left disparity, in the input's
  frame) is turned with the image, and the early maps the video loop takes as the next
  prior (`FrameHint.on_disparity`) come back in the input's frame."""
  image, _ = _anaglyph(3.0)
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='anaglyph', rectify='auto'))
  first = unmixer(image)
  told = []
  hint = hints.FrameHint(mixture='anaglyph', rectify=tuple(first['info']['tilt']),
                         disparity_range=tuple(first['info']['disparity_range']),
                         prior=first['disparity_left'], prior_window=(4, 4),
                         on_disparity=told.append)
  second = unmixer(image, hint=hint)
  assert second['info']['prior'] and second['info']['tilt'] == first['info']['tilt']
  assert told and told[0]['disparity_left'].shape == image.shape[:2]
  assert np.mean(np.abs(second['disparity_left'] - first['disparity_left']) <= 1) > 0.9


def test_a_turned_double_image_is_turned_level_and_its_outputs_back():
  """Motorcycle's double image turned by 4 degrees: 'auto' finds the turn from its echo
  (`classical/echo_tilt`), the classical method then matches most pixels right where
  'off' does not, and its outputs have the input's size."""
  left, right, truth = skimage.data.stereo_motorcycle()
  half = lambda x: np.float32(cv2.resize(x, (370, 250), interpolation=cv2.INTER_AREA))
  mixed = np.uint8(np.round((half(left) + half(right)) / 2))
  turn = cv2.getRotationMatrix2D((185, 125), 4.0, 1.0)
  warp = lambda x, how: cv2.warpAffine(x, turn, (370, 250), flags=how,
                                       borderMode=cv2.BORDER_REFLECT)
  truth = cv2.resize(np.float32(truth), (370, 250), interpolation=cv2.INTER_NEAREST) / 2
  image, truth = warp(mixed, cv2.INTER_LINEAR), warp(truth, cv2.INTER_NEAREST)
  inner = (slice(30, -30), slice(40, -40))
  known = (truth > 0)[inner]
  bad = {}
  for setting in ('off', 'auto'):
    out = predictors.build_unmixer(predictors.PredictorConfig(
        'classical', mixture='diplopia', rectify=setting))(image)
    assert out['left'].shape == image.shape and out['disparity_right'].shape == (250, 370)
    bad[setting] = np.mean(np.abs(out['disparity_left'] - truth)[inner][known] > 1)
    assert ('tilt' in out['info']) == (setting == 'auto')
  assert out['info']['tilt'] == [pytest.approx(-4.0, abs=0.3), 0.0]
  assert bad['auto'] < 0.6 * bad['off'], bad
  assert tilt.turnable('diplopia') and tilt.turnable('gray') and not tilt.turnable('monocular')
