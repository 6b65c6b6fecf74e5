"""The Dubois leak read from the matrices (measured in images: detection_test)."""

import numpy as np

from mixstereo_tf.core import mixtures
from mixstereo_tf.restoration import dubois_leak
from mixstereo_tf.unmixing import detection


def test_expected_leak_is_the_odd_eyes_row_sums():
  # Red-cyan Dubois: G gets (-0.040 - 0.038 - 0.016) of the left view, R (0.456 + 0.500 +
  # 0.176); B gets (-0.015 - 0.021 - 0.005).
  spec = mixtures.get_mixture('dubois_ffmpeg')
  left = np.asarray(spec.left_matrix)
  np.testing.assert_allclose(dubois_leak.expected('dubois_ffmpeg', 0),
                             [left[1].sum() / left[0].sum(), left[2].sum() / left[0].sum()])
  assert -0.09 < dubois_leak.expected('dubois_ffmpeg', 0)[0] < -0.07
  for name in ('anaglyph', 'half_color', 'gray', 'green_magenta', 'amber_blue_half'):
    odd = detection.FAMILY_ODD_CHANNEL[mixtures.get_mixture(name).family]
    np.testing.assert_array_equal(dubois_leak.expected(name, odd), [0.0, 0.0])
