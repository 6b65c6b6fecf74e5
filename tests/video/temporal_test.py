"""Tests for temporal consistency: scene cuts, per-shot decisions, the prior (temporal)."""

import dataclasses

import numpy as np
import pytest

from mixstereo_tf.classical import anaglyph
from mixstereo_tf.classical import matcher
from mixstereo_tf.core import hints
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import synthetic
from mixstereo_tf.data import texture_atlas
from mixstereo_tf.unmixing import detection
from mixstereo_tf.unmixing import eye_order
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.video import motion
from mixstereo_tf.video import temporal
from tests.unmixing import eye_order_test

HEIGHT, WIDTH, PAN = 48, 80, 2


def _anaglyph(left, right, name='anaglyph'):
  mixed = mixtures.mix(name, image_range.u8_to_signed(left), image_range.u8_to_signed(right))
  return image_range.signed_to_u8(mixed.numpy())


def _shot(seed, frames, pan=PAN, noise=0.0, name='anaglyph'):
  """`frames` mixtures (`name`) seen by a camera panning `pan` px per frame over procedural
  scene `seed` (held-out textures), with Gaussian noise of `noise` levels per frame."""
  config = synthetic.SceneConfig(max_disparity=12, height=HEIGHT,
                                 width=WIDTH + pan * (frames - 1))
  scene = synthetic.render_scene(seed, config, texture_atlas.load_textures('heldout'))
  mixture = _anaglyph(scene['left'], scene['right'], name)
  rng = np.random.RandomState(seed)
  shot = []
  for index in range(frames):
    crop = mixture[:, pan * index:pan * index + WIDTH].astype(np.float32)
    crop += rng.normal(0.0, noise, crop.shape) if noise else 0.0
    shot.append(np.clip(np.round(crop), 0, 255).astype(np.uint8))
  return shot


@pytest.fixture(scope='module')
def two_shots():
  """12 frames: 7 of one scene, then a cut to 5 of another."""
  return _shot(3, 7) + _shot(11, 5)


def test_cut_found_exactly_at_the_planted_cut(two_shots):
  assert temporal.find_cuts(two_shots) == [7]
  state = temporal.VideoState()
  for frame in two_shots:
    state.begin(frame)
  assert state.cuts == [7] and state.shot_starts == [0, 7]
  # A forced cut (a segment start) starts a shot without being a scene cut.
  state, started = temporal.VideoState(), []
  for index, frame in enumerate(two_shots):
    state.begin(frame, cut=index == 4)
    started.append(state.started_shot())
  assert state.cuts == [7] and state.shot_starts == [0, 4, 7]
  assert [i for i, s in enumerate(started) if s] == [0, 4, 7]
  alone = temporal.VideoState(temporal.TemporalConfig(enabled=False))
  alone.begin(two_shots[0])
  assert not alone.started_shot()  # Every frame decided alone: no shot to list.


def test_a_cut_between_scenes_of_similar_colours_is_found_by_the_thumbnails():
  """Histogram distance 0.2 (between the soft and the hard threshold) both ways: the
  layout turned from columns to rows is a cut (thumbnail correlation 0), the columns
  moved (a pan) are not; a user's clip cut at 0.28 and was one shot."""
  def split(black_share, rows=False):
    image = np.full((40, 80, 3), 255, np.uint8)
    if rows:
      image[:round(40 * black_share)] = 0
    else:
      image[:, :round(80 * black_share)] = 0
    return image
  columns, turned, panned = split(0.5), split(0.3, rows=True), split(0.3)
  config = temporal.TemporalConfig()
  for other in (turned, panned):
    distance = temporal.histogram_distance(temporal.colour_histograms(columns),
                                           temporal.colour_histograms(other))
    assert distance == pytest.approx(0.2)
  signatures = [temporal.signature(image, config) for image in (columns, turned, panned)]
  assert temporal.is_cut(signatures[0], signatures[1], config)
  assert not temporal.is_cut(signatures[0], signatures[2], config)
  assert temporal.find_cuts([columns, columns, turned, turned]) == [2]
  assert not temporal.is_cut(signatures[0], signatures[1], dataclasses.replace(
      config, soft_cut_threshold=0.3))  # Histograms alone, as before.


def test_histogram_distance_known_answers():
  black = np.zeros((10, 20, 3), np.uint8)
  white = np.full((10, 20, 3), 255, np.uint8)
  half = np.concatenate([black[:, :10], white[:, 10:]], axis=1)
  histograms = {k: temporal.colour_histograms(v) for k, v in
                (('black', black), ('white', white), ('half', half))}
  assert temporal.histogram_distance(histograms['black'], histograms['white']) == 1.0
  assert temporal.histogram_distance(histograms['black'], histograms['half']) == 0.5
  assert temporal.histogram_distance(histograms['half'], histograms['half']) == 0.0
  # Moving the content (a pan, a flip) changes nothing.
  assert temporal.histogram_distance(histograms['half'],
                                     temporal.colour_histograms(half[:, ::-1])) == 0.0


def _counting(monkeypatch, module, name):
  """Replaces module.name by a wrapper counting its calls; returns the call list."""
  calls, original = [], getattr(module, name)

  def wrapper(*args, **kwargs):
    calls.append((args, kwargs))
    return original(*args, **kwargs)
  monkeypatch.setattr(module, name, wrapper)
  return calls


def _run(frames, config=temporal.TemporalConfig(), mixture='anaglyph', search=None):
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture=mixture, disparity_range=search))
  state, outputs = temporal.VideoState(config), []
  for frame in frames:
    hint = state.begin(frame)
    outputs.append(unmixer(frame, hint=hint))
    state.end(outputs[-1])
  return outputs


def test_encoding_and_range_decided_once_per_shot(two_shots, monkeypatch):
  monkeypatch.setattr(detection, 'detect', lambda image: detection.Detection(
      'anaglyph', 0.97, 'stub', {}))
  detected = _counting(monkeypatch, detection, 'detect')
  estimated = _counting(monkeypatch, matcher, 'estimate_range')
  outputs = _run(two_shots, mixture='auto')
  assert len(detected) == 2 and len(estimated) == 2
  assert [o['info']['mixture'] for o in outputs] == ['anaglyph'] * 12
  assert all(o['info']['detected'] == 'anaglyph' for o in outputs)
  ranges = [tuple(o['info']['disparity_range']) for o in outputs]
  assert len(set(ranges[:7])) == 1 and len(set(ranges[7:])) == 1
  # Without temporal consistency every frame is detected and estimated alone.
  del detected[:], estimated[:]
  _run(two_shots, temporal.TemporalConfig(enabled=False), mixture='auto')
  assert len(detected) == 12 and len(estimated) == 12


def test_prior_is_the_previous_disparity_and_none_after_a_cut(two_shots, monkeypatch):
  calls = _counting(monkeypatch, anaglyph, 'unmix_anaglyph')
  outputs = _run(two_shots, search=(0, 12))
  priors = [kwargs['prior'] for _, kwargs in calls]
  assert priors[0] is None and priors[7] is None
  for index in list(range(1, 7)) + list(range(8, 12)):
    previous = outputs[index - 1]
    # NaN (search everything) where the previous match failed the left-right check, and
    # moved with the camera's pan (the frame shows at x what the previous one did at x + 2).
    np.testing.assert_array_equal(priors[index], motion.shift_map(np.where(
        previous['consistent_left'], previous['disparity_left'], np.nan), -PAN, 0))
  assert any(np.isnan(prior).any() for prior in priors[1:7])
  assert [o['info']['prior'] for o in outputs] == [i not in (0, 7) for i in range(12)]
  # A shot's first frame (only) gets the coarse-to-fine threshold of its full search.
  cells = [kwargs['config'].matching.full_search_cells for _, kwargs in calls]
  first = temporal.TemporalConfig().first_frame_cells
  own = matcher.MatcherConfig().full_search_cells
  assert cells == [first if i in (0, 7) else own for i in range(12)]
  # use_prior off: the shot's decisions stay, no prior is passed.
  del calls[:]
  _run(two_shots, temporal.TemporalConfig(use_prior=False), search=(0, 12))
  assert all(kwargs['prior'] is None for _, kwargs in calls)


def test_a_frame_without_a_consistency_mask_hands_on_its_whole_disparity():
  state = temporal.VideoState()
  frame = np.zeros((8, 8, 3), np.uint8)
  state.begin(frame)
  disparity = np.arange(64, dtype=np.float32).reshape(8, 8)
  state.end({'disparity_left': disparity})
  np.testing.assert_array_equal(state.begin(frame).prior, disparity)
  consistent = disparity % 3 > 0
  state.end({'disparity_left': disparity, 'consistent_left': consistent})
  prior = state.begin(frame).prior
  np.testing.assert_array_equal(np.isnan(prior), ~consistent)
  np.testing.assert_array_equal(prior[consistent], disparity[consistent])


def test_a_double_image_weight_is_estimated_once_per_shot():
  """The first frame's mixing weight (info) is the rest of the shot's; a cut forgets it."""
  state = temporal.VideoState()
  frame = np.zeros((8, 8, 3), np.uint8)
  assert state.begin(frame).mixing_weight is None
  state.end({'info': {'mixture': 'diplopia', 'mixing_weight': 0.37}})
  assert state.begin(frame).mixing_weight == 0.37
  state.end({'info': {'mixture': 'diplopia', 'mixing_weight': 0.6}})  # Not a shot start.
  assert state.begin(frame).mixing_weight == 0.37
  assert state.begin(frame, cut=True).mixing_weight is None


def test_a_halftone_screen_and_a_tilt_are_found_once_per_shot():
  """The first frame's screen (info 'screen_period') and turn (info 'tilt'), 'off' where
  none was found, are the rest of the shot's settings; a cut finds them anew."""
  state = temporal.VideoState()
  frame = np.zeros((8, 8, 3), np.uint8)
  assert state.begin(frame).descreen is None
  state.end({'info': {'mixture': 'anaglyph', 'screen_period': 4.5}})
  assert state.begin(frame).descreen == 4.5
  assert state.begin(frame, cut=True).descreen is None
  state.end({'info': {'mixture': 'anaglyph'}})
  assert state.begin(frame).descreen == 'off' and state.begin(frame).rectify == 'off'
  state.begin(frame, cut=True)
  state.end({'info': {'mixture': 'anaglyph', 'tilt': [-2.5, 0.25]}})
  assert state.begin(frame).rectify == (-2.5, 0.25)


def test_prior_lowers_flicker_on_a_static_noisy_clip():
  frames = _shot(5, 8, pan=0, noise=3.0)
  flicker = {}
  for use_prior in (False, True):
    disparities = [o['disparity_left'] for o in _run(
        frames, temporal.TemporalConfig(use_prior=use_prior), search=(0, 12))]
    flicker[use_prior] = float(np.mean(np.abs(np.diff(disparities, axis=0))))
  assert flicker[True] < 0.7 * flicker[False], flicker


def test_eye_order_decided_once_per_shot_and_the_prior_mirrored(monkeypatch):
  left, right, disparity = eye_order_test._pair()  # pylint: disable=protected-access
  frames = [_anaglyph(right, left)] * 3  # Cyan-red: the eyes swapped.
  detected = _counting(monkeypatch, eye_order, 'detect')
  matched = _counting(monkeypatch, anaglyph, 'unmix_anaglyph')
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='anaglyph', swap_eyes='auto'))
  state, outputs = temporal.VideoState(), []
  for frame in frames:
    outputs.append(unmixer(frame, hint=state.begin(frame)))
    state.end(outputs[-1])
  assert len(detected) == 1
  assert [o['info']['eye_order'] for o in outputs] == ['swapped'] * 3
  assert all(o['info']['eye_order_score'] < -2 for o in outputs)
  # Later frames search around the previous left disparity made the mirrored run's left one.
  prior = matched[1][1]['prior']
  np.testing.assert_array_equal(prior, eye_order.right_from_left(np.where(
      outputs[0]['consistent_left'], outputs[0]['disparity_left'], np.nan))[:, ::-1])
  for out in outputs:
    assert np.mean(np.abs(out['disparity_left'] - disparity) > 1) < 0.05


def test_an_encoding_that_also_fits_a_larger_one_settles_on_the_first_frame_showing_it():
  """A shot whose first frame reads half-colour (also fitting the colour anaglyph) is read
  as half-colour, its frames detected again, until a frame's colours need the colour
  anaglyph: from then on the shot is read as that, and detected no more; a cut forgets."""
  frame = np.zeros((8, 8, 3), np.uint8)
  state = temporal.VideoState()  # Detected again on every 4th frame of the shot:
  state.begin(frame)
  state.end({'info': {'mixture': 'half_color', 'also_fits': 'anaglyph'}})
  may_be = []
  for _ in range(8):
    may_be.append(state.begin(frame).may_be)
    state.end({'info': {'mixture': 'half_color'}})
  assert may_be == [None, None, None, 'anaglyph'] * 2
  state = temporal.VideoState(temporal.TemporalConfig(settle_every=1))  # on every frame:
  state.begin(frame)
  state.end({'info': {'mixture': 'half_color', 'detected': 'half_color', 'confidence': 0.8,
                      'also_fits': 'anaglyph'}})
  hint = state.begin(frame)
  assert (hint.mixture, hint.may_be) == ('half_color', 'anaglyph')
  state.end({'info': {'mixture': 'half_color'}})  # Still fits both.
  assert state.begin(frame).may_be == 'anaglyph'
  state.end({'info': {'mixture': 'anaglyph', 'detected': 'anaglyph', 'confidence': 0.5}})
  hint = state.begin(frame)
  assert (hint.mixture, hint.may_be) == ('anaglyph', None)
  assert hint.detection == {'detected': 'anaglyph', 'confidence': 0.5}
  state.end({'info': {'mixture': 'anaglyph'}})
  assert state.begin(frame, cut=True).mixture is None


@pytest.mark.parametrize('found,read', [('anaglyph', 'anaglyph'), ('half_color', 'half_color'),
                                        (None, 'half_color')])
def test_a_frame_of_an_unsettled_shot_is_read_as_the_larger_encoding_only_when_detected(
    found, read, monkeypatch):
  left, right, _ = eye_order_test._pair()  # pylint: disable=protected-access
  image = _anaglyph(left, right)
  monkeypatch.setattr(detection, 'detect', lambda image: detection.Detection(
      found, 0.7, 'test', {}, 'anaglyph' if found == 'half_color' else None))
  unmixer = predictors.build_unmixer(predictors.PredictorConfig('classical', mixture='auto'))
  hint = hints.FrameHint(mixture='half_color', may_be='anaglyph',
                         detection={'detected': 'half_color'}, disparity_range=(0, 12),
                         swap_eyes=False)
  info = unmixer(image, hint=hint)['info']
  assert info['mixture'] == read
  assert info['detected'] == (found if read == 'anaglyph' else 'half_color')


def test_a_frame_read_as_the_videos_encoding_does_not_decide_its_shot(two_shots):
  """The dark frames of a fade are read as the video's encoding ('undecided'); the shot is
  decided by its first frame whose encoding was found."""
  state = temporal.VideoState(fallback_mixture='half_color')
  state.begin(two_shots[0])
  state.end({'info': {'mixture': 'half_color', 'detected': None, 'undecided': True,
                      'disparity_range': [0, 5]}})
  assert state.begin(two_shots[1]).mixture is None  # Still to decide: detected anew.
  state.end({'info': {'mixture': 'anaglyph', 'detected': 'anaglyph',
                      'disparity_range': [0, 9]}})
  hint = state.begin(two_shots[2])
  assert (hint.mixture, hint.disparity_range) == ('anaglyph', (0, 9))
