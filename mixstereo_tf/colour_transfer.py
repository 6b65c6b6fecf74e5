"""Local linear colour transfer: a view's colours predicted from the channels it kept.

Where an anaglyph's views do not match (occlusions, the image border), neither the mixture
nor the other view fixes the channels a view lost; `restoration` then leans on a prior
predicted from the channels the view kept in the mixture (its "eye channels") by a
guided-filter-style local linear model (He et al. 2013), fitted where the views do match.
Box filters (OpenCV) make the work per pixel independent of the window radius.
"""

import cv2
import numpy as np


def _box(image: np.ndarray, radius: int) -> np.ndarray:
  size = 2 * radius + 1
  return cv2.boxFilter(image, -1, (size, size), normalize=False,
                       borderType=cv2.BORDER_CONSTANT)


def local_linear_transfer(guide: np.ndarray, target: np.ndarray, train: np.ndarray,
                          radius: int = 7, eps: float = 1e-3,
                          prior_count: float = 10.0) -> np.ndarray:
  """Predicts `target` from `guide` with a guided-filter-style local linear model.

  In every (2r + 1)^2 window, target = a . guide + b is fitted by ridge least squares on
  the `train` pixels (He et al. 2013); every window's moments are blended with the
  image-wide ones as if `prior_count` extra pixels had them (windows with few training
  pixels lean on the global fit); coefficients are averaged over the windows covering a
  pixel and applied everywhere.

  Args:
    guide: float [H, W, K], K = 1 or 2, [0, 1].
    target: float [H, W, M]; read only where `train`.
    train: bool [H, W].
    radius, eps, prior_count: window radius (pixels), ridge, global-moment weight.

  Returns:
    float32 [H, W, M] in [0, 1]; with no training pixel, the guide's mean per pixel.
  """
  guide, target = np.asarray(guide, np.float32), np.asarray(target, np.float32)
  k, m = guide.shape[-1], target.shape[-1]
  if k not in (1, 2):
    raise ValueError(f'local_linear_transfer takes 1 or 2 guide channels, got {k}.')
  if not train.any():
    return np.repeat(guide.mean(-1, keepdims=True), m, axis=-1)
  weight = train.astype(np.float32)
  count, total = _box(weight, radius), float(weight.sum())

  def moment(feature):
    weighted = feature * weight
    image_mean = float(weighted.sum(dtype=np.float64) / total)
    return (_box(weighted, radius) + prior_count * image_mean) / (count + prior_count)

  g = [moment(guide[..., i]) for i in range(k)]
  t = [moment(target[..., j]) for j in range(m)]
  var = [[moment(guide[..., i] * guide[..., j]) - g[i] * g[j] + (eps if i == j else 0.0)
          for j in range(k)] for i in range(k)]
  cov = [[moment(guide[..., i] * target[..., j]) - g[i] * t[j] for j in range(m)]
         for i in range(k)]
  if k == 1:
    coeff = [[cov[0][j] / var[0][0] for j in range(m)]]
  else:
    det = var[0][0] * var[1][1] - var[0][1] * var[0][1]
    coeff = [[(var[1][1] * cov[0][j] - var[0][1] * cov[1][j]) / det for j in range(m)],
             [(var[0][0] * cov[1][j] - var[0][1] * cov[0][j]) / det for j in range(m)]]
  windows = _box(np.ones(weight.shape, np.float32), radius)
  out = np.empty(target.shape[:2] + (m,), np.float32)
  for j in range(m):
    offset = t[j] - sum(g[i] * coeff[i][j] for i in range(k))
    out[..., j] = _box(offset, radius) / windows + sum(
        guide[..., i] * (_box(coeff[i][j], radius) / windows) for i in range(k))
  return np.clip(out, 0.0, 1.0)
