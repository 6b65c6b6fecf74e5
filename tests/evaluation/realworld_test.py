"""Tests for evaluation/realworld.py: window alignment, encoders and the scores."""

import numpy as np
import pytest

from mixstereo_tf.core import mixtures
from mixstereo_tf.evaluation import realworld


def _pair(shift_per_column=0.0):
  """A 20 x 60 pair whose left disparity grows from 4 to 14 px along the rows' columns."""
  rng = np.random.RandomState(0)
  left = rng.randint(0, 256, (20, 60, 3)).astype(np.uint8)
  right = rng.randint(0, 256, (20, 60, 3)).astype(np.uint8)
  disparity = np.tile(np.linspace(4.0, 14.0, 60, dtype=np.float32), (20, 1))
  valid = np.ones((20, 60), bool)
  valid[:, :3] = False  # Percentiles use valid pixels only.
  return {'left': left, 'right': right, 'disparity_left': disparity + shift_per_column,
          'valid_left': valid}


def test_window_shift_puts_the_fraction_below_zero():
  data = _pair()
  low, high = np.percentile(data['disparity_left'][data['valid_left']], [1, 99])
  for fraction in (0.0, 0.3, 0.7, 1.0):
    s = realworld.window_shift(data['disparity_left'], data['valid_left'], fraction)
    assert s == round(low + fraction * (high - low))
    below = (data['disparity_left'][data['valid_left']] - s < 0).mean()
    assert abs(below - fraction) < 0.06


def test_window_align_crops_the_views_and_shifts_the_ground_truth():
  data = _pair()
  aligned = realworld.window_align(data, 0.3)
  s = aligned['shift']
  assert s == realworld.window_shift(data['disparity_left'], data['valid_left'], 0.3) > 0
  width = 60 - s
  assert aligned['left'].shape == aligned['right'].shape == (20, width, 3)
  # The left view keeps columns [s, W), the right view [0, W - s): d becomes d - s.
  np.testing.assert_array_equal(aligned['left'], data['left'][:, s:])
  np.testing.assert_array_equal(aligned['right'], data['right'][:, :width])
  np.testing.assert_allclose(aligned['disparity_left'], data['disparity_left'][:, s:] - s)
  np.testing.assert_array_equal(aligned['valid_left'], data['valid_left'][:, s:])
  assert aligned['disparity_left'].min() < 0 < aligned['disparity_left'].max()
  # A left pixel x still matches the right pixel x - d: the content moved with the crop.
  x, d = 30, int(data['disparity_left'][0, 30 + s])  # Column 30 of the aligned pair.
  assert aligned['left'][0, x].tolist() == data['left'][0, x + s].tolist()
  assert aligned['right'][0, x - (d - s)].tolist() == data['right'][0, x + s - d].tolist()


def test_window_align_negative_shift_and_errors():
  data = _pair(shift_per_column=-20.0)  # Disparities -16 .. -6: s < 0.
  aligned = realworld.window_align(data, 0.5)
  s = aligned['shift']
  assert s < 0
  np.testing.assert_array_equal(aligned['left'], data['left'][:, :60 + s])
  np.testing.assert_array_equal(aligned['right'], data['right'][:, -s:])
  np.testing.assert_allclose(aligned['disparity_left'], data['disparity_left'][:, :60 + s] - s)
  with pytest.raises(ValueError, match=r'\[0, 1\]'):
    realworld.window_align(data, 1.5)
  with pytest.raises(ValueError, match='too little'):
    realworld.window_align(_pair(shift_per_column=40.0), 0.0)


def test_our_encoder_is_the_mixture_operator():
  data = _pair()
  for name in ('anaglyph', 'gray'):
    image = realworld.make_anaglyph(data, name, 'ours')
    spec = mixtures.get_mixture(name)
    expected = (data['left'].astype(float) @ np.asarray(spec.left_matrix).T +
                data['right'].astype(float) @ np.asarray(spec.right_matrix).T)
    assert np.abs(image.astype(float) - np.clip(expected, 0, 255)).max() <= 1.0
  with pytest.raises(ValueError, match='Unknown encoder'):
    realworld.make_anaglyph(data, 'anaglyph', 'stereophotomaker')


def test_luma_and_scores_known_answers():
  data = _pair()
  np.testing.assert_allclose(realworld.luma(np.full((1, 1, 3), [255, 0, 0], np.uint8)),
                             [[0.299 * 255]], rtol=1e-6)
  perfect = realworld.score(data, data['left'], data['right'], data['disparity_left'])
  assert perfect['psnr_left'] == perfect['ypsnr_right'] == 100.0
  assert perfect['bad1'] == perfect['bad3'] == 0.0
  # A uniform error of 2 px: bad-1 is 100 %, bad-3 0 %.
  wrong = realworld.score(data, data['left'], data['right'], data['disparity_left'] + 2.0)
  assert wrong['bad1'] == pytest.approx(1.0) and wrong['bad3'] == 0.0
  # Gray views of the truth: luma PSNR stays high while RGB PSNR drops.
  gray = lambda v: np.repeat(np.round(realworld.luma(v))[..., None], 3, 2).astype(np.uint8)
  row = realworld.score(data, gray(data['left']), gray(data['right']))
  assert row['ypsnr_left'] > 45.0 > 20.0 > row['psnr_left']
  assert 'bad1' not in row


def test_scores_count_negative_disparities_of_aligned_pairs():
  aligned = realworld.window_align(_pair(), 0.5)
  truth = aligned['disparity_left']
  assert (truth < 0).any()
  row = realworld.score(aligned, aligned['left'], aligned['right'], truth + 0.5)
  assert row['bad1'] == 0.0  # Every valid pixel counts, the negative ones included.
  off = np.where(truth < 0, truth + 5.0, truth)
  row = realworld.score(aligned, aligned['left'], aligned['right'], off)
  negative = (truth < 0) & aligned['valid_left']
  assert row['bad1'] == pytest.approx(negative.sum() / aligned['valid_left'].sum())
