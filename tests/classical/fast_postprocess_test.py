"""The numba post-processing equals the NumPy reference `sgm.postprocess` bit for bit."""

import numpy as np
import pytest

from mixstereo_tf.classical import fast_postprocess
from mixstereo_tf.classical import sgm


def _maps(seed, height=23, width=41):
  """Noisy left / right maps of a two-layer scene, with unmatched right pixels (-1e4) and
  values that round exactly half-way."""
  rng = np.random.default_rng(seed)
  truth = np.where(np.arange(width)[None, :] > width // 2, 7.0, 2.0) * np.ones((height, 1))
  left = (truth + rng.normal(0, 0.8, truth.shape)).astype(np.float32)
  right = (truth + rng.normal(0, 0.8, truth.shape)).astype(np.float32)
  right[rng.uniform(size=right.shape) < 0.05] = -1e4
  left[rng.uniform(size=left.shape) < 0.05] = 3.5
  return left, right


@pytest.mark.parametrize('seed', range(4))
@pytest.mark.parametrize('threshold', [0.0, 0.3, 1.0])
def test_equals_the_numpy_reference(seed, threshold):
  left, right = _maps(seed)
  want = sgm.postprocess(left, right, threshold)
  got = fast_postprocess.postprocess(left, right, threshold)
  assert sorted(got) == sorted(want)
  for key in want:
    np.testing.assert_array_equal(got[key], want[key])
    assert got[key].dtype == want[key].dtype


def test_rows_without_a_consistent_pixel_take_the_smallest_consistent_disparity():
  left = np.array([[2.0, 2.0, 2.0, 2.0], [9.0, 9.0, 9.0, 9.0]], np.float32).repeat(3, 0)
  right = np.full(left.shape, -1e4, np.float32)
  right[:3, :2] = 2.0  # Left pixels 2, 3 of the top rows match right pixels 0, 1.
  got = fast_postprocess.postprocess(left, right, 1.0)
  np.testing.assert_array_equal(got['disparity_left'], 2.0)  # The 9s are all replaced.
  assert got['consistent_left'][:2, 2:].all() and not got['consistent_left'][3:].any()
  np.testing.assert_array_equal(got['disparity_left'],
                                sgm.postprocess(left, right, 1.0)['disparity_left'])


def test_no_consistent_pixel_at_all_gives_zero():
  left = np.full((4, 5), 3.0, np.float32)
  got = fast_postprocess.postprocess(left, np.full((4, 5), -1e4, np.float32), 1.0)
  np.testing.assert_array_equal(got['disparity_left'], 0.0)
