"""Tests of unmixing.steps: ranges, the encoding's use (a mixing weight, signed disparities)
and bad input."""

from absl import logging
import numpy as np
import pytest

from mixstereo_tf.classical import diplopia_weight
from mixstereo_tf.core import image_range
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


def _deep(image):
  """A 16-bit copy of a uint8 image whose samples are not multiples of 257: 8-bit storage
  could not hold them."""
  fine = np.random.default_rng(5).integers(-128, 128, image.shape)
  return np.clip(image.astype(np.int64) * 257 + fine, 0, 65535).astype(np.uint16)


@pytest.mark.parametrize('config', [
    dict(method='classical'), dict(method='sgbm'), dict(method='model'),
    dict(method='model', pretrained='anaglyph'), dict(method='classical', swap_eyes=True)])
def test_a_16_bit_anaglyph_is_matched_at_8_bits_and_its_views_restored_at_16(config):
  """Disparities as those of its 8-bit copy; the channels each view copies are the input's
  own 16-bit samples (the left view's red, the right view's green and blue)."""
  deep = _deep(_anaglyph()[0])  # Swapped eyes: unmixed mirrored, the views swapped back.
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      mixture='anaglyph', disparity_range=(0, 20), **config))
  ours, eight = unmixer(deep), unmixer(image_range.eight_bits(deep))
  np.testing.assert_array_equal(ours['disparity_left'], eight['disparity_left'])
  assert ours['left'].dtype == ours['right'].dtype == np.uint16
  assert eight['left'].dtype == np.uint8
  for key in ('left', 'right'):
    assert np.abs(image_range.eight_bits(ours[key]).astype(int) - eight[key]).max() <= 1
  if not config.get('swap_eyes'):
    np.testing.assert_array_equal(ours['left'][..., 0], deep[..., 0])
    np.testing.assert_array_equal(ours['right'][..., 1:], deep[..., 1:])


@pytest.mark.parametrize('config', [
    dict(method='classical'), dict(method='model'),
    dict(method='model', pretrained='diplopia_echo')])
def test_a_16_bit_double_image_is_matched_at_8_bits_and_its_layers_solved_at_16(config):
  """Views uint16, within four 8-bit levels of the 8-bit copy's (their layers come from the
  16-bit samples; a right view is twice the mixture less the left, which doubles the
  differences: 3 at most measured); disparities the 8-bit copy's, but for the default
  refiner's, which sees its base's 16-bit layers through their 8-bit copy (measured:
  below 0.1 px everywhere, 0.07 at most here; on a textured ramp 0.004 px on average)."""
  deep = _deep(_anaglyph('diplopia')[0])
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      mixture='diplopia', disparity_range=(1, 20), **config))
  ours, eight = unmixer(deep), unmixer(image_range.eight_bits(deep))
  assert ours['left'].dtype == ours['right'].dtype == np.uint16
  assert eight['left'].dtype == np.uint8
  exact = config.get('pretrained') or config['method'] == 'classical'
  np.testing.assert_allclose(ours['disparity_left'], eight['disparity_left'],
                             atol=0 if exact else 0.1)
  for key in ('left', 'right'):
    difference = np.abs(image_range.eight_bits(ours[key]).astype(int) - eight[key])
    assert difference.max() <= 4 and difference.mean() < 0.5, (key, difference.max())


def test_a_16_bit_double_image_keeps_its_samples_where_any_disparity_fits():
  """Known answer: a vertical 16-bit gradient (each row constant, so every disparity
  explains it and both layers are the image itself). The views hold its 16-bit samples
  exactly; the 8-bit copy's views are off by up to 110 of those levels (measured)."""
  ramp = np.repeat(np.linspace(0.2, 0.8, 64)[:, None, None], 96, 1).repeat(3, 2)
  deep = np.rint(ramp * 65535).astype(np.uint16)
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='diplopia', disparity_range=(1, 12)))
  ours, eight = unmixer(deep), unmixer(image_range.eight_bits(deep))
  for key in ('left', 'right'):
    np.testing.assert_array_equal(ours[key], deep)
    assert np.abs(eight[key].astype(int) * 257 - deep).max() > 100


def test_an_auto_weight_that_found_no_echo_says_it_used_one_half():
  """`--mixing_weight=auto` on a double image without isolated edges (a smooth gradient)
  falls back to 1/2; the info says so (`diplopia_weight.NO_ECHO`), a named weight not."""
  y, x = np.mgrid[:48, :96]
  smooth = np.dstack([40 + x, 60 + y, np.full((48, 96), 90)]).astype(np.uint8)
  for weight, note in (('auto', diplopia_weight.NO_ECHO), (0.3, None)):
    info = predictors.build_unmixer(predictors.PredictorConfig(
        'classical', mixture='diplopia', mixing_weight=weight,
        disparity_range=(1, 8)))(smooth)['info']
    assert info['mixing_weight'] == (0.5 if note else 0.3)
    assert info.get('mixing_weight_note') == note
