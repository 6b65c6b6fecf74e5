"""Local linear colour transfer: a view's colours predicted from the channels it kept.

Where an anaglyph's views do not match (occlusions, the image border), neither the mixture
nor the other view fixes the channels a view lost; `views` then leans on a prior
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


def _averaged_coefficients(guide, target, weight, radius, eps, prior_count):
  """([[a_ij]], [b_j]): the ridge fits of every window (moments from `weight`-weighted
  pixels blended with the image-wide ones), averaged over the windows covering each
  pixel: float32 [H, W] maps, a indexed [guide channel][target channel]."""
  k, m = guide.shape[-1], target.shape[-1]
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
  offsets = [_box(t[j] - sum(g[i] * coeff[i][j] for i in range(k)), radius) / windows
             for j in range(m)]
  return [[_box(c, radius) / windows for c in row] for row in coeff], offsets


def _apply(guide: np.ndarray, coeff, offsets) -> np.ndarray:
  """float32 [H, W, M] = offsets[j] + sum_i coeff[i][j] guide[..., i], clipped to [0, 1]."""
  out = np.empty(guide.shape[:2] + (len(offsets),), np.float32)
  for j, offset in enumerate(offsets):
    out[..., j] = offset + sum(guide[..., i] * coeff[i][j] for i in range(guide.shape[-1]))
  return np.clip(out, np.float32(0.0), np.float32(1.0), out=out)


def _area(image: np.ndarray, size) -> np.ndarray:
  """Area-downsampled [h, w, C] copy of [H, W, C]."""
  out = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
  return out.reshape(size[::-1] + image.shape[2:])


def apply_reduced_fit(guide: np.ndarray, small_guide: np.ndarray, small_target: np.ndarray,
                      small_train: np.ndarray, radius: int, eps: float = 1e-3,
                      prior_count: float = 10.0) -> np.ndarray:
  """The local linear model fitted on reduced copies, applied to the full-size guide.

  The fits (`local_linear_transfer`'s, window radius `radius` at the reduced size) and
  their window averages are computed on `small_guide` [h, w, K], `small_target` [h, w, M]
  and `small_train` [h, w] (float weights in [0, 1] or bool); the averaged coefficients
  are upsampled bilinearly and applied to `guide` [H, W, K] (He and Sun 2015's fast
  guided filter). Returns float32 [H, W, M] in [0, 1]; with no training weight, the
  guide's mean per pixel.
  """
  guide = np.asarray(guide, np.float32)
  weight = np.asarray(small_train, np.float32)
  m = small_target.shape[-1]
  if not weight.any():
    return np.repeat(guide.mean(-1, keepdims=True), m, axis=-1)
  coeff, offsets = _averaged_coefficients(np.asarray(small_guide, np.float32),
                                          np.asarray(small_target, np.float32), weight,
                                          radius, eps, prior_count)
  height, width = guide.shape[:2]
  full = lambda x: cv2.resize(x, (width, height), interpolation=cv2.INTER_LINEAR)
  return _apply(guide, [[full(c) for c in row] for row in coeff], [full(b) for b in offsets])


def reduced_size(height: int, width: int, factor: int):
  """(width, height) of a copy reduced `factor` times (OpenCV's order), at least 1."""
  return max(1, round(width / factor)), max(1, round(height / factor))


def local_linear_transfer(guide: np.ndarray, target: np.ndarray, train: np.ndarray,
                          radius: int = 7, eps: float = 1e-3,
                          prior_count: float = 10.0, subsample: int = 1) -> np.ndarray:
  """Predicts `target` from `guide` with a guided-filter-style local linear model.

  In every (2r + 1)^2 window, target = a . guide + b is fitted by ridge least squares on
  the `train` pixels (He et al. 2013); every window's moments are blended with the
  image-wide ones as if `prior_count` extra pixels had them (windows with few training
  pixels lean on the global fit); coefficients are averaged over the windows covering a
  pixel and applied everywhere. With `subsample` s > 1 the fits and their averages are
  computed on copies area-reduced s times (radius r / s; the target averaged over its
  training pixels) and the averaged coefficients upsampled bilinearly before they are
  applied to the full-size guide (He and Sun 2015's fast guided filter): about 1 / s^2 of
  the work.

  Args:
    guide: float [H, W, K], K = 1 or 2, [0, 1].
    target: float [H, W, M]; read only where `train`.
    train: bool [H, W].
    radius, eps, prior_count: window radius (pixels), ridge, global-moment weight.
    subsample: the reduction factor s of the fits (1: exact).

  Returns:
    float32 [H, W, M] in [0, 1]; with no training pixel, the guide's mean per pixel.
  """
  guide, target = np.asarray(guide, np.float32), np.asarray(target, np.float32)
  k, m = guide.shape[-1], target.shape[-1]
  if k not in (1, 2):
    raise ValueError(f'local_linear_transfer takes 1 or 2 guide channels, got {k}.')
  if subsample < 1:
    raise ValueError(f'local_linear_transfer needs subsample >= 1, got {subsample}.')
  if not train.any():
    return np.repeat(guide.mean(-1, keepdims=True), m, axis=-1)
  weight = train.astype(np.float32)
  if subsample == 1:
    return _apply(guide, *_averaged_coefficients(guide, target, weight, radius, eps,
                                                 prior_count))
  size = reduced_size(*weight.shape, subsample)
  small_weight = _area(weight, size)
  small_target = _area(target * weight[..., None], size) / np.maximum(
      small_weight, 1e-6)[..., None]
  return apply_reduced_fit(guide, _area(guide, size), small_target, small_weight,
                           max(1, round(radius / subsample)), eps, prior_count)
