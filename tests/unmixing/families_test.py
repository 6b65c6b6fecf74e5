"""Tests for mixstereo_tf.unmixing.families: the registry and each family's strategy."""

import numpy as np
import pytest
import skimage.data

from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import matcher
from mixstereo_tf.core import hints
from mixstereo_tf.core import mixtures
from mixstereo_tf.unmixing import families
from tests.classical import classical_test

_H, _W = classical_test._H, classical_test._W  # pylint: disable=protected-access
_scene, _mix = classical_test._scene, classical_test._mix  # pylint: disable=protected-access


def test_every_mixture_has_its_family():
  for name in mixtures.ANAGLYPH_NAMES:
    assert isinstance(families.of(name), families.Anaglyph)
  assert isinstance(families.of('diplopia'), families.Diplopia)
  assert isinstance(families.of('monocular'), families.Monocular)
  assert families.of('gray') is families.of('amber_blue_dubois')  # One strategy object.
  assert families.detected() is families.of('anaglyph')
  assert families.classical_names() == mixtures.ANAGLYPH_NAMES + ('diplopia',)
  with pytest.raises(ValueError, match="'nonsense'; valid mixtures are: anaglyph"):
    families.of('nonsense')


def test_what_each_family_says():
  anaglyph, double, single = (families.of(n) for n in ('anaglyph', 'diplopia', 'monocular'))
  assert (anaglyph.detectable, anaglyph.signed, anaglyph.restores_views) == (True,) * 3
  for family in (double, single):
    assert (family.detectable, family.signed, family.restores_views) == (False,) * 3
  assert (anaglyph.has_classical, double.has_classical, single.has_classical) == (
      True, True, False)
  assert anaglyph.learned_stages == ('refiner', 'features')
  assert double.learned_stages == ('refiner', 'echo_features')
  assert single.learned_stages == () and single.input_is_left
  # The network plan shifts the right eye's channels of anaglyphs only.
  assert anaglyph.right_eye('anaglyph') == (1, 2)
  assert anaglyph.right_eye('green_magenta') == (0, 2)
  assert anaglyph.right_eye('amber_blue') == (2,)
  assert double.right_eye('diplopia') == single.right_eye('monocular') == ()
  # The classical method's own ranges: diplopia has no zero shift.
  largest = diplopia.DiplopiaConfig().matching.max_disparity
  assert (anaglyph.display_range(), anaglyph.classical_range()) == (128, (0, 127))
  assert (double.display_range(), double.classical_range()) == (largest, (1, largest))
  assert single.classical_range() == (0, 127)
  assert families.input_is_left('monocular')
  assert not families.input_is_left('anaglyphs')
  assert not families.input_is_left('monocular,anaglyph')


def test_range_planning_on_tiny_images():
  left, right, _, _ = _scene(d_bg=3, d_fg=8)
  low, high = families.of('anaglyph').estimate_range(_mix('anaglyph', left, right),
                                                     'anaglyph', (0, 127))
  assert low <= 3 and high >= 8 and high - low < 40, (low, high)
  left, right, _, _ = _scene(d_bg=5, d_fg=5)
  low, high = families.of('diplopia').estimate_range(_mix('diplopia', left, right),
                                                     'diplopia', (1, 64))
  assert 1 <= low <= 5 <= high, (low, high)
  image = np.zeros((_H, _W, 3), np.uint8)
  assert families.of('monocular').estimate_range(image, 'monocular', (0, 9)) == (0, 9)


def test_the_hint_reaches_the_matcher(monkeypatch):
  left, right, _, _ = _scene(2, 6)
  image = _mix('anaglyph', left, right)
  family = families.of('anaglyph')
  assert family.matching() == family.matching(hints.FrameHint()) == matcher.MatcherConfig()
  # A prior window without a prior changes nothing.
  assert family.matching(hints.FrameHint(prior_window=(1, 2))) == matcher.MatcherConfig()
  calls = {}
  for name in ('match', 'estimate_range'):
    original = getattr(matcher, name)

    def spy(*args, _name=name, _original=original):
      calls.setdefault(_name, []).append(args)
      return _original(*args)
    monkeypatch.setattr(matcher, name, spy)
  hint = hints.FrameHint(prior=np.full((_H, _W), 4.0, np.float32), prior_window=(1, 2),
                         full_search_cells=1000, matcher_strips=1)
  family.classical(image, 'anaglyph', (0, 10), hint)
  config = calls['match'][0][4]
  assert (config.full_search_cells, config.prior_radius, config.prior_spread,
          config.strips) == (1000, 1, 2, 1)
  np.testing.assert_array_equal(calls['match'][0][5], hint.prior)
  family.estimate_range(image, 'anaglyph', (0, 127), hints.FrameHint(matcher_strips=1))
  assert calls['estimate_range'][0][2].strips == 1
  family.classical(image, 'anaglyph', (0, 10))
  assert calls['match'][1][4] == matcher.MatcherConfig() and calls['match'][1][5] is None


def test_what_a_family_cannot_do_is_refused():
  image = np.zeros((8, 16, 3), np.uint8)
  with pytest.raises(ValueError, match="'monocular': a single view"):
    families.of('monocular').classical(image, 'monocular')
  with pytest.raises(ValueError, match="'diplopia' has no view restoration"):
    families.of('diplopia').restore(image / 255.0, 'diplopia', *np.zeros((2, 8, 16)))


def test_a_new_family_is_one_class_and_its_registration(monkeypatch):
  registry = families._REGISTRY  # pylint: disable=protected-access
  monkeypatch.setattr(families, '_REGISTRY', {
      name: family for name, family in registry.items() if name != 'monocular'})

  class Stills(families.Family):
    names = ('monocular',)
    input_is_left = True

    def estimate_range(self, image, name, default, hint=None):
      return 0, image.shape[1] // 4

  stills = families.register(Stills())
  assert families.of('monocular') is stills
  assert stills.estimate_range(np.zeros((8, 40, 3)), 'monocular', (0, 1)) == (0, 10)
  assert families.classical_names() == mixtures.ANAGLYPH_NAMES + ('diplopia',)
  with pytest.raises(ValueError, match="'monocular' belongs to Stills already"):
    families.register(Stills())
  with pytest.raises(ValueError, match="'hologram'"):
    families.register(type('Holograms', (families.Family,), {'names': ('hologram',)})())


def test_double_images_take_a_frames_prior_and_its_window(monkeypatch):
  seen = {}
  monkeypatch.setattr(diplopia, 'unmix_diplopia',
                      lambda image, search, **kwargs: seen.update(kwargs) or {})
  prior = np.full((4, 6), 3.0, np.float32)
  double = families.of('diplopia')
  double.classical(np.zeros((4, 6, 3), np.uint8), 'diplopia', (1, 9),
                   hints.FrameHint(prior=prior, prior_window=(2, 3), mixing_weight=0.4))
  assert seen['prior'] is prior and seen['prior_window'] == (2, 3)
  assert seen['weight'] == 0.4
  double.classical(np.zeros((4, 6, 3), np.uint8), 'diplopia', (1, 9))
  assert seen['prior'] is None and seen['weight'] is None  # A still image: no prior.


@pytest.mark.parametrize('dtype', [np.uint8, np.uint16])
def test_an_anaglyphs_refined_views_are_restored_from_its_channels(dtype):
  """`Anaglyph.settle_views`: the views at the mixture's depth, each copying the channels
  the anaglyph holds of it (the left red, the right green and blue) exactly, the rest
  near the truth at the true disparities; with its left-right check for a video's prior.
  A family that settles nothing keeps a refiner's views as they are."""
  texture = skimage.data.astronaut()[60:108:2, 150:294:2]  # Natural colours: the
  left, right = texture[:, 2:66], texture[:, 6:70]  # transfer's local colour statistics.
  scale = 257 if dtype == np.uint16 else 1
  mixture = np.dstack([left[..., 0], right[..., 1], right[..., 2]]).astype(dtype) * scale
  refined = {'left': left, 'right': right, 'disparity_left': np.full((24, 64), 4.0),
             'disparity_right': np.full((24, 64), 4.0)}
  out = families.of('anaglyph').settle_views(mixture, 'anaglyph', refined, {})
  assert out['left'].dtype == dtype and out['right'].dtype == dtype
  np.testing.assert_array_equal(out['left'][..., 0], mixture[..., 0])
  np.testing.assert_array_equal(out['right'][..., 1:], mixture[..., 1:])
  inner = np.s_[:, 8:-8]
  for key, view in (('left', left), ('right', right)):
    error = np.abs(out[key][inner].astype(float) / scale - view[inner])
    assert np.median(error) <= 4.0, (key, np.median(error))  # Left x: right x - 4.
  assert out['consistent_left'][inner].mean() > 0.9
  kept = families.Family().settle_views(mixture, 'anaglyph', refined, {})
  assert kept.keys() == {'left', 'right'} and kept['left'] is left
