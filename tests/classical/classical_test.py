"""Classical de-anaglyph / de-diplopia baselines on synthetic scenes with known disparity."""

import dataclasses
import warnings

import cv2
import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.classical import anaglyph
from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import diplopia_cepstrum
from mixstereo_tf.classical import diplopia_costs
from mixstereo_tf.classical import diplopia_range
from mixstereo_tf.classical import diplopia_layers
from mixstereo_tf.classical import sgm
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import sample
from mixstereo_tf.evaluation import metrics

_H, _W = 64, 96
_RECT = (16, 48, 32, 72)  # y0, y1, x0, x1 of the foreground in the left view.


def _texture(rng, height, width):
  """Smooth random colour texture, channels correlated like natural images, [0, 255]."""
  def blur():
    noise = cv2.GaussianBlur(rng.normal(size=(height, width)).astype(np.float32), (0, 0), 1.5)
    return noise / noise.std()

  base = blur()
  channels = [0.8 * base + 0.4 * blur() + rng.uniform(-0.5, 0.5) for _ in range(3)]
  return np.clip(127.5 + 40.0 * np.stack(channels, -1), 0, 255)


def _scene(d_bg, d_fg, seed=0):
  """Background plane (disparity d_bg) behind a fronto-parallel rectangle (d_fg).

  Returns uint8 left, right, the true left disparity [H, W] and the non-occluded left mask.
  """
  rng = np.random.default_rng(seed)
  background = _texture(rng, _H, _W + d_bg)
  foreground = _texture(rng, _H, _W)
  y0, y1, x0, x1 = _RECT
  left, right = background[:, :_W].copy(), background[:, d_bg:].copy()
  left[y0:y1, x0:x1] = foreground[y0:y1, x0:x1]
  right[y0:y1, x0 - d_fg:x1 - d_fg] = foreground[y0:y1, x0:x1]
  d_left = np.full((_H, _W), d_bg, np.float32)
  d_left[y0:y1, x0:x1] = d_fg
  d_right = np.full((_H, _W), d_bg, np.float32)
  d_right[y0:y1, x0 - d_fg:x1 - d_fg] = d_fg
  match = np.arange(_W)[None, :] - d_left.astype(np.int64)
  nonocc = (match >= 0) & (np.take_along_axis(d_right, np.clip(match, 0, _W - 1), 1) == d_left)
  return np.rint(left).astype(np.uint8), np.rint(right).astype(np.uint8), d_left, nonocc


def _mix(name, left, right):
  to_tf = lambda a: image_range.u8_to_signed(tf.constant(a))
  return image_range.signed_to_u8(mixtures.mix(name, to_tf(left), to_tf(right)).numpy())


def test_fill_holes_takes_the_smaller_neighbour():
  disparity = np.array([[9., 0., 0., 4., 0.], [0., 7., 0., 0., 0.]], np.float32)
  valid = disparity > 0
  np.testing.assert_array_equal(sgm.fill_holes(disparity, valid),
                                [[9, 4, 4, 4, 4], [7, 7, 7, 7, 7]])


def test_lr_check_flags_an_inconsistent_pixel():
  d_left = np.full((1, 8), 2.0, np.float32)
  d_right = d_left.copy()
  d_right[0, 3] = 5.0  # Left pixel 5 matches right pixel 3.
  ok_left, ok_right = sgm.lr_check(d_left, d_right, 1.0)
  np.testing.assert_array_equal(ok_left[0], [0, 0, 1, 1, 1, 0, 1, 1])
  np.testing.assert_array_equal(ok_right[0], [1, 1, 1, 0, 1, 1, 0, 0])


def test_lr_check_reads_nan_as_inconsistent_without_a_cast_warning():
  d_left = np.full((1, 6), 1.0, np.float32)
  d_right = d_left.copy()
  d_left[0, 2], d_right[0, 4] = np.nan, np.nan  # No estimate there (occluded).
  with warnings.catch_warnings():
    warnings.simplefilter('error')  # NaN cast to an index warned, and read garbage.
    ok_left, ok_right = sgm.lr_check(d_left, d_right, 1.0)
  np.testing.assert_array_equal(ok_left[0], [0, 1, 0, 1, 1, 0])
  np.testing.assert_array_equal(ok_right[0], [1, 0, 1, 1, 0, 0])


def _y_psnr(image, truth):
  luma = np.array(mixtures.LUMA)
  return metrics.psnr(image.astype(np.float64) @ luma, truth.astype(np.float64) @ luma)


@pytest.mark.parametrize('name', ['anaglyph', 'green_magenta', 'amber_blue'])
def test_anaglyph_disparity_and_colours(name):
  left, right, d_left, nonocc = _scene(d_bg=3, d_fg=8)
  mixture = _mix(name, left, right)
  out = anaglyph.unmix_anaglyph(mixture, name)
  bad1 = metrics.bad_pixel_rate(out['disparity_left'], d_left, nonocc, 1.0)
  trivial = metrics.bad_pixel_rate(np.full_like(d_left, np.median(d_left)), d_left, nonocc, 1.0)
  assert bad1 < 0.15 and bad1 < trivial / 2, (bad1, trivial)
  assert out['left'].dtype == np.uint8 and out['disparity_right'].shape == (_H, _W)
  for view, truth in (('left', left), ('right', right)):
    gain = metrics.psnr(out[view], truth) - metrics.psnr(mixture, truth)
    assert gain >= 6.0, (view, gain)


def test_diplopia_constant_shift_and_layers():
  left, right, d_left, nonocc = _scene(d_bg=5, d_fg=5)
  mixture = _mix('diplopia', left, right)
  out = diplopia.unmix_diplopia(mixture)
  interior = nonocc & (np.arange(_W)[None, :] >= 8)
  assert abs(np.median(out['disparity_left'][interior]) - 5.0) < 1.0
  assert metrics.bad_pixel_rate(out['disparity_left'], d_left, interior, 1.0) < 0.25
  for view, truth in (('left', left), ('right', right)):
    gain = metrics.psnr(out[view], truth) - metrics.psnr(mixture, truth)
    assert gain >= 1.0, (view, gain)


def test_diplopia_layers_from_a_16_bit_copy_keep_its_depth():
  """`views_image`: the same disparities (matched on the 8-bit mixture), the layers solved
  from the 16-bit samples and returned as uint16; a copy of another size is named."""
  left, right, _, _ = _scene(d_bg=5, d_fg=5)
  mixture = _mix('diplopia', left, right)
  deep = mixture.astype(np.uint16) * 257 + 100
  out, eight = diplopia.unmix_diplopia(mixture, views_image=deep), diplopia.unmix_diplopia(mixture)
  np.testing.assert_array_equal(out['disparity_left'], eight['disparity_left'])
  assert out['left'].dtype == out['right'].dtype == np.uint16
  for view in ('left', 'right'):  # 100 / 257 of a level brighter, as the copy is.
    shift = out[view].astype(float) / 257 - eight[view]
    assert abs(np.median(shift) - 100 / 257) < 0.2, (view, np.median(shift))
  with pytest.raises(ValueError, match=r'views_image has shape \(16, 16, 3\)'):
    diplopia.unmix_diplopia(mixture, views_image=deep[:16, :16])


@pytest.mark.parametrize('shape', [(64, 1), (12, 12), (8, 16), (16, 8)])
def test_a_double_image_smaller_than_the_zncc_window_is_a_clear_error(shape):
  """A 1-px strip gave an IndexError, a 12 x 12 image a broadcasting error."""
  image = np.random.RandomState(0).uniform(0, 1, shape + (3,)).astype(np.float32)
  with pytest.raises(ValueError, match=rf'a {shape[0]}x{shape[1]} image is smaller than the '
                                       r"double-image matcher's ZNCC window of 15x15"):
    diplopia_range.estimate_range(image)
  assert diplopia_range.estimate_range(np.resize(image, (15, 15, 3)))  # Large enough.
  # With a range given, a strip without a lag inside it is named (it was an IndexError).
  if shape[1] == 1:
    with pytest.raises(ValueError, match='a 64x1 image has no lag of \\[1, 4\\]'):
      diplopia.unmix_diplopia(image, (1, 4))


def test_diplopia_reports_its_disparities_before_solving_the_layers(monkeypatch):
  left, right, _, _ = _scene(d_bg=5, d_fg=5)
  told, solve = [], diplopia_layers.separate_layers

  def layers(*args, **kwargs):
    assert len(told) == 1  # Told once, before the layer solve (a video's next frame
    return solve(*args, **kwargs)  # starts then, `hints.FrameHint.on_disparity`).

  monkeypatch.setattr(diplopia_layers, 'separate_layers', layers)
  out = diplopia.unmix_diplopia(_mix('diplopia', left, right), on_disparity=told.append)
  assert sorted(told[0]) == ['disparity_left', 'disparity_right']
  for key in told[0]:
    np.testing.assert_array_equal(told[0][key], out[key])


def test_a_noisy_echo_is_found_by_the_shipped_window_and_missed_by_7x7():
  """The echo shares half of each window's signal: with noise the 7 x 7 ZNCC (the window
  before 2026-11-26) loses the lag where the shipped 15 x 15 one keeps it (the ZNCC costs
  alone: the echo score of 2026-11-29 finds it with either window)."""
  rng = np.random.default_rng(0)
  lag, height, width = 12, 48, 160
  texture = cv2.GaussianBlur(rng.uniform(0, 255, (height, width + lag)).astype(np.float32),
                             (0, 0), 1.0)  # Standard deviation about 21 levels.
  double = (texture[:, lag:] + texture[:, :width]) / 2  # Left x matches right x - 12.
  noisy = np.clip(double + rng.normal(0, 10, double.shape), 0, 255).astype(np.uint8)
  image = np.repeat(noisy[..., None], 3, axis=-1)

  def found(config):
    out = diplopia.unmix_diplopia(image, (1, 30), config)
    return np.mean(np.abs(out['disparity_left'][:, 30:] - lag) <= 1)

  zncc_alone = diplopia.DiplopiaConfig(cepstrum=diplopia_cepstrum.CepstrumConfig(weight=0))
  assert zncc_alone.window_radius == 7
  assert found(zncc_alone) > 0.98  # 0.995 on 2 cores (0.976 at P 8 / 64).
  assert found(dataclasses.replace(zncc_alone, window_radius=3)) < 0.95  # 0.918 (0.827).


def test_add_prior_penalises_each_lag_by_its_distance_to_the_prior_window():
  config = diplopia.DiplopiaConfig(matching=sgm.SgmConfig(min_disparity=1, max_disparity=30),
                                   prior_weight=4, prior_cap=16)
  volume = np.zeros((2, 3, 30), np.uint8)  # Lags 1..30.
  volume[1, 2] = 250
  prior = np.full((2, 3), 10.0, np.float32)
  prior[0, 1] = np.nan  # No prior there: the whole range, no penalty.
  out = diplopia_costs.add_prior(volume, config, prior, (1, 0))  # Window [9, 11].
  lags = np.arange(1, 31)
  expected = np.minimum(4 * np.maximum(np.maximum(9 - lags, 0), lags - 11), 16)
  np.testing.assert_array_equal(out[0, 0], expected)  # e.g. lag 8: 4, lag 5: cap 16.
  np.testing.assert_array_equal(out[0, 1], 0)
  np.testing.assert_array_equal(out[1, 2], np.minimum(250 + expected, 255))  # Saturates.
  with pytest.raises(ValueError, match='prior'):
    diplopia_costs.add_prior(volume, config, prior[:1], (1, 0))


def test_a_prior_holds_the_echo_that_noise_hides():
  """A video frame's prior (the previous frame's disparity) keeps the lag where the noise
  leaves the self-matching ambiguous; the same frame alone loses it."""
  rng = np.random.default_rng(0)
  lag, height, width = 12, 48, 160
  texture = cv2.GaussianBlur(rng.uniform(0, 255, (height, width + lag)).astype(np.float32),
                             (0, 0), 1.0)
  double = (texture[:, lag:] + texture[:, :width]) / 2
  noisy = double + np.random.default_rng(1).normal(0, 30, double.shape)
  image = np.repeat(np.clip(noisy, 0, 255).astype(np.uint8)[..., None], 3, axis=-1)
  found = lambda out: np.mean(np.abs(out['disparity_left'][:, 30:] - lag) <= 1)
  alone = diplopia.unmix_diplopia(image, (1, 30))
  held = diplopia.unmix_diplopia(image, (1, 30),
                                 prior=np.full((height, width), float(lag), np.float32))
  assert found(alone) < 0.5  # 0.30 on 2 cores (0.11 before the echo score of 2026-11-29).
  assert found(held) > 0.95  # 0.99.


def test_diplopia_layers_with_true_shift_beat_the_mixture():
  left, right, _, _ = _scene(d_bg=5, d_fg=5)
  mixture01 = _mix('diplopia', left, right) / 255.0
  layers = diplopia_layers.separate_layers(mixture01, np.full((_H, _W), 5.0))
  gain = (metrics.psnr(image_range.unit_to_u8(layers['left']), left) -
          metrics.psnr(mixture01 * 255.0, left))
  assert gain >= 4.0, gain


@pytest.mark.parametrize('name', ['gray', 'half_color', 'dubois', 'dubois_ffmpeg',
                                  'green_magenta_half', 'amber_blue_dubois'])
def test_lossy_encodings_beat_the_mixture_in_luminance(name):
  left, right, d_left, nonocc = _scene(d_bg=3, d_fg=8, seed=2)
  mixture = _mix(name, left, right)
  out = anaglyph.unmix_anaglyph(mixture, name)
  bad1 = metrics.bad_pixel_rate(out['disparity_left'], d_left, nonocc, 1.0)
  assert bad1 < 0.2, bad1
  for view, truth in (('left', left), ('right', right)):
    gain = _y_psnr(out[view], truth) - _y_psnr(mixture, truth)
    assert gain >= 3.0, (view, gain)
  if name == 'gray':  # No colour was transmitted: the views come back (nearly) gray.
    for view in ('left', 'right'):
      tint = np.abs(out[view].astype(float) - out[view].mean(-1, keepdims=True))
      assert tint.mean() < 1.0 and np.percentile(tint, 99) < 4.0, (view, tint.max())


def test_window_aligned_pair_has_negative_disparities():
  """Shifting the right view by 6 px makes the background -3 and the rectangle +2."""
  left, right, d_left, nonocc = _scene(d_bg=3, d_fg=8, seed=1)
  shifted = np.concatenate([np.repeat(right[:, :1], 6, 1), right[:, :-6]], axis=1)
  mixture = _mix('anaglyph', left[:, 6:], shifted[:, 6:])
  truth = d_left[:, 6:] - 6
  inside = np.arange(_W - 6)[None, :] - truth <= _W - 7  # The match lies inside the image.
  valid = nonocc[:, 6:] & inside
  out = anaglyph.unmix_anaglyph(mixture, 'anaglyph')
  low, high = out['disparity_range']
  assert low <= -3 and high >= 2
  background, foreground = valid & (truth < 0), valid & (truth > 0)
  assert abs(np.median(out['disparity_left'][background]) + 3) < 0.5
  assert abs(np.median(out['disparity_left'][foreground]) - 2) < 0.5
  assert metrics.bad_pixel_rate(out['disparity_left'], truth, valid, 1.0) < 0.25
  given = anaglyph.unmix_anaglyph(mixture, 'anaglyph', disparity_range=(-5, 4))
  assert given['disparity_range'] == (-5, 4)
  assert given['disparity_left'].min() >= -5 - 0.5


@pytest.mark.parametrize('name', ['monocular', 'diplopia', 'nonsense'])
def test_a_non_anaglyph_mixture_is_refused_by_the_de_anaglyph(name):
  with pytest.raises(ValueError, match=name):
    anaglyph.unmix_anaglyph(np.zeros((8, 16, 3), np.uint8), name)


def test_bad_image_raises():
  with pytest.raises(ValueError, match='mixture'):
    anaglyph.unmix_anaglyph(np.zeros((8, 16), np.uint8), 'anaglyph')
  with pytest.raises(ValueError, match=r'\[0, 1\]'):
    diplopia.unmix_diplopia(np.full((8, 16, 3), 2.0))


def test_the_small_lag_penalty_keeps_a_real_double_image_off_the_smallest_lags():
  """Motorcycle (a real Middlebury 2014 pair, disparities 7-60 px at this size) as a double
  image: without the penalty a fifth of its pixels lock onto lags 1-3, where neighbouring
  pixels of a camera image correlate whatever the echo; with it they find their echoes
  (the ZNCC costs alone, as the penalty was chosen; the echo score comes on top)."""
  left, right, truth = sample.motorcycle()
  image = np.rint((left.astype(np.float64) + right) / 2).astype(np.uint8)
  search = diplopia_range.estimate_range(image)
  valid = truth > 0

  def scores(config):
    found = diplopia.unmix_diplopia(image, search, config)['disparity_left'][valid]
    return np.mean(np.abs(found - truth[valid]) > 1), np.mean(found < 4)

  assert search[0] < 4 <= 4 * 4 <= search[1]
  zncc_alone = diplopia.DiplopiaConfig(cepstrum=diplopia_cepstrum.CepstrumConfig(weight=0))
  bad_without, small_without = scores(dataclasses.replace(zncc_alone, small_lag_penalty=0))
  bad, small = scores(zncc_alone)
  assert small_without > 0.1 and small < 0.01  # 0.19 and 0.004 on 2 cores.
  assert bad < bad_without - 0.04  # 0.346 against 0.402.


def test_the_small_lag_penalty_spares_narrow_ranges_and_saturates():
  config = diplopia.DiplopiaConfig(matching=sgm.SgmConfig(min_disparity=1, max_disparity=16))
  assert diplopia_costs.small_lags(config) == 3  # Lags 1, 2, 3.
  volume = np.full((2, 2, 16), 10, np.uint8)
  volume[0, 0, 1] = 250
  out = diplopia_costs.penalise_small_lags(volume.copy(), config)
  expected = volume.astype(int)
  expected[..., :3] += 8
  np.testing.assert_array_equal(out, np.minimum(expected, 255))  # 250 + 8 saturates.
  narrow = dataclasses.replace(config, matching=sgm.SgmConfig(min_disparity=1,
                                                               max_disparity=15))
  assert diplopia_costs.small_lags(narrow) == 0  # Copies at most 15 px apart keep lags 1-3.
  above = dataclasses.replace(config, matching=sgm.SgmConfig(min_disparity=6,
                                                              max_disparity=40))
  assert diplopia_costs.small_lags(above) == 0
  with pytest.raises(ValueError, match='min_lag'):
    diplopia.DiplopiaConfig(min_lag=0)
  with pytest.raises(ValueError, match='small_lag_penalty'):
    diplopia.DiplopiaConfig(small_lag_penalty=256)
