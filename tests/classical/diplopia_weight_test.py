"""Tests of the double-image mixing weight: known answers on drawn echoes."""

import numpy as np
import pytest

from mixstereo_tf.classical import diplopia_weight

from tests.classical import double_images

_H, _W, _D = double_images.H, double_images.W, double_images.D


@pytest.mark.parametrize('weight', [0.3, 0.4, 0.5, 0.6, 0.7])
def test_the_weight_comes_from_the_echoes_of_edges(weight):
  left, right = double_images.steps_pair()
  mixture = weight * left + (1 - weight) * right
  d_left = np.full((_H, _W), float(_D))
  found = diplopia_weight.estimate_weight(mixture, d_left, np.ones((_H, _W), bool))
  assert found == pytest.approx(weight, abs=0.03)


@pytest.mark.parametrize('weight', [0.3, 0.5, 0.7])
def test_the_echo_peak_stands_out_of_unrelated_pairs_around_one_half(weight):
  """A small image's histogram: unrelated edge pairs spread around 1/2 and outweigh the
  true echoes' peak at a; the fit finds the peak where the mode stays at the spread's top."""
  bins = diplopia_weight.RATIO_BINS
  counts = (100 * np.exp(-0.5 * ((bins - 0.5) / 0.13) ** 2)
            + 30 * np.exp(-0.5 * ((bins - weight) / 0.03) ** 2))
  if weight != 0.5:
    assert abs(bins[np.argmax(counts)] - 0.5) < 0.05  # The mode misses it.
  assert diplopia_weight.echo_peak(counts) == pytest.approx(weight, abs=0.01)


def test_without_echoes_the_weight_stays_one_half():
  flat = np.full((_H, _W, 3), 0.5)
  assert diplopia_weight.estimate_weight(flat, np.full((_H, _W), 5.0),
                                         np.ones((_H, _W), bool)) == 0.5


def test_resolve_weight_and_bad_weights():
  left, right = double_images.steps_pair()
  mixture = 0.6 * left + 0.4 * right
  args = (mixture, np.full((_H, _W), float(_D)), np.ones((_H, _W), bool))
  assert diplopia_weight.resolve_weight(None, *args) == (0.5, None)
  assert diplopia_weight.resolve_weight(0.25, *args) == (0.25, None)
  found, note = diplopia_weight.resolve_weight('auto', *args)
  assert found == pytest.approx(0.6, abs=0.03) and note is None
  flat = (np.full_like(mixture, 0.5), *args[1:])  # No edge, no echo: 1/2, and said.
  assert diplopia_weight.resolve_weight('auto', *flat) == (0.5, diplopia_weight.NO_ECHO)
  for bad in (0.0, 1.0, -0.2):
    with pytest.raises(ValueError, match='mixing weight'):
      diplopia_weight.resolve_weight(bad, *args)
