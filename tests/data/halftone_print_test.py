"""The print simulator: ink coverage kept on average, paper and solid ink exact, screens at
their period and angle."""

import numpy as np
import pytest

from mixstereo_tf.data import halftone_print


@pytest.mark.parametrize('level', [0, 64, 128, 200, 255])
def test_flat_tones_keep_their_mean_and_paper_and_solids_stay_exact(level):
  flat = np.full((90, 120, 3), level, np.uint8)
  printed = halftone_print.halftone_print(flat, 6.0)
  assert abs(printed.mean() - level) < 6, printed.mean()
  if level in (0, 255):
    np.testing.assert_array_equal(printed, flat)
  else:
    assert printed.std() > 20  # Dots, not a flat tone.


def test_each_ink_lies_on_its_own_screen():
  """The strongest spectral peak of each channel of a mid-gray print sits at 1 / period and
  at its ink's screen angle (modulo the square lattice's 90 degrees)."""
  printed = halftone_print.halftone_print(np.full((256, 256, 3), 128, np.uint8), 8.0)
  fy, fx = np.mgrid[-128:128, -128:128] / 256
  for channel, angle in enumerate(halftone_print.ANGLES):
    plane = printed[..., channel].astype(float)
    power = np.abs(np.fft.fftshift(np.fft.fft2(plane - plane.mean()))) ** 2
    peak = np.unravel_index(np.argmax(power), power.shape)
    assert np.hypot(fx[peak], fy[peak]) == pytest.approx(1 / 8, abs=0.01)
    found = np.degrees(np.arctan2(fy[peak], fx[peak])) % 90
    assert min(abs(found - angle), 90 - abs(found - angle)) < 4, (channel, found)
