"""Planning copies: frames copied as before, panoramas as rows of 4 : 1 frames."""

import numpy as np

from mixstereo_tf.core import planning_copies


def test_images_up_to_4_to_1_are_copied_as_before():
  """The size every planning copy had before: `width` px wide, the height rounded."""
  for height in range(80, 1200, 7):
    for full in range(321, 4 * height + 1, 13):
      assert planning_copies.frame_width((height, full)) == full
      assert planning_copies.copy_size((height, full, 3), 320) == (
          320, max(1, round(height * 320 / full))), (height, full)
  assert planning_copies.copy_size((375, 1242), 2000) == (1242, 375)  # Narrower: as it is.
  assert planning_copies.reach((96, 320), 1 / 3) == 107


def test_a_panorama_is_a_row_of_frames():
  # 24 : 1: frames 512 px wide, each copied 320 px wide; the search reaches a frame's third.
  assert planning_copies.frame_width((128, 3072)) == 512
  assert planning_copies.copy_size((128, 3072), 320) == (1920, 80)
  assert planning_copies.reach((80, 1920), 1 / 3) == 107
  assert planning_copies.copy_size((60, 1242), 320) == (1242, 60)  # A frame of 240 px.


def test_area_copy_averages_and_leaves_small_images_alone():
  image = np.arange(8 * 64, dtype=np.float32).reshape(8, 64)
  assert planning_copies.area_copy(image, 32) is image  # Frame width 32: nothing reduced.
  halved = planning_copies.area_copy(image, 16)
  np.testing.assert_allclose(halved, image.reshape(4, 2, 32, 2).mean(axis=(1, 3)))
