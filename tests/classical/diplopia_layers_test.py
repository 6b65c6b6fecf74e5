"""Tests of the double-image layers: known answers on drawn echoes."""

import numpy as np
import pytest

from mixstereo_tf.classical import diplopia_layers
from mixstereo_tf.evaluation import metrics

from tests.classical import double_images


def test_separating_with_the_true_weight_beats_one_half():
  left, right = double_images.steps_pair(1)
  mixture = 0.3 * left + 0.7 * right
  d_right = np.full((double_images.H, double_images.W), float(double_images.D))
  scores = {}
  for weight in (0.3, 0.5):
    layers = diplopia_layers.separate_layers(mixture, d_right, weight=weight)
    scores[weight] = metrics.psnr(layers['left'] * 255.0, left * 255.0)
  assert scores[0.3] > scores[0.5] + 3.0, scores
  assert scores[0.3] > metrics.psnr(mixture * 255.0, left * 255.0) + 10.0, scores


@pytest.mark.parametrize('weight', [0.3, 0.5, 0.7])
def test_views_onto_the_mixture_satisfy_it_and_come_nearer_to_the_truth(weight):
  """Known answers of `onto_mixture`: the views it returns make the mixture again; the
  orthogonal projection (k = 1) brings any pair nearer to the true pair, both views
  together; k = inf keeps the left view and makes the right one (I - a L) / (1 - a)."""
  left, right = double_images.steps_pair(2)
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
  left, right = double_images.steps_pair(4)
  d_right = np.full((double_images.H, double_images.W), float(double_images.D))
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
