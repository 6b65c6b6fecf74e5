"""Image range helpers and the local linear colour transfer of the classical baselines.

`local_linear_transfer` predicts missing colour channels from observed ones with a
guided-filter-style local linear model (He et al. 2013): in every (2r+1)^2 window,
target = A guide + b is fitted by ridge least squares on the training pixels, the
coefficients are averaged over the windows covering a pixel, and applied everywhere.
Windows with few training pixels lean on the global fit: every window's moments are
blended with the image-wide moments as if `prior_count` extra pixels had them.
"""

import cv2
import numpy as np


def to_unit_float(image, name: str = 'mixture') -> np.ndarray:
  """uint8 [H, W, 3] (0..255) or float [H, W, 3] in [0, 1] -> float32 in [0, 1]."""
  image = np.asarray(image)
  if image.ndim != 3 or image.shape[-1] != 3:
    raise ValueError(f'{name} must be an RGB image [H, W, 3], got shape {image.shape}.')
  if image.dtype == np.uint8:
    return image.astype(np.float32) / 255.0
  if not np.issubdtype(image.dtype, np.floating):
    raise ValueError(f'{name} must be uint8 or float in [0, 1], got dtype {image.dtype}.')
  if not np.all(np.isfinite(image)) or image.min() < -1e-3 or image.max() > 1 + 1e-3:
    raise ValueError(f'float {name} must be finite and in [0, 1], got range '
                     f'[{np.nanmin(image)}, {np.nanmax(image)}].')
  return np.clip(image, 0.0, 1.0).astype(np.float32)


def to_uint8(image01: np.ndarray) -> np.ndarray:
  """float in [0, 1] -> uint8 with rounding and clipping."""
  return np.clip(np.rint(np.asarray(image01) * 255.0), 0, 255).astype(np.uint8)


def _box_sum(image: np.ndarray, radius: int) -> np.ndarray:
  size = 2 * radius + 1
  return cv2.boxFilter(image, -1, (size, size), normalize=False,
                       borderType=cv2.BORDER_CONSTANT)


def local_linear_transfer(guide: np.ndarray, target: np.ndarray, train: np.ndarray,
                          radius: int = 7, eps: float = 1e-3,
                          prior_count: float = 10.0) -> np.ndarray:
  """Predicts `target` channels from `guide` channels with a local linear model.

  Args:
    guide: float [H, W, K] observed channels (K = 1 or 2 here), [0, 1].
    target: float [H, W, M] channels to predict; only read where `train`.
    train: bool [H, W], pixels where both guide and target are known.
    radius: window radius, pixels.
    eps: ridge regulariser on the guide covariance (guided filter's epsilon).
    prior_count: weight, in pixels, of the global moments in every window.

  Returns:
    float32 [H, W, M] predictions at every pixel, clipped to [0, 1]. With no training
    pixel at all the prediction is the guide's mean per pixel (a grey estimate).
  """
  guide = np.asarray(guide, np.float64)
  target = np.asarray(target, np.float64)
  h, w, k = guide.shape
  m = target.shape[-1]
  if not train.any():
    return np.repeat(guide.mean(-1, keepdims=True), m, axis=-1).astype(np.float32)
  weight = train.astype(np.float64)
  # Per-pixel products whose window sums give the moments: guide, target, guide guide^T,
  # guide target^T.
  gg = guide[..., :, None] * guide[..., None, :]
  gt = guide[..., :, None] * target[..., None, :]
  features = [weight[..., None] * a.reshape(h, w, -1) for a in (guide, target, gg, gt)]
  stacked = np.concatenate(features, axis=-1)
  global_moments = stacked.reshape(-1, stacked.shape[-1]).sum(0) / weight.sum()
  count = _box_sum(weight, radius)[..., None]
  sums = np.stack([_box_sum(stacked[..., c], radius) for c in range(stacked.shape[-1])], -1)
  moments = (sums + prior_count * global_moments) / (count + prior_count)
  splits = np.cumsum([k, m, k * k])
  mean_g, mean_t, e_gg, e_gt = np.split(moments, splits, axis=-1)
  cov_gg = e_gg.reshape(h, w, k, k) - mean_g[..., :, None] * mean_g[..., None, :]
  cov_gt = e_gt.reshape(h, w, k, m) - mean_g[..., :, None] * mean_t[..., None, :]
  coeff = np.linalg.solve(cov_gg + eps * np.eye(k), cov_gt)  # [H, W, K, M]
  offset = mean_t - np.einsum('hwk,hwkm->hwm', mean_g, coeff)
  # Average the coefficients of all windows covering each pixel, as the guided filter does.
  ones = _box_sum(np.ones((h, w)), radius)[..., None]
  flat = np.concatenate([coeff.reshape(h, w, k * m), offset], axis=-1)
  flat = np.stack([_box_sum(flat[..., c], radius) for c in range(flat.shape[-1])], -1) / ones
  coeff, offset = flat[..., :k * m].reshape(h, w, k, m), flat[..., k * m:]
  prediction = np.einsum('hwk,hwkm->hwm', guide, coeff) + offset
  return np.clip(prediction, 0.0, 1.0).astype(np.float32)
