"""Tests of the prior following the camera (video.motion): the shift's sign and size, the
moved map, refusals, and VideoState handing the moved prior on."""

import cv2
import numpy as np
import pytest
from skimage import data

from mixstereo_tf.video import motion
from mixstereo_tf.video import temporal


def _frames(dx, dy, width=400, height=300):
  """Two crops of a photograph: the second shows at (x, y) what the first showed at
  (x - dx, y - dy)."""
  image = data.astronaut()
  first = image[40:40 + height, 50:50 + width]
  second = image[40 - dy:40 - dy + height, 50 - dx:50 - dx + width]
  return first, second


@pytest.mark.parametrize('dx, dy', [(-8, 0), (5, -3), (0, 0), (-37, 6)])
def test_the_translation_between_two_frames_is_found_with_its_sign(dx, dy):
  first, second = _frames(dx, dy)
  copies = [motion.motion_copy(frame, 200) for frame in (first, second)]
  assert copies[0].shape == (150, 200)  # Area-reduced to 200 px wide: 2 frame px each.
  found = motion.global_shift(*copies, frame_width=400)
  assert found is not None
  assert abs(found[0] - dx) <= 1 and abs(found[1] - dy) <= 1


def test_unrelated_frames_give_no_shift():
  first = motion.motion_copy(data.astronaut()[:256, :256], 256)
  second = motion.motion_copy(data.chelsea()[:256, :256], 256)
  assert motion.global_shift(first, second, 256) is None


@pytest.mark.parametrize('bars, kept', [(None, -8), (0.0, -7)])
def test_black_bars_do_not_pull_the_shift_towards_none(bars, kept):
  """Pillarbox bars' static edges pull a pan of 8 px to 7 when they are kept
  (border_level 0); left out (the default), the pan is found."""
  image = cv2.resize(data.astronaut(), (1400, 800), interpolation=cv2.INTER_CUBIC)
  frames = [image[40:760, 60:1340].copy(), image[40:760, 68:1348].copy()]
  for frame in frames:
    frame[:, :160], frame[:, -160:] = 0, 0
  config = motion.MotionConfig() if bars is None else motion.MotionConfig(border_level=bars)
  copies = [motion.motion_copy(frame, 320) for frame in frames]
  assert motion.global_shift(*copies, frame_width=1280, config=config) == (kept, 0)


def test_a_black_frame_gives_no_shift():
  black = np.zeros((150, 200), np.float32)
  assert motion.global_shift(black, black, 400) is None


def test_the_moved_map_is_the_shifted_values_with_nan_where_nothing_was_seen():
  values = np.arange(12, dtype=np.float32).reshape(3, 4)
  moved = motion.shift_map(values, 1, -1)  # out[y, x] = values[y + 1, x - 1].
  np.testing.assert_array_equal(moved[:2, 1:], values[1:, :3])
  assert np.isnan(moved[:, 0]).all() and np.isnan(moved[2]).all()
  assert np.isnan(motion.shift_map(values, 4, 0)).all()
  np.testing.assert_array_equal(motion.shift_map(values, 0, 0), values)


def test_a_bad_config_is_refused():
  with pytest.raises(ValueError, match='width'):
    motion.MotionConfig(width=4)
  with pytest.raises(ValueError, match='min_response'):
    motion.MotionConfig(min_response=1.0)
  with pytest.raises(ValueError, match='border_level'):
    motion.MotionConfig(border_level=-0.1)


@pytest.mark.parametrize('enabled', [True, False])
def test_video_state_moves_the_prior_with_a_pan(enabled):
  first, second = _frames(-6, 0)
  state = temporal.VideoState(temporal.TemporalConfig(
      motion=motion.MotionConfig(enabled=enabled)))
  state.begin(first)
  disparity = np.tile(np.arange(400, dtype=np.float32), (300, 1))
  state.end({'disparity_left': disparity})
  prior = state.begin(second).prior
  expected = motion.shift_map(disparity, -6, 0) if enabled else disparity
  np.testing.assert_array_equal(prior, expected)


def test_the_copies_are_left_as_they_were():
  """OpenCV's phaseCorrelate windows its inputs in place; a video's copy is compared
  twice (with the frame before and the frame after), so it must come back unchanged."""
  first, second = (motion.motion_copy(frame, 200) for frame in _frames(-8, 0))
  kept = first.copy(), second.copy()
  for _ in range(2):
    assert motion.global_shift(first, second, 400) == (-8, 0)
  np.testing.assert_array_equal(first, kept[0])
  np.testing.assert_array_equal(second, kept[1])


def test_a_sixteen_bit_frame_gives_the_copy_of_its_eight_bit_twin():
  frame = data.astronaut()[:300, :400]
  deep = frame.astype(np.uint16) * 257
  np.testing.assert_allclose(motion.motion_copy(deep, 200), motion.motion_copy(frame, 200),
                             atol=1 / 255)
