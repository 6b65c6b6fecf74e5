"""Tests of unmixing.refiner_stage: what the refiner is fed and how its views settle."""

import numpy as np

from mixstereo_tf.core import image_range
from mixstereo_tf.unmixing import refiner_stage


def test_a_double_image_refiner_is_fed_the_right_view_it_was_trained_on():
  """The classical right layer is now what the mixture leaves of the left one; the shipped
  refiners were trained on the left layer warped by d_R, which the base gives as
  'right_warped' and the network is fed. Its views then settle onto (L + R) / 2 = I."""
  image = np.full((8, 8, 3), 100, np.uint8)
  ones = np.ones((8, 8), np.float32)
  base = {'left': np.full_like(image, 90), 'right': np.full_like(image, 110),
          'right_warped': np.full_like(image, 30), 'disparity_left': ones,
          'disparity_right': ones, 'info': {'mixing_weight': 0.5}}
  seen = []

  def network(skipped):
    del skipped

    def identity(x):  # The base's views and disparities, unchanged.
      seen.append(np.asarray(x))
      return {'left': x[..., 3:6], 'right': x[..., 6:9], 'disparity_left': x[..., 9:10],
              'disparity_right': x[..., 10:11]}
    return identity

  out = refiner_stage.refiner_unmix(network, 1, image, 'diplopia', (1, 4), None, lambda *_: base)
  np.testing.assert_allclose(seen[0][0, ..., 6:9], image_range.u8_to_signed(base['right_warped']))
  # k = 3 at a = 1/2: the residual 100 - (90 + 30) / 2 = 40 goes 1 : 3 to the views.
  assert (out['left'] == 110).all() and (out['right'] == 90).all()
