"""The numba census-SGM matcher: equal to sgm.match, signed ranges, priors, coarse-to-fine."""

import cv2
import numpy as np
import pytest

from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import diplopia_costs
from mixstereo_tf.classical import matcher
from mixstereo_tf.classical import parallel_sgm
from mixstereo_tf.classical import sgm

_H, _W = 48, 96


def _texture(rng, height, width):
  """Smooth random colour texture in [0, 255], channels correlated like natural images."""
  def blur():
    noise = cv2.GaussianBlur(rng.normal(size=(height, width)).astype(np.float32), (0, 0), 1.2)
    return noise / noise.std()

  base = blur()
  return np.clip(127.5 + 40.0 * np.stack([0.8 * base + 0.4 * blur() for _ in range(3)], -1),
                 0, 255)


def _layered(d_bg, d_fg, height=_H, width=_W, seed=0):
  """A background plane at d_bg behind a rectangle at d_fg (signed integer disparities).

  Returns the anaglyph channels (left R [H, W, 1], right G and B [H, W, 2], float32), the
  true left disparity and the left pixels visible in the right view.
  """
  rng = np.random.default_rng(seed)
  margin = abs(d_bg) + 1
  background = _texture(rng, height, width + 2 * margin)
  foreground = _texture(rng, height, width)
  y0, y1, x0, x1 = height // 4, 3 * height // 4, width // 3, 2 * width // 3
  left = background[:, margin:margin + width].copy()
  right = background[:, margin + d_bg:margin + d_bg + width].copy()
  left[y0:y1, x0:x1] = foreground[y0:y1, x0:x1]
  right[y0:y1, x0 - d_fg:x1 - d_fg] = foreground[y0:y1, x0:x1]
  d_left = np.full((height, width), d_bg, np.float32)
  d_left[y0:y1, x0:x1] = d_fg
  d_right = np.full((height, width), d_bg, np.float32)
  d_right[y0:y1, x0 - d_fg:x1 - d_fg] = d_fg
  match = np.arange(width)[None, :] - d_left.astype(np.int64)
  inside = (match >= 0) & (match < width)
  visible = inside & (np.take_along_axis(d_right, np.clip(match, 0, width - 1), 1) == d_left)
  return (np.float32(left[..., :1]), np.float32(right[..., 1:]), d_left,
          visible & (np.arange(width) >= 4) & (np.arange(width) < width - 4))


def _bad1(disparity, truth, mask):
  return float(np.mean(np.abs(disparity - truth)[mask] > 1.0))


def test_one_strip_equals_sgm_match_bit_for_bit():
  left, right, _, _ = _layered(2, 9, height=40, width=64)
  ours = matcher.match(left, right, 0, 14, matcher.MatcherConfig(strips=1, threads=1))
  theirs = sgm.match(left, right, sgm.SgmConfig(min_disparity=0, max_disparity=14))
  for key in theirs:
    np.testing.assert_array_equal(ours[key], theirs[key], err_msg=key)


@pytest.mark.parametrize('seed', [0, 1])
def test_a_stored_volume_through_the_numba_sgm_equals_sgm_match_volume(seed):
  """The diplopia self-matching volume of a double image, and costs up to 255 with ties
  (random), give the NumPy SGM's outputs bit for bit."""
  rng = np.random.default_rng(seed)
  left, right, _, _ = _layered(3, 8, height=40, width=64, seed=seed)
  gray = (left[..., 0] + right.mean(-1)) / 2
  config = diplopia.DiplopiaConfig(matching=sgm.SgmConfig(min_disparity=1, max_disparity=20,
                                                          p1=8, p2=64))
  volumes = [diplopia_costs.self_matching_volume(gray, config),
             rng.integers(0, 256, (24, 40, 9)).astype(np.uint8) // 16 * 16]
  for volume, low in zip(volumes, (1, 3)):
    settings = sgm.SgmConfig(min_disparity=low, max_disparity=low + volume.shape[2] - 1,
                             p1=8, p2=64)
    ours = parallel_sgm.match_volume(volume, settings)
    theirs = sgm.match_volume(volume, settings)
    for key in theirs:
      np.testing.assert_array_equal(ours[key], theirs[key], err_msg=key)


def test_strips_and_threads_change_almost_nothing():
  left, right, _, _ = _layered(2, 9)
  one = matcher.match(left, right, 0, 14, matcher.MatcherConfig(strips=1))
  three = matcher.match(left, right, 0, 14, matcher.MatcherConfig(strips=3, strip_overlap=8))
  serial = matcher.match(left, right, 0, 14,
                         matcher.MatcherConfig(strips=3, strip_overlap=8, threads=1))
  np.testing.assert_array_equal(three['disparity_left'], serial['disparity_left'])
  # 16-row strips with 8 rows of overlap: paths from beyond the overlap move sub-pixel
  # offsets a little (with 32 rows, the default, nothing changes here).
  assert np.mean(np.abs(one['disparity_left'] - three['disparity_left']) < 0.25) > 0.98


def test_strip_bounds_balance_cells_and_respect_the_budget():
  widths = np.full((16, 4), 3, np.int32)  # 192 cells, 384 bytes.
  np.testing.assert_array_equal(parallel_sgm.strip_bounds(widths, 2, 0, 10**6), [0, 8, 16])
  np.testing.assert_array_equal(parallel_sgm.strip_bounds(widths, 1, 0, 96),
                                [0, 4, 8, 12, 16])
  np.testing.assert_array_equal(parallel_sgm.strip_bounds(widths, 2, 1, 96), [0, 16])
  widths[0] = 45  # Row 0 holds 180 of the 360 cells.
  np.testing.assert_array_equal(parallel_sgm.strip_bounds(widths, 2, 0, 10**6), [0, 1, 16])


def test_constant_negative_disparity_is_recovered_exactly():
  rng = np.random.default_rng(3)
  texture = cv2.GaussianBlur(rng.uniform(0, 255, (_H, _W + 5)).astype(np.float32), (0, 0),
                             0.7)
  left = texture[:, 5:, None]  # The left pixel x matches the right pixel x + 5: d = -5.
  # Two right channels, monotonic in the left's intensity (census sees them as equal).
  right = np.stack([0.5 * texture[:, :_W] + 40, 12 * np.sqrt(texture[:, :_W])], -1)
  out = matcher.match(left, right, -12, 4)
  d_left, d_right = out['disparity_left'], out['disparity_right']
  # Where the match is inside the other view the winner is -5 (the parabola adds less
  # than 0.5 px) and passes the left-right check. (In the 5 columns of each view without
  # a match, -4 can pass the 1 px check.)
  inside = np.arange(_W) < _W - 5
  assert np.all(np.abs(d_left[:, inside] + 5.0) < 0.5)
  assert np.all(np.abs(d_right[:, 5:] + 5.0) < 0.5)
  assert np.all(out['consistent_left'][:, inside]) and np.all(out['consistent_right'][:, 5:])


def test_signed_layers_at_least_as_good_as_sgm_on_the_shifted_pair():
  left, right, truth, visible = _layered(-5, 6)
  ours = matcher.match(left, right, -10, 10)
  # sgm.match takes d >= 0: the right view moved 10 px left (edge padding) adds 10 px.
  shifted = np.pad(right, ((0, 0), (0, 10), (0, 0)), mode='edge')[:, 10:]
  theirs = sgm.match(left, shifted, sgm.SgmConfig(min_disparity=0, max_disparity=20))
  bad_ours = _bad1(ours['disparity_left'], truth, visible)
  bad_theirs = _bad1(theirs['disparity_left'] - 10.0, truth, visible)
  assert bad_theirs < 0.15 and bad_ours <= bad_theirs + 0.005, (bad_ours, bad_theirs)


def test_a_right_prior_keeps_the_result():
  left, right, truth, visible = _layered(-4, 7, seed=1)
  full = matcher.match(left, right, -16, 16)
  # A previous frame: the scene moved by 1 px, the prior is one column stale.
  prior = np.roll(full['disparity_left'], 1, axis=1)
  banded = matcher.match(left, right, -16, 16, prior=prior)
  change = np.abs(banded['disparity_left'] - full['disparity_left'])[visible]
  assert np.mean(change < 0.5) > 0.97
  assert (_bad1(banded['disparity_left'], truth, visible) <=
          _bad1(full['disparity_left'], truth, visible) + 0.01)
  with pytest.raises(ValueError, match='prior'):
    matcher.match(left, right, -16, 16, prior=prior[:, 1:])


def test_coarse_to_fine_above_the_cell_threshold_stays_close_to_the_full_search():
  left, right, truth, visible = _layered(-6, 10, height=64, width=128, seed=2)
  config = matcher.MatcherConfig(full_search_cells=64 * 128 * 33 // 8)
  assert matcher.coarse_factor(64, 128, -16, 16, matcher.MatcherConfig()) == 1
  assert matcher.coarse_factor(64, 128, -16, 16, config) == 2
  full = matcher.match(left, right, -16, 16)
  coarse = matcher.match(left, right, -16, 16, config)
  assert not np.array_equal(coarse['disparity_left'], full['disparity_left'])
  change = np.abs(coarse['disparity_left'] - full['disparity_left'])[visible]
  assert np.mean(change <= 1.0) > 0.95
  # The reduced level is only 32x64 here: a few more edge pixels go wrong than at full size.
  assert (_bad1(coarse['disparity_left'], truth, visible) <=
          _bad1(full['disparity_left'], truth, visible) + 0.03)


@pytest.mark.parametrize('d_bg, d_fg, width, range_width', [
    (-6, 9, _W, 320),  # Searched as it is (+-32 px).
    (12, -10, 256, 64),  # Searched at 1/4 width (+-21 px of the copy).
])
def test_estimate_range_brackets_the_true_range(d_bg, d_fg, width, range_width):
  left, right, _, _ = _layered(d_bg, d_fg, height=_H if width == _W else 96, width=width)
  config = matcher.MatcherConfig(range_width=range_width)
  low, high = matcher.estimate_range(left, right, config)
  assert isinstance(low, int) and isinstance(high, int)
  true_low, true_high = min(d_bg, d_fg), max(d_bg, d_fg)
  slack = 4 * (width / range_width if width > range_width else 1) + 1
  assert true_low - slack <= low <= true_low and true_high <= high <= true_high + slack, (
      low, high)


def test_a_strip_is_searched_over_a_frame_not_over_its_width():
  """A strip 50 times as wide as high (`planning_copies`): searched as it is over a third of a
  4 : 1 frame, +-32 px; before, its 320-px copy was 6 px high (refused as too thin) and the
  search reached +-427 px of it."""
  left, right, truth, _ = _layered(3, 12, height=24, width=1200)
  copies, scale, reach = matcher.range_copy((left, right))
  assert copies[0].shape == left.shape and scale == 1 and reach == 32
  low, high = matcher.estimate_range(left, right)
  assert low <= 3 and high >= 12 and high - low <= 20, (low, high)
  wide, _, _, _ = _layered(3, 12, height=100, width=1000)  # 10 : 1, reduced 400 / 320 times.
  copies, scale, reach = matcher.range_copy((wide, wide))
  assert copies[0].shape[:2] == (80, 800) and scale == 1.25 and reach == 107


def test_dense_range_keeps_the_dense_disparities_widened_and_scaled():
  config = matcher.MatcherConfig(range_density=0.05, range_margin=2.0)
  # 200 matches on surfaces at 3..10 px of the copy, 4 scattered false ones.
  found = np.concatenate([np.repeat(np.arange(3, 11), 25), [-30, -17, 22, 29]])
  assert matcher.dense_range(found, 32, 1.0, 500, config) == (1, 12)
  assert matcher.dense_range(found, 32, 2.5, 500, config) == (2, 30)  # floor / ceil of 2.5x.
  assert matcher.dense_range(found, 32, 2.5, 20, config) == (2, 19)  # |d| <= W - 1.
  assert matcher.dense_range(np.array([]), 32, 1.0, 500, config) == (-32, 32)  # None dense.
  # A copy a few px wide searches fewer than the 5 bins of the density window.
  assert matcher.dense_range(np.array([0, 0, 1]), 1, 1.0, 4, config) == (-2, 3)


def test_bad_ranges_and_configs_raise():
  left, right, _, _ = _layered(2, 5)
  for low, high in ((5, 5), (6, 2)):
    with pytest.raises(ValueError, match='min_disparity < max_disparity'):
      matcher.match(left, right, low, high)
  with pytest.raises(ValueError, match=f'image {_W} px wide'):
    matcher.match(left, right, _W, _W + 20)
  with pytest.raises(ValueError, match='min_disparity must be a whole number'):
    matcher.match(left, right, 0.5, 8)
  with pytest.raises(ValueError, match=r"smaller than the matcher's census window of 7x9"):
    matcher.match(left[:6], right[:6], 0, 4)
  with pytest.raises(ValueError, match='one size'):
    matcher.match(left, right[:, 1:], 0, 4)
  with pytest.raises(ValueError, match='MatcherConfig.census_width'):
    matcher.MatcherConfig(census_width=8)
  with pytest.raises(ValueError, match='MatcherConfig.p2'):
    matcher.MatcherConfig(p1=20, p2=10)
  with pytest.raises(ValueError, match='MatcherConfig.range_width'):
    matcher.MatcherConfig(range_width=20)
  with pytest.raises(ValueError, match='MatcherConfig.range_width'):  # A 311 x 7 copy.
    matcher.estimate_range(np.zeros((9, 400)), np.zeros((9, 400)), matcher.MatcherConfig(
        census_height=9, census_width=7, range_width=28))


def test_a_stored_volume_in_strips_changes_almost_nothing():
  left, right, _, _ = _layered(3, 8, height=60, width=64, seed=2)
  gray = (left[..., 0] + right.mean(-1)) / 2
  config = diplopia.DiplopiaConfig(matching=sgm.SgmConfig(min_disparity=1, max_disparity=20,
                                                          p1=8, p2=64), window_radius=3)
  volume = diplopia_costs.self_matching_volume(gray, config)  # Any volume: a 7 x 7 ZNCC one.
  one = parallel_sgm.match_volume(volume, config.matching)
  # Three 20-row strips, each aggregating up to 32 rows beyond its own, in three threads:
  # vertical paths that start there move a few winners (with 8 rows, 6% of them here).
  three = parallel_sgm.match_volume(volume, config.matching, threads=3)
  assert np.mean(np.abs(one['disparity_left'] - three['disparity_left']) < 0.25) > 0.99
  assert not np.array_equal(one['disparity_left'], three['disparity_left'])


def test_a_strip_budget_cuts_a_large_volume_as_more_threads_would():
  # 128 x 128 x 40 cells hold 1.25 MiB of uint16 path sums: a 1 MiB budget needs two
  # strips even on one thread, the same two that two threads get; a small volume keeps
  # one strip per thread whatever the budget.
  rng = np.random.default_rng(3)
  volume = rng.integers(0, 64, (128, 128, 40), dtype=np.uint8)
  volume = cv2.GaussianBlur(volume, (5, 5), 0)  # Some spatial structure for SGM.
  config = sgm.SgmConfig(min_disparity=1, max_disparity=40, p1=8, p2=64)
  one = parallel_sgm.match_volume(volume, config)
  budget = parallel_sgm.match_volume(volume, config, max_strip_mib=1)
  two = parallel_sgm.match_volume(volume, config, threads=2)
  for key in ('disparity_left', 'disparity_right'):
    np.testing.assert_array_equal(budget[key], two[key])
  assert not np.array_equal(budget['disparity_left'], one['disparity_left'])
  small = volume[:40]
  np.testing.assert_array_equal(
      parallel_sgm.match_volume(small, config, max_strip_mib=1)['disparity_left'],
      parallel_sgm.match_volume(small, config)['disparity_left'])
