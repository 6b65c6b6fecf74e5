"""Tests of the signed disparity range logic around a network with D levels."""

import numpy as np
import pytest

from mixstereo_tf.unmixing import disparity_range


def test_parse():
  assert disparity_range.parse('auto') is None
  assert disparity_range.parse(' Network ') == disparity_range.NETWORK
  assert disparity_range.parse(' AUTO ') is None
  assert disparity_range.parse('-40,120') == (-40, 120)
  # Fractional bounds widen to cover the range asked (rounding cut 10.5 off).
  assert disparity_range.parse('0.5,10.5') == (0, 11)
  assert disparity_range.parse('-2.5,-0.2') == (-3, 0)
  for bad in ('5,5', '10,2', 'a,b', '1,2,3', '7', 'nan,4', '0,inf'):
    with pytest.raises(ValueError, match='disparity range'):
      disparity_range.parse(bad)


def test_plan_shifts_negative_ranges_and_scales_wide_ones():
  assert disparity_range.plan((0, 50), 96, 100, 200) == disparity_range.Plan(0, 1.0)
  shifted = disparity_range.plan((-30, 40), 96, 100, 200)
  assert shifted.shift == 30 and shifted.scale == 1.0
  # The network's own range [0, D - 1] is fed at full size; one pixel more is reduced.
  assert disparity_range.plan((0, 95), 96, 100, 200).scale == 1.0
  assert disparity_range.plan((0, 96), 96, 100, 200).scale == pytest.approx(96 / (0.9 * 95))
  # 300 px of range into 96 levels with a 10 % margin: (280 + 20) / (0.9 * 95).
  wide = disparity_range.plan((-20, 280), 96, 3000, 4000)
  assert wide.shift == 20 and wide.scale == pytest.approx(300 / (0.9 * 95))
  budget = disparity_range.plan((0, 10), 96, 3000, 4000, max_pixels=1_000_000)
  assert budget.scale == pytest.approx(np.sqrt(12.0))
  with pytest.raises(ValueError, match='negative disparities'):
    disparity_range.plan((-5, 10), 96, 10, 10, can_shift=False)


def test_to_and_from_network_round_trip_a_known_shift():
  rng = np.random.default_rng(0)
  mixture = rng.integers(0, 256, (6, 20, 3), dtype=np.uint8)
  p = disparity_range.Plan(shift=3, scale=1.0)
  net = disparity_range.to_network(mixture, (1, 2), p)
  np.testing.assert_array_equal(net[..., 0], mixture[..., 0])  # Left eye untouched.
  np.testing.assert_array_equal(net[:, :-3, 1:], mixture[:, 3:, 1:])  # Right eye at x + 3.
  # A network answering d' = 5 everywhere means d = 2 in the input's pixels.
  outputs = {'left': net, 'right': net, 'disparity_left': np.full((6, 20), 5.0, np.float32),
             'disparity_right': np.full((6, 20), 5.0, np.float32)}
  back = disparity_range.from_network(outputs, p, 6, 20)
  np.testing.assert_allclose(back['disparity_left'], 2.0)
  np.testing.assert_allclose(back['disparity_right'], 2.0)
  np.testing.assert_array_equal(back['right'][:, 3:, 1:], mixture[:, 3:, 1:])


def test_from_network_rescales_disparities_with_the_width():
  p = disparity_range.Plan(shift=0, scale=2.0)
  mixture = np.zeros((40, 60, 3), np.uint8)
  net = disparity_range.to_network(mixture, (1, 2), p)
  assert net.shape == (20, 30, 3)
  outputs = {'left': net, 'right': net, 'disparity_left': np.full((20, 30), 4.0, np.float32),
             'disparity_right': np.full((20, 30), 4.0, np.float32)}
  back = disparity_range.from_network(outputs, p, 40, 60)
  assert back['left'].shape == (40, 60, 3)
  np.testing.assert_allclose(back['disparity_left'], 8.0)
