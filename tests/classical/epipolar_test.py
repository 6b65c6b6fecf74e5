"""The eyes' displacement line: fitted through outliers, estimated on turned pairs, and the
turn undone."""

import cv2
import numpy as np
import pytest

from mixstereo_tf.classical import epipolar


def test_the_line_is_fitted_through_outliers():
  rng = np.random.default_rng(0)
  dx = rng.uniform(0, 60, 200)
  dy = 0.05 * dx + 1.0 + rng.normal(0, 0.1, 200)
  dy[:40] = rng.uniform(-10, 10, 40)  # Wrong matches.
  slope, offset, inliers = epipolar.fit_line(np.stack([dx, dy], 1), 1.0)
  assert slope == pytest.approx(0.05, abs=0.005) and offset == pytest.approx(1.0, abs=0.1)
  assert 150 <= inliers <= 170
  # One depth: no slope to see, the offset alone.
  flat = np.stack([np.full(50, 12.0) + rng.uniform(0, 2, 50), np.full(50, -2.0)], 1)
  assert epipolar.fit_line(flat, 1.0) == (0.0, -2.0, 50)
  assert epipolar.fit_line(np.zeros((1, 2)), 1.0) is None


def _pair(angle: float, offset: float = 0.0):
  """A textured pair at disparities 4-24 px (a ramp across the image), turned by `angle`
  degrees, the left image moved down by `offset` px first."""
  rng = np.random.default_rng(1)
  height, width = 240, 360
  texture = cv2.GaussianBlur(rng.uniform(0, 255, (height, width + 40)).astype(np.float32),
                             (0, 0), 1.5)
  rows, columns = np.mgrid[:height, :width].astype(np.float32)
  disparity = 4 + 20 * columns / width
  left = texture[:, 20:20 + width]
  right = cv2.remap(texture, columns + 20 + disparity, rows, cv2.INTER_LINEAR)
  left = cv2.warpAffine(left, np.float64([[1, 0, 0], [0, 1, offset]]), (width, height),
                        borderMode=cv2.BORDER_REFLECT)
  turn = cv2.getRotationMatrix2D((width / 2, height / 2), angle, 1.0)
  return [cv2.warpAffine(x, turn, (width, height), borderMode=cv2.BORDER_REFLECT)
          for x in (left, right)]


@pytest.mark.parametrize('angle, offset', [(0.0, 0.0), (3.0, 0.0), (-2.0, 1.5)])
def test_a_turned_pair_gives_its_turn_and_offset(angle, offset):
  tilt = epipolar.estimate(*_pair(angle, offset))
  assert tilt.angle == pytest.approx(-angle, abs=0.25) and tilt.matches >= 20
  assert tilt.offset == pytest.approx(offset, abs=0.3)
  assert epipolar.worth_rectifying(tilt) == bool(angle or offset)


def test_rectify_turns_the_eyes_level_and_back_undoes_it():
  left, right = _pair(3.0, 1.5)
  image = np.dstack([left, right, right]).astype(np.uint8)
  tilt = epipolar.estimate(left, right)
  level, back, forth = epipolar.rectify(image, tilt, [1, 2])
  assert level.shape[0] > image.shape[0] and level.shape[1] > image.shape[1]  # Whole.
  again = epipolar.estimate(level[..., 0].astype(np.float32),
                            level[..., 1].astype(np.float32))
  assert abs(again.angle) < 0.25 and abs(again.offset) < 0.3  # Level now.
  inner = (slice(20, -20), slice(20, -20))
  ramp = np.float32(np.arange(360))[None].repeat(240, 0)  # A map of the image's frame.
  there = forth(ramp)
  assert there.shape == level.shape[:2] and np.isnan(there[0, 0])  # A corner: none.
  np.testing.assert_allclose(back(there)[inner], ramp[inner], atol=0.5)
  for channel, right_eye in ((0, False), (1, True)):
    undone = back(level[..., channel], right=right_eye)
    assert undone.shape == image.shape[:2]
    assert np.abs(undone[inner].astype(float) - image[inner][..., channel]).mean() < 4
