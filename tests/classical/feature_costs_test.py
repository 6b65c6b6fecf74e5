"""Tests of the descriptor cost volumes and the SGM of a signed stored volume."""

import numpy as np
import pytest

from mixstereo_tf.classical import feature_costs
from mixstereo_tf.classical import parallel_sgm


def _unit(rng, shape):
  x = rng.normal(size=shape).astype(np.float32)
  return x / np.linalg.norm(x, axis=-1, keepdims=True)


@pytest.mark.parametrize('threads', [1, 2])
def test_costs_match_the_definition(threads):
  rng = np.random.default_rng(0)
  left, right = _unit(rng, (5, 20, 4)), _unit(rng, (5, 20, 4))
  volume = feature_costs.cosine_costs(left, right, -3, 7, 32.0, outside=200, threads=threads)
  for x in range(20):
    for i in range(7):
      xr = x - (-3 + i)
      if 0 <= xr < 20:
        expected = np.floor((1 - (left[:, x] * right[:, xr]).sum(-1)) * 32 + 0.5)
        np.testing.assert_allclose(volume[:, x, i], expected, atol=1)
      else:
        assert (volume[:, x, i] == 200).all()


def test_identical_descriptors_cost_zero_at_their_disparity():
  rng = np.random.default_rng(1)
  right = _unit(rng, (4, 30, 8))
  left = np.roll(right, -2, axis=1)  # left x = right x + 2: d = -2 (x matches x - d).
  volume = feature_costs.cosine_costs(left, right, -5, 11, 32.0)
  assert (volume[:, :27, -2 + 5] == 0).all()
  assert (volume[:, :27].argmin(-1) == 3).all()


def test_sgm_of_a_signed_volume_finds_the_planted_disparity():
  rng = np.random.default_rng(2)
  h, w, low = 24, 40, -6
  volume = rng.integers(20, 60, size=(h, w, 13)).astype(np.uint8)
  volume[:, :, 4] = 2  # d = low + 4 = -2 everywhere.
  out = parallel_sgm.match_cost_volume(volume, low, 8, 60, 1.0)
  assert np.median(out['disparity_left']) == pytest.approx(-2, abs=0.01)
  inner = out['disparity_left'][:, 8:-8]
  assert (np.abs(inner + 2) < 0.5).mean() > 0.95


def test_bad_arguments_are_refused():
  with pytest.raises(ValueError, match='one shape'):
    feature_costs.cosine_costs(np.zeros((2, 3, 4)), np.zeros((2, 4, 4)), 0, 2, 32.0)
  with pytest.raises(ValueError, match='num_disparities'):
    feature_costs.cosine_costs(np.zeros((2, 3, 4)), np.zeros((2, 3, 4)), 0, 0, 32.0)


def test_the_stored_census_volume_is_the_matchers_cost_bit_for_bit():
  """SGM of `census_volume` = the census matcher's full search in one strip, which never
  stores the volume; a red eye against green and blue, a signed range."""
  from mixstereo_tf.classical import matcher  # pylint: disable=g-import-not-at-top
  rng = np.random.default_rng(3)
  base = rng.uniform(0, 255, (30, 64, 3)).astype(np.float32)
  left, right = base[..., :1], np.roll(base, -3, axis=1)[..., 1:]
  config = matcher.MatcherConfig(strips=1, threads=1)
  expected = matcher.match(left, right, -6, 9, config)
  volume = parallel_sgm.census_volume(left, right, -6, 16, 7, 9, threads=2)
  assert volume.shape == (30, 64, 16)
  got = parallel_sgm.match_cost_volume(volume, -6, config.p1, config.p2, config.lr_threshold)
  for key in ('disparity_left', 'disparity_right', 'consistent_left'):
    np.testing.assert_array_equal(got[key], expected[key])


@pytest.mark.parametrize('weight', [0.5, 0.3, 0.0, 1.0])
@pytest.mark.parametrize('threads', [1, 3])
def test_blend_is_numpys_arithmetic_bit_for_bit(weight, threads):
  rng = np.random.default_rng(7)
  other = rng.integers(0, 256, (9, 11, 6), dtype=np.uint8)
  volume = rng.integers(0, 256, (9, 11, 6), dtype=np.uint8)
  volume[0, 0, :2], other[0, 0, :2] = (3, 4), (4, 3)  # Sums ending in .5: ties to even.
  expected = np.rint(weight * other.astype(np.float32) + (1 - weight) * volume).astype(np.uint8)
  out = feature_costs.blend(other, volume, weight, threads)
  assert out is volume
  np.testing.assert_array_equal(out, expected)


def test_blend_refuses_mismatched_volumes_and_weights():
  volume = np.zeros((2, 3, 4), np.uint8)
  with pytest.raises(ValueError, match='blend'):
    feature_costs.blend(np.zeros((2, 3, 5), np.uint8), volume, 0.5)
  with pytest.raises(ValueError, match='blend'):
    feature_costs.blend(volume.copy(), volume, 1.5)
  with pytest.raises(ValueError, match='blend'):
    feature_costs.blend(volume.astype(np.float32), volume, 0.5)
