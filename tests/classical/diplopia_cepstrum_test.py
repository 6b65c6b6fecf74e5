"""Tests of the double-image matcher's regional echo score."""

import dataclasses

import cv2
import numpy as np
import pytest

from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import diplopia_cepstrum

CONFIG = diplopia_cepstrum.CepstrumConfig()


def _echo(texture, lag, weight=0.5):
  """a L(x) + (1 - a) L(x + lag) of float [H, W + lag] `texture`, [H, W]."""
  return weight * texture[:, :-lag] + (1 - weight) * texture[:, lag:]


def test_the_best_lag_of_a_textured_echo_is_its_delay():
  texture = np.random.default_rng(0).uniform(0, 255, (48, 300))
  for lag, weight in ((12, 0.5), (23, 0.5), (17, 0.35)):
    scores = diplopia_cepstrum.echo_scores(_echo(texture, lag, weight), 2, 40, CONFIG)
    best = 2 + np.argmax(scores, axis=-1)
    assert np.mean(best == lag) > 0.95, (lag, weight)


def test_the_rahmonic_counts_a_periodic_texture_against_its_period():
  # Stripes of period 10 under noise, no echo: without the rahmonic term the period
  # scores like an echo; with it the period scores lower than without.
  rng = np.random.default_rng(1)
  x = np.arange(260)
  stripes = 60 * np.sign(np.sin(2 * np.pi * x / 10)) + rng.normal(0, 20, (40, 260))
  plain = dataclasses.replace(CONFIG, rahmonic=0.0)
  at_period = lambda config: diplopia_cepstrum.echo_scores(stripes, 2, 30, config)[..., 8]
  assert np.median(at_period(plain)) > 2.0  # 4.8 when written.
  assert np.median(at_period(CONFIG)) < np.median(at_period(plain)) - 1.0  # 1.8.


def test_scores_of_an_image_without_echo_are_standardised():
  gray = np.random.default_rng(2).uniform(0, 255, (60, 90))
  scores = diplopia_cepstrum.echo_scores(gray, 1, 20, CONFIG)
  assert scores.shape == (15, 6, 20)  # ceil(60 / 4), ceil(90 / 16), lags 1..20.
  # The levels are running medians over the lags: near 0 and 1, not exactly (180 points).
  assert np.abs(np.median(scores, axis=(0, 1))).max() < 0.8  # 0.69 when written.
  spread = np.median(np.abs(scores), axis=(0, 1))
  assert 0.6 < spread.min() and spread.max() < 1.6  # 0.74, 1.40.


def test_the_window_grows_to_hold_twice_the_largest_lag_within_the_image():
  assert diplopia_cepstrum.window_width(CONFIG, 10, 4000) == 128
  assert diplopia_cepstrum.window_width(CONFIG, 62, 4000) == 128
  assert diplopia_cepstrum.window_width(CONFIG, 63, 4000) == 256
  assert diplopia_cepstrum.window_width(CONFIG, 300, 4000) == 1024
  assert diplopia_cepstrum.window_width(CONFIG, 300, 1202) == 600  # Half of it, even.
  assert diplopia_cepstrum.window_width(CONFIG, 96, 256) == 128
  assert diplopia_cepstrum.window_width(CONFIG, 96, 70) == 64  # At least window / 2.


def test_lags_the_window_cannot_resolve_score_zero():
  # 192 px wide: a 96-px window resolves lags up to 46; 47..60 get no evidence.
  texture = np.random.default_rng(7).uniform(0, 255, (40, 192 + 12))
  scores = diplopia_cepstrum.echo_scores(_echo(texture, 12), 2, 60, CONFIG)
  assert scores.shape[-1] == 59 and (scores[..., 45:] == 0).all()
  assert not (scores[..., :45] == 0).all(axis=(0, 1)).any()
  assert np.mean(2 + np.argmax(scores, axis=-1) == 12) > 0.9


def test_added_costs_are_the_bilinear_grid_rounded_and_saturating():
  gray = np.random.default_rng(3).uniform(0, 255, (21, 37))
  volume = np.full((21, 37, 6), 250, np.uint8)
  volume[::2] = 10
  low = 3
  scores = diplopia_cepstrum.echo_scores(gray, low, low + 5, CONFIG)
  grid = CONFIG.weight * (CONFIG.clip - np.clip(scores, -CONFIG.clip, CONFIG.clip))
  # The grid point (i, j) sits on pixel (4 i, 16 j); between them bilinear, beyond the
  # last one the last value.
  want = np.empty((21, 37, 6))
  for y in range(21):
    fy = min(y / 4, grid.shape[0] - 1)
    i0 = min(int(fy), grid.shape[0] - 2)
    rows = (1 - (fy - i0)) * grid[i0] + (fy - i0) * grid[i0 + 1]
    for x in range(37):
      fx = min(x / 16, grid.shape[1] - 1)
      j0 = min(int(fx), grid.shape[1] - 2)
      want[y, x] = (1 - (fx - j0)) * rows[j0] + (fx - j0) * rows[j0 + 1]
  expected = np.minimum(volume + np.floor(want + 0.5), 255).astype(np.uint8)
  got = diplopia_cepstrum.add_echo_costs(volume.copy(), gray, low, CONFIG)
  np.testing.assert_array_equal(got, expected)
  assert got[1].max() == 255 and got[0].max() <= 10 + 2 * CONFIG.clip * CONFIG.weight


def test_the_matcher_uses_it_by_default():
  assert diplopia.DiplopiaConfig().cepstrum == CONFIG and CONFIG.weight > 0


def test_zero_weight_leaves_the_costs():
  volume = np.random.default_rng(4).integers(0, 256, (9, 11, 4), dtype=np.uint8)
  off = dataclasses.replace(CONFIG, weight=0.0)
  got = diplopia_cepstrum.add_echo_costs(volume.copy(), np.ones((9, 11)), 1, off)
  np.testing.assert_array_equal(got, volume)


def test_a_one_pixel_grid_is_one_value_everywhere():
  gray = np.random.default_rng(5).uniform(0, 255, (3, 5))
  big = dataclasses.replace(CONFIG, row_step=8, step=8)
  got = diplopia_cepstrum.add_echo_costs(np.zeros((3, 5, 2), np.uint8), gray, 1, big)
  assert (got == got[:1, :1]).all()


@pytest.mark.parametrize('field, value', [('weight', -1.0), ('clip', 0.0), ('rahmonic', -0.5),
                                          ('rows', 0), ('step', 0)])
def test_bad_parameters_are_refused_by_name(field, value):
  with pytest.raises(ValueError, match=field if field != 'step' else 'step'):
    dataclasses.replace(CONFIG, **{field: value})


def test_the_echo_score_rights_the_matcher_on_a_smooth_double_image():
  # A blurred texture correlates with itself over several pixels, which draws the ZNCC
  # costs to small lags; the cepstrum does not see the blur. Known answer: the echo.
  rng = np.random.default_rng(6)
  texture = cv2.GaussianBlur(rng.uniform(0, 255, (64, 300)), (0, 0), 4.0)
  texture = 255 * (texture - texture.min()) / np.ptp(texture)
  image = np.repeat(_echo(texture, 14)[..., None], 3, -1).astype(np.uint8)
  off = diplopia.DiplopiaConfig(cepstrum=dataclasses.replace(CONFIG, weight=0.0))
  inner = (slice(8, -8), slice(30, -30))
  right = lambda config: np.mean(np.abs(diplopia.unmix_diplopia(
      image, (1, 30), config)['disparity_left'][inner] - 14) <= 1)
  assert right(diplopia.DiplopiaConfig()) > 0.75  # 0.81 when written.
  assert right(off) < 0.65  # 0.60: ZNCC alone loses the echo at 40% of the pixels.


@pytest.mark.parametrize('with_prior, calls', [(False, 1), (True, 2)])
def test_video_frames_with_a_prior_skip_it_unless_asked(monkeypatch, with_prior, calls):
  seen = []
  real = diplopia_cepstrum.add_echo_costs
  monkeypatch.setattr(diplopia_cepstrum, 'add_echo_costs',
                      lambda *args: seen.append(1) or real(*args))
  image = np.random.default_rng(8).integers(0, 256, (24, 64, 3), dtype=np.uint8)
  config = diplopia.DiplopiaConfig(cepstrum=dataclasses.replace(CONFIG, with_prior=with_prior))
  diplopia.unmix_diplopia(image, (1, 12), config)  # A still (a shot's first frame).
  diplopia.unmix_diplopia(image, (1, 12), config, prior=np.full((24, 64), 5.0, np.float32))
  assert len(seen) == calls
