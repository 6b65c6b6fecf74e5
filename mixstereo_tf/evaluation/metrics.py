"""Evaluation metrics: PSNR, disparity error rates and Eigen-split depth metrics.

Pure NumPy functions. Conventions (docs/DESIGN.md): disparities are in pixels, positive;
ground truth 0 means unknown. Every function evaluates ONE image; dataset numbers are the
mean of per-image values (the paper averages PSNR and D1-all over the 200 KITTI images;
monodepth averages depth metrics over images), see `MeanOf` / `Accumulator`.

Error rates are fractions in [0, 1]; the paper prints them in percent.
"""

import math
from typing import Dict, Iterable, Mapping, Optional

import cv2
import numpy as np

# The KITTI stereo rig's baseline; the focal length comes from each frame's calibration
# (`velodyne.rectified_focal_length`), since the raw drives differ in it and in image width.
KITTI_BASELINE_M = 0.54

# Crop fractions (top, bottom, left, right) of the image height / width.
_CROPS = {
    'garg': (0.40810811, 0.99189189, 0.03594771, 0.96405229),
    'eigen': (0.3324324, 0.91351351, 0.03594771, 0.96405229),
}


def psnr(pred_u8, gt_u8, mask=None, max_db: Optional[float] = 100.0) -> float:
  """Peak signal-to-noise ratio on the 8-bit scale, 10 log10(255² / MSE), in dB.

  Args:
    pred_u8: [H, W, C] (or [H, W]) uint8 (`image_range.signed_to_u8` quantises network
      views like published result images), or float values on the [0, 255] scale.
    gt_u8: same shape.
    mask: optional bool/0-1 [H, W]; the MSE averages over masked pixels and all channels.
    max_db: cap on the result. Identical images have infinite PSNR, which would dominate
      a mean over images; the default caps at 100 dB (MSE below 255² · 1e-10). None
      disables the cap (identical images then give `math.inf`).

  Returns:
    PSNR in dB; NaN when the mask selects no pixel.
  """
  pred = np.asarray(pred_u8, dtype=np.float64)
  gt = np.asarray(gt_u8, dtype=np.float64)
  _check_shapes(pred=pred, gt=gt)
  squared = (pred - gt) ** 2
  if mask is not None:
    mask = np.asarray(mask).astype(bool)
    if mask.shape != gt.shape[:mask.ndim] or mask.ndim not in (2, gt.ndim):
      raise ValueError(f'mask shape {mask.shape} does not match image shape {gt.shape}.')
    squared = squared[mask]
  if squared.size == 0:
    return math.nan
  mse = float(np.mean(squared))
  value = math.inf if mse == 0 else 10.0 * math.log10(255.0 ** 2 / mse)
  return value if max_db is None else min(value, float(max_db))


def view_difference_agreement(left, right, true_left, true_right) -> float:
  """Cosine between the difference of two restored views and that of the true views,
  <L' - R', L - R> / (|L' - R'| |L - R|), over every pixel and channel: > 0 where the
  eyes are in order, < 0 where they are swapped (the difference flips sign). Unlike
  comparing L' with L and with R, it does not count a weak separation of an unequal mix
  I = a L + (1 - a) R as swapped: there both views stay near the mixture, which is
  nearer to the heavier eye, but their small difference still points one way.

  Args:
    left, right, true_left, true_right: [H, W, C] (or [H, W]) on one scale (e.g. uint8).

  Returns:
    A value in [-1, 1]; NaN when either difference is zero everywhere.
  """
  views = [np.asarray(v, dtype=np.float64) for v in (left, right, true_left, true_right)]
  _check_shapes(left=views[0], right=views[1], true_left=views[2], true_right=views[3])
  ours, truth = (views[0] - views[1]).ravel(), (views[2] - views[3]).ravel()
  norm = float(np.linalg.norm(ours) * np.linalg.norm(truth))
  return float(np.dot(ours, truth) / norm) if norm > 0 else float('nan')


def _check_shapes(**arrays: np.ndarray) -> None:
  shapes = {name: np.shape(a) for name, a in arrays.items()}
  if len(set(shapes.values())) != 1:
    raise ValueError('Shape mismatch: ' + ', '.join(f'{k} {v}' for k, v in shapes.items()))


def _disparity_errors(pred, gt, valid):
  """|pred - gt| and gt at the evaluated pixels: valid, finite GT > 0 (GT 0 = unknown)."""
  pred = np.asarray(pred, dtype=np.float64)
  gt = np.asarray(gt, dtype=np.float64)
  valid = np.asarray(valid)
  _check_shapes(pred=pred, gt=gt, valid=valid)
  selected = valid.astype(bool) & np.isfinite(gt) & (gt > 0)
  # A NaN prediction gets an infinite error, so it counts as bad rather than vanishing.
  error = np.abs(pred[selected] - gt[selected])
  return np.where(np.isnan(error), np.inf, error), gt[selected]


def d1_error(pred, gt, valid) -> float:
  """KITTI 2015 D1: fraction of pixels with |d - gt| > 3 px AND |d - gt| / gt > 5 %.

  Both inequalities are strict, as in the official devkit.

  Args:
    pred: predicted disparity, pixels, any shape ([H, W] or [H, W, 1]).
    gt: ground-truth disparity, same shape; 0 (or non-finite) = unknown, never evaluated.
    valid: bool or 0/1 mask, same shape.

  Returns:
    Bad fraction in [0, 1] over evaluated pixels; NaN when there are none.
  """
  error, gt_values = _disparity_errors(pred, gt, valid)
  if error.size == 0:
    return math.nan
  bad = (error > 3.0) & (error / gt_values > 0.05)
  return float(np.mean(bad))


def bad_pixel_rate(pred, gt, valid, threshold: float) -> float:
  """Fraction of evaluated pixels with |d - gt| > threshold px (strict); NaN if none.

  Shapes and masking as in `d1_error`.
  """
  error, _ = _disparity_errors(pred, gt, valid)
  return math.nan if error.size == 0 else float(np.mean(error > threshold))


def end_point_error(pred, gt, valid) -> float:
  """Mean |d - gt| in pixels over evaluated pixels; NaN if none. Shapes as in `d1_error`."""
  error, _ = _disparity_errors(pred, gt, valid)
  return math.nan if error.size == 0 else float(np.mean(error))


def middlebury_bad(pred, gt, masks: Optional[Mapping[str, np.ndarray]] = None,
                   threshold: float = 1.0) -> Dict[str, float]:
  """Middlebury bad-1: `bad_pixel_rate` at `threshold` px over each region mask.

  The readers already divide the Middlebury GT by its scale factor, so `gt` is in pixels
  and the paper's 1 px threshold applies directly.

  Args:
    pred, gt: disparity in pixels, same shape.
    masks: {region name: mask}, e.g. {'all': valid_left, 'nonocc': nonocc_left}; when None
      or empty, the region 'valid' = every pixel with known GT.
    threshold: pixels.

  Returns:
    {region name: bad fraction (NaN for an empty region)}.
  """
  if not masks:
    masks = {'valid': np.ones(np.shape(gt), dtype=bool)}
  return {name: bad_pixel_rate(pred, gt, mask, threshold) for name, mask in masks.items()}


def disparity_to_depth(disparity_px, focal_px: float,
                       baseline_m: float = KITTI_BASELINE_M) -> np.ndarray:
  """Depth in metres = focal_px · baseline_m / disparity_px; disparity <= 0 gives inf.

  Infinite depth is clamped to the maximum depth by `depth_metrics`.
  """
  disparity = np.asarray(disparity_px, dtype=np.float64)
  depth = np.full(disparity.shape, np.inf)
  positive = disparity > 0
  depth[positive] = focal_px * baseline_m / disparity[positive]
  return depth


def resize_disparity(disparity_px, height: int, width: int) -> np.ndarray:
  """Bilinearly resizes an [h, w] disparity map to [height, width], in target pixels.

  Values are multiplied by width / w, because a disparity is a horizontal distance (as
  monodepth's evaluation does when it resizes predictions to the ground-truth size).
  """
  disparity = np.asarray(disparity_px, dtype=np.float32)
  if disparity.ndim != 2:
    raise ValueError(f'disparity must be [H, W], got shape {disparity.shape}.')
  resized = cv2.resize(disparity, (width, height), interpolation=cv2.INTER_LINEAR)
  return resized.astype(np.float64) * (width / disparity.shape[1])


def prediction_to_kitti_depth(disparity_px, height: int, width: int, focal_px: float,
                              baseline_m: float = KITTI_BASELINE_M) -> np.ndarray:
  """A predicted [h, w] disparity as depth in metres at the [height, width] GT size.

  Args:
    disparity_px: [h, w] pixels of the prediction's size.
    height, width: ground-truth size.
    focal_px: focal length in pixels at the ground-truth size (KITTI raw: P_rect_02[0, 0]
      of the drive's calib_cam_to_cam.txt).
    baseline_m: stereo baseline in metres.
  """
  return disparity_to_depth(resize_disparity(disparity_px, height, width), focal_px,
                            baseline_m)


def eigen_crop_mask(height: int, width: int, crop: Optional[str] = 'garg') -> np.ndarray:
  """Bool [height, width] mask of the evaluated region on the Eigen split.

  'garg': rows [0.40810811 H, 0.99189189 H), cols [0.03594771 W, 0.96405229 W);
  'eigen': rows [0.3324324 H, 0.91351351 H), same cols; None: the whole image. Bounds are
  truncated to integers (int32 cast of the products, as monodepth does) and used as
  half-open slices.
  """
  mask = np.zeros((height, width), dtype=bool)
  if crop is None:
    mask[:] = True
    return mask
  if crop not in _CROPS:
    raise ValueError(f'Unknown crop {crop!r}; expected one of {sorted(_CROPS)} or None.')
  top, bottom, left, right = _CROPS[crop]
  bounds = np.array([top * height, bottom * height, left * width, right * width])
  y0, y1, x0, x1 = bounds.astype(np.int32)
  mask[y0:y1, x0:x1] = True
  return mask


DEPTH_METRIC_NAMES = ('abs_rel', 'sq_rel', 'rmse', 'rmse_log', 'a1', 'a2', 'a3')


def depth_metrics(pred_depth, gt_depth, min_depth: float = 1e-3, max_depth: float = 80.0,
                  crop: Optional[str] = 'garg') -> Dict[str, float]:
  """Eigen et al. depth metrics of one image.

  Evaluated pixels: min_depth < gt < max_depth and inside `eigen_crop_mask(crop)`. The
  prediction is clamped to [min_depth, max_depth] first (NaN counts as max_depth).
    abs_rel = mean(|d - g| / g); sq_rel = mean((d - g)² / g); rmse = sqrt(mean((d - g)²));
    rmse_log = sqrt(mean((ln d - ln g)²)); a_k = fraction of max(d / g, g / d) < 1.25^k.

  Args:
    pred_depth: [H, W] metres (resize predictions to the GT size first).
    gt_depth: [H, W] metres, 0 = no measurement.
    min_depth, max_depth: metres.
    crop: 'garg', 'eigen' or None.

  Returns:
    {name: value} for `DEPTH_METRIC_NAMES`; all NaN when no pixel is evaluated.
  """
  pred = np.asarray(pred_depth, dtype=np.float64)
  gt = np.asarray(gt_depth, dtype=np.float64)
  _check_shapes(pred_depth=pred, gt_depth=gt)
  if gt.ndim != 2:
    raise ValueError(f'depth maps must be [H, W], got shape {gt.shape}.')
  selected = (gt > min_depth) & (gt < max_depth) & eigen_crop_mask(*gt.shape, crop)
  if not selected.any():
    return {name: math.nan for name in DEPTH_METRIC_NAMES}
  g = gt[selected]
  d = np.clip(np.nan_to_num(pred[selected], nan=max_depth), min_depth, max_depth)
  ratio = np.maximum(d / g, g / d)
  return {
      'abs_rel': float(np.mean(np.abs(d - g) / g)),
      'sq_rel': float(np.mean((d - g) ** 2 / g)),
      'rmse': float(np.sqrt(np.mean((d - g) ** 2))),
      'rmse_log': float(np.sqrt(np.mean((np.log(d) - np.log(g)) ** 2))),
      'a1': float(np.mean(ratio < 1.25)),
      'a2': float(np.mean(ratio < 1.25 ** 2)),
      'a3': float(np.mean(ratio < 1.25 ** 3)),
  }


class MeanOf:
  """Running mean of per-image values; NaN values (nothing evaluated) are counted apart."""

  def __init__(self):
    self._total = 0.0
    self.count = 0
    self.nan_count = 0

  def add(self, value: float) -> None:
    value = float(value)
    if math.isnan(value):
      self.nan_count += 1
    else:
      self._total += value
      self.count += 1

  @property
  def mean(self) -> float:
    """Mean of the non-NaN values; NaN before any was added."""
    return self._total / self.count if self.count else math.nan


class Accumulator:
  """Named `MeanOf`s: `add({'d1_all': 0.05, ...})` per image, then `means()`."""

  def __init__(self, names: Iterable[str] = ()):
    self._means = {name: MeanOf() for name in names}

  def add(self, values: Mapping[str, float]) -> None:
    for name, value in values.items():
      self._means.setdefault(name, MeanOf()).add(value)

  def means(self) -> Dict[str, float]:
    return {name: m.mean for name, m in self._means.items()}

  def counts(self) -> Dict[str, int]:
    """Number of non-NaN values per name."""
    return {name: m.count for name, m in self._means.items()}
