"""A tilted double image's echo direction, and its self-matching's consistent share."""

import cv2
import numpy as np
import pytest
import skimage.data

from mixstereo_tf.classical import echo_tilt


def _double_image(angle: float) -> np.ndarray:
  """Motorcycle's double image (a = 1/2) at half size, turned by `angle` degrees, gray."""
  left, right, _ = skimage.data.stereo_motorcycle()
  half = lambda x: np.float32(cv2.resize(x, (370, 250), interpolation=cv2.INTER_AREA))
  mixed = ((half(left) + half(right)) / 2).mean(axis=-1)
  turn = cv2.getRotationMatrix2D((185, 125), angle, 1.0)
  return cv2.warpAffine(mixed, turn, (370, 250), flags=cv2.INTER_LINEAR,
                        borderMode=cv2.BORDER_REFLECT)


@pytest.mark.parametrize('angle', [-3.0, 4.0])
def test_the_turn_of_a_tilted_double_image_is_found(angle):
  tilt = echo_tilt.estimate(_double_image(angle))
  assert tilt.angle == pytest.approx(-angle, abs=0.3) and tilt.offset == 0.0
  assert tilt.matches >= echo_tilt.EchoConfig().min_matches


def test_a_level_double_image_reads_nearly_level_and_matches_best():
  level, turned = _double_image(0.0), _double_image(4.0)
  assert abs(echo_tilt.estimate(level).angle) < 0.3
  assert (echo_tilt.consistent_share(level, 640) >
          echo_tilt.consistent_share(turned, 640) + 0.1)


def test_echoes_are_found_on_the_left_at_the_drawn_shift_and_not_in_a_photo():
  """A drawn texture plus its copy 9 px to the right: every match lies at dx = 9, dy = 0;
  the texture alone (no echo) gives too few matches for a line."""
  rng = np.random.default_rng(0)
  texture = cv2.GaussianBlur(np.float32(rng.uniform(0, 255, (120, 200))), (0, 0), 1.2)
  echoed = (texture[:, 9:] + texture[:, :-9]) / 2  # I(x) = (T(x + 9) + T(x)) / 2.
  moves = echo_tilt.echo_displacements(255 * (echoed - echoed.min()) / np.ptp(echoed))
  assert len(moves) >= 20
  np.testing.assert_allclose(np.median(moves, axis=0), [9, 0], atol=0.1)
  assert echo_tilt.estimate(texture) is None


def test_the_slope_is_fitted_through_the_origin_past_outliers():
  dx = np.arange(6.0, 46.0)
  moves = np.stack([dx, 0.05 * dx], 1)
  moves[::5, 1] += 7.0  # A fifth of them wrong.
  slope, inliers = echo_tilt.fit_slope(moves)
  assert slope == pytest.approx(0.05, abs=1e-9) and inliers == 32
  assert echo_tilt.fit_slope(moves[:1]) is None
