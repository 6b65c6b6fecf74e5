"""Search windows around a prior: known answers, missing pixels."""

import numpy as np

from mixstereo_tf.classical import search_windows


def test_windows_around_a_prior_known_answer():
  prior = np.float32([[0, 0, 5, 5]])
  lo, widths = search_windows.around_prior(prior, -10, 10, radius=1, spread=1)
  np.testing.assert_array_equal(lo, [[-1, -1, -1, 4]])
  np.testing.assert_array_equal(widths, [[3, 8, 8, 3]])
  lo, widths = search_windows.around_prior(prior, 0, 5, radius=1, spread=0)
  np.testing.assert_array_equal(lo, [[0, 0, 4, 4]])
  np.testing.assert_array_equal(widths, [[2, 2, 2, 2]])


def test_missing_prior_pixels_search_their_neighbours_range_or_everything():
  prior = np.float32([[0, np.nan, 5, 5, 5, 5, 5, np.nan]])
  lo, widths = search_windows.around_prior(prior, -10, 10, radius=1, spread=0,
                                              missing_spread=1)
  # Pixel 1: its valid neighbours 0 and 5, +-1; pixel 7: neighbour 5, +-1.
  np.testing.assert_array_equal(lo, [[-1, -1, 4, 4, 4, 4, 4, 4]])
  np.testing.assert_array_equal(widths, [[3, 8, 3, 3, 3, 3, 3, 3]])
  # No valid prior within reach (or missing_spread <= spread): the whole range.
  lo, widths = search_windows.around_prior(
      np.float32([[np.nan, np.nan, np.nan, 2]]), -3, 6, radius=0, spread=0, missing_spread=1)
  np.testing.assert_array_equal(lo, [[-3, -3, 2, 2]])
  np.testing.assert_array_equal(widths, [[10, 10, 1, 1]])
  lo, widths = search_windows.around_prior(prior, -10, 10, radius=1, spread=0)
  np.testing.assert_array_equal(lo[0, [1, 7]], [-10, -10])
  np.testing.assert_array_equal(widths[0, [1, 7]], [21, 21])
