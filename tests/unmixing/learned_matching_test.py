"""Tests of the learned matching stage with hand-made descriptors (the stage, not a model):
signed disparities recovered, the reduced-scale route, views restored, a video prior."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.classical import matcher
from mixstereo_tf.core import hints
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import photo_warps
from mixstereo_tf.data import texture_atlas
from mixstereo_tf.unmixing import learned_matching


def _patch_descriptors(single, pair):
  """Unit 5x5 patches of each eye's standardised mean channel: an exact matcher for a
  gray anaglyph, whose eyes both carry luminance."""
  def describe(image):
    x = tf.reduce_mean(image, -1, keepdims=True)
    mean, var = tf.nn.moments(x, axes=[1, 2], keepdims=True)
    x = (x - mean) * tf.math.rsqrt(var + 1e-6)
    patches = tf.image.extract_patches(x, [1, 5, 5, 1], [1, 1, 1, 1], [1, 1, 1, 1], 'SAME')
    patches -= tf.reduce_mean(patches, -1, keepdims=True)
    return tf.math.l2_normalize(patches, -1)
  return describe(single), describe(pair)


@pytest.fixture(scope='module')
def pair():
  config = photo_warps.WarpConfig(height=96, width=160, max_disparity=32,
                                  window_probability=1.0)
  return photo_warps.warped_pair(4, config, texture_atlas.load_textures('heldout'))


def _gray_anaglyph(pair):
  left, right = (tf.constant(pair[k], tf.float32) / 127.5 - 1 for k in ('left', 'right'))
  return (mixtures.mix('gray', left, right).numpy() + 1) / 2


def _bad1(out, pair):
  valid = pair['nonocc_left']
  return (np.abs(out['disparity_left'] - pair['disparity_left']) > 1)[valid].mean()


def test_signed_disparities_are_recovered(pair):
  low, high = np.floor(pair['disparity_left'].min()) - 3, np.ceil(pair['disparity_left'].max()) + 3
  assert low < 0 < high  # Window-aligned: both signs.
  out = learned_matching.match(_patch_descriptors, _gray_anaglyph(pair), 'gray', low, high)
  assert _bad1(out, pair) < 0.12
  assert out['consistent_left'].mean() > 0.7


def test_reduced_scale_route_stays_close(pair):
  low, high = np.floor(pair['disparity_left'].min()) - 3, np.ceil(pair['disparity_left'].max()) + 3
  small = learned_matching.LearnedMatchConfig(max_cells=100_000)  # 96*160*D / 8 < 1e5: f = 2.
  out = learned_matching.match(_patch_descriptors, _gray_anaglyph(pair), 'gray', low, high,
                               small)
  assert out['disparity_left'].shape == (96, 160)
  assert _bad1(out, pair) < 0.25


def test_learned_unmix_restores_views_and_takes_a_video_prior(pair):
  image = np.rint(255 * _gray_anaglyph(pair)).astype(np.uint8)
  search = (int(pair['disparity_left'].min()) - 3, int(pair['disparity_left'].max()) + 3)
  told = []  # A video frame without a prior tells its disparities before its views.
  out = learned_matching.learned_unmix(_patch_descriptors, image, 'gray', search,
                                       hints.FrameHint(on_disparity=told.append))
  assert len(told) == 1 and set(told[0]) == {'disparity_left', 'disparity_right',
                                             'consistent_left'}
  np.testing.assert_array_equal(told[0]['disparity_left'], out['disparity_left'])
  assert out['left'].dtype == np.uint8 and out['left'].shape == (96, 160, 3)
  assert set(out) == {'left', 'right', 'disparity_left', 'disparity_right', 'consistent_left'}
  hint = hints.FrameHint(prior=out['disparity_left'])
  again = learned_matching.learned_unmix(_patch_descriptors, image, 'gray', search, hint)
  assert set(again) == set(out)
  assert np.abs(again['disparity_left'] - out['disparity_left']).mean() < 2.0


@pytest.mark.parametrize('range_width', [320, 80])  # As it is; a copy half as wide.
def test_the_stage_plans_its_range_with_its_own_costs(pair, range_width):
  image = np.rint(255 * _gray_anaglyph(pair)).astype(np.uint8)
  config = matcher.MatcherConfig(range_width=range_width)
  low, high = learned_matching.estimate_range(_patch_descriptors, image, 'gray', config)
  truth = pair['disparity_left'][pair['nonocc_left']]
  # The margin (3 px of the copy) and one bin of the copy, scaled, + 1 px of rounding.
  slack = (3 + 1) * 160 / min(range_width, 160) + 1
  assert truth.min() - slack <= low <= np.percentile(truth, 1), (low, truth.min())
  assert np.percentile(truth, 99) <= high <= truth.max() + slack, (high, truth.max())


def test_bad_config_and_range_are_refused():
  with pytest.raises(ValueError, match='cost_scale'):
    learned_matching.LearnedMatchConfig(cost_scale=0)
  with pytest.raises(ValueError, match='range'):
    learned_matching.match(_patch_descriptors, np.zeros((8, 8, 3), np.float32), 'gray', 9, 12)


def test_the_intersection_with_the_census_plan_is_the_overlap_of_both(pair):
  image = np.rint(255 * _gray_anaglyph(pair)).astype(np.uint8)
  own = learned_matching.estimate_range(_patch_descriptors, image, 'gray')
  census = matcher.estimate_range(image[..., :1].astype(np.float32),
                                  image[..., 1:].astype(np.float32))
  both = learned_matching.estimate_range(
      _patch_descriptors, image, 'gray',
      config=learned_matching.LearnedMatchConfig(intersect_census_range=True))
  overlap = max(own[0], census[0]), min(own[1], census[1])
  assert both == (overlap if overlap[0] < overlap[1] else own), (own, census, both)
