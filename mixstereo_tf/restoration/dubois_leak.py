"""The Dubois encodings' leak of one eye into the other eye's channels (`detection` step 3).

Dubois matrices are least-squares fits, so each eye's channels carry a little of the other
eye (red-cyan: the mixture's G gets -0.094 of the left view). Regressing the high-passed
other channels at a right pixel on the high-passed odd channel at the matching left pixel
and at the same pixel, the second coefficient is that leak: `observed` measures it in an
image, `expected` reads it from an encoding's matrices (0 for colour, gray, half-colour
and optimized encodings).
"""

from typing import Tuple

import cv2
import numpy as np

from mixstereo_tf.core import mixtures


def observed(small: np.ndarray, odd: int, matched: Tuple[np.ndarray, ...], sigma: float,
             correlation: float, min_shift: int, collinearity: float) -> np.ndarray:
  """[2]: per other channel, the leak of the odd channel's eye into it; ~0 without one.

  Args:
    small: float [h, w, 3] image on 0..255.
    odd: the channel of the eye that owns one channel alone.
    matched: (ys, xs, xr) int arrays: the odd channel's pixel (ys, xs) sees the surface
      the other channels see at (ys, xr).
    sigma: the Gaussian high-pass's sigma, pixels.
    correlation, min_shift: only pixels whose high-passed odd and other channels agree
      over 7x7 (normalised correlation >= `correlation`) and lie >= `min_shift` px apart
      count ...
    collinearity: ... and where the two regressors (the odd channel at the matching and at
      the same pixel) correlate over 7x7 by less than this in magnitude: where they repeat
      each other (horizontal edges, smooth texture seen a few pixels apart), the second
      absorbs whatever the first leaves unexplained of the other channels' colour.
  """
  high = small / 255.0 - cv2.GaussianBlur(small / 255.0, (0, 0), sigma)
  others = [c for c in range(3) if c != odd]
  ys, xs, xr = matched
  odd_map, other_map, same_map = (np.zeros(small.shape[:2], np.float32) for _ in range(3))
  odd_map[ys, xs] = high[ys, xs, odd]
  other_map[ys, xs] = high[ys, xr][:, others].mean(axis=1)
  same_map[ys, xs] = high[ys, xr, odd]
  box = lambda image: cv2.boxFilter(image, -1, (7, 7), normalize=False)
  local_correlation = lambda a, b: (box(a * b) / np.sqrt(box(a ** 2) * box(b ** 2) + 1e-12)
                                    )[ys, xs]
  keep = ((local_correlation(odd_map, other_map) >= correlation) &
          (np.abs(local_correlation(odd_map, same_map)) < collinearity) &
          (np.abs(xs - xr) >= min_shift))
  ys, xs, xr = ys[keep], xs[keep], xr[keep]
  if ys.size < 50:
    return np.zeros(2)
  regressors = np.stack([high[ys, xs, odd], high[ys, xr, odd]], axis=1)
  return np.array([np.linalg.lstsq(regressors, high[ys, xr, c], rcond=None)[0][1]
                   for c in others])


def expected(name: str, odd: int) -> np.ndarray:
  """[2]: an encoding's leak of the odd channel's eye into the other channels, relative to
  the odd channel (row sums of that eye's matrix; zero for all but Dubois)."""
  spec = mixtures.get_mixture(name)
  left, right = np.asarray(spec.left_matrix), np.asarray(spec.right_matrix)
  eye = left if np.abs(left[odd]).sum() > np.abs(right[odd]).sum() else right
  return np.array([eye[c].sum() / eye[odd].sum() for c in range(3) if c != odd])
