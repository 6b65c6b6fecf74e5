"""Tests of the double-image layers and mixing weight: known answers on drawn echoes."""

import numpy as np
import pytest

from mixstereo_tf.classical import diplopia_layers
from mixstereo_tf.evaluation import metrics

_H, _W, _D = 24, 160, 7


def _steps_pair(seed=0):
  """A left view of vertical steps 20-40 px apart (distinct levels per 8-row band), the
  right view = left shifted by _D (R(x) = L(x + _D)), float [H, W, 3] in [0, 1]."""
  rng = np.random.default_rng(seed)
  wide = np.zeros((_H, _W + _D, 3))
  for band in range(0, _H, 8):
    x = 0
    while x < _W + _D:
      step = int(rng.integers(20, 41))
      wide[band:band + 8, x:x + step] = rng.uniform(0.1, 0.9, 3)
      x += step
  return wide[:, :_W], wide[:, _D:]


@pytest.mark.parametrize('weight', [0.3, 0.4, 0.5, 0.6, 0.7])
def test_the_weight_comes_from_the_echoes_of_edges(weight):
  left, right = _steps_pair()
  mixture = weight * left + (1 - weight) * right
  d_left = np.full((_H, _W), float(_D))
  found = diplopia_layers.estimate_weight(mixture, d_left, np.ones((_H, _W), bool))
  assert found == pytest.approx(weight, abs=0.03)


@pytest.mark.parametrize('weight', [0.3, 0.5, 0.7])
def test_the_echo_peak_stands_out_of_unrelated_pairs_around_one_half(weight):
  """A small image's histogram: unrelated edge pairs spread around 1/2 and outweigh the
  true echoes' peak at a; the fit finds the peak where the mode stays at the spread's top."""
  bins = diplopia_layers.RATIO_BINS
  counts = (100 * np.exp(-0.5 * ((bins - 0.5) / 0.13) ** 2)
            + 30 * np.exp(-0.5 * ((bins - weight) / 0.03) ** 2))
  if weight != 0.5:
    assert abs(bins[np.argmax(counts)] - 0.5) < 0.05  # The mode misses it.
  assert diplopia_layers.echo_peak(counts) == pytest.approx(weight, abs=0.01)


def test_without_echoes_the_weight_stays_one_half():
  flat = np.full((_H, _W, 3), 0.5)
  assert diplopia_layers.estimate_weight(flat, np.full((_H, _W), 5.0),
                                         np.ones((_H, _W), bool)) == 0.5


def test_separating_with_the_true_weight_beats_one_half():
  left, right = _steps_pair(1)
  mixture = 0.3 * left + 0.7 * right
  d_right = np.full((_H, _W), float(_D))
  scores = {}
  for weight in (0.3, 0.5):
    layers = diplopia_layers.separate_layers(mixture, d_right, weight=weight)
    scores[weight] = metrics.psnr(layers['left'] * 255.0, left * 255.0)
  assert scores[0.3] > scores[0.5] + 3.0, scores
  assert scores[0.3] > metrics.psnr(mixture * 255.0, left * 255.0) + 10.0, scores


def test_resolve_weight_and_bad_weights():
  left, right = _steps_pair()
  mixture = 0.6 * left + 0.4 * right
  args = (mixture, np.full((_H, _W), float(_D)), np.ones((_H, _W), bool))
  assert diplopia_layers.resolve_weight(None, *args) == (0.5, None)
  assert diplopia_layers.resolve_weight(0.25, *args) == (0.25, None)
  found, note = diplopia_layers.resolve_weight('auto', *args)
  assert found == pytest.approx(0.6, abs=0.03) and note is None
  flat = (np.full_like(mixture, 0.5), *args[1:])  # No edge, no echo: 1/2, and said.
  assert diplopia_layers.resolve_weight('auto', *flat) == (0.5, diplopia_layers.NO_ECHO)
  for bad in (0.0, 1.0, -0.2):
    with pytest.raises(ValueError, match='mixing weight'):
      diplopia_layers.resolve_weight(bad, *args)


@pytest.mark.parametrize('weight', [0.3, 0.5, 0.7])
def test_views_onto_the_mixture_satisfy_it_and_come_nearer_to_the_truth(weight):
  """Known answers of `onto_mixture`: the views it returns make the mixture again; the
  orthogonal projection (k = 1) brings any pair nearer to the true pair, both views
  together; k = inf keeps the left view and makes the right one (I - a L) / (1 - a)."""
  left, right = _steps_pair(2)
  mixture = weight * left + (1 - weight) * right
  rng = np.random.default_rng(3)
  guess = [np.clip(view + rng.normal(0, 0.05, view.shape), 0.2, 0.8) for view in (left, right)]
  for share in (1.0, 3.0, np.inf):
    new_left, new_right = diplopia_layers.onto_mixture(mixture, *guess, weight, share)
    inside = (new_left > 0) & (new_left < 1) & (new_right > 0) & (new_right < 1)
    remade = weight * new_left + (1 - weight) * new_right
    np.testing.assert_allclose(remade[inside], mixture[inside], atol=1e-5)
  error = lambda pair: sum(np.sum((a - b) ** 2) for a, b in zip(pair, (left, right)))
  assert error(diplopia_layers.onto_mixture(mixture, *guess, weight, 1.0)) < 0.8 * error(guess)
  kept, made = diplopia_layers.onto_mixture(mixture, *guess, weight, np.inf)
  np.testing.assert_allclose(kept, guess[0], atol=1e-6)
  with pytest.raises(ValueError, match='right_share must be positive'):
    diplopia_layers.onto_mixture(mixture, *guess, weight, 0.0)


def test_the_right_layer_from_the_mixture_is_right_where_the_left_view_hides_it():
  """A foreground strip 12 px nearer than its background: the right view shows background
  the left one hides, which the left layer sampled at x + d_R cannot give; what the mixture
  leaves of the left layer can, as far as that layer is right (`LayerConfig.
  right_from_mixture`; measured around the strip 13.5 -> 14.5 dB, the left layer there
  being wrong too, and over the whole view higher as well)."""
  left, right = _steps_pair(4)
  d_right = np.full((_H, _W), float(_D))
  right = right.copy()
  right[:, 60:72] = 0.95  # Seen by the right eye alone: no left pixel holds it.
  mixture = 0.5 * left + 0.5 * right
  psnr, whole, warped = {}, {}, {}
  for from_mixture in (False, True):
    config = diplopia_layers.LayerConfig(right_from_mixture=from_mixture)
    layers = diplopia_layers.separate_layers(mixture, d_right, config)
    psnr[from_mixture] = metrics.psnr(layers['right'][:, 56:76] * 255, right[:, 56:76] * 255)
    whole[from_mixture] = metrics.psnr(layers['right'] * 255, right * 255)
    warped[from_mixture] = layers['right_warped']
  assert psnr[True] > psnr[False] + 0.7 and whole[True] > whole[False], (psnr, whole)
  np.testing.assert_array_equal(warped[True], warped[False])  # The refiners' input.
