"""A file-backed stereo sample (`records.StereoSample`) loaded into arrays: views, ground
truth and masks checked against each other, optionally shrunk to fit a disparity range.
"""

from typing import Dict, Optional, Tuple

import numpy as np

from mixstereo_tf.data import disparity_io
from mixstereo_tf.data import image_io
from mixstereo_tf.data import records


def _check_shape(array: np.ndarray, shape: Tuple[int, int], path: str, what: str) -> None:
  if array.shape[:2] != shape:
    raise ValueError(f'{what} {path} is {array.shape[1]}x{array.shape[0]} but the left '
                     f'image is {shape[1]}x{shape[0]}')


def _read_gt(path: Optional[str], scale: float,
             shape: Tuple[int, int]) -> Tuple[np.ndarray, np.ndarray]:
  if path is None:
    return np.zeros(shape, np.float32), np.zeros(shape, bool)
  disparity, valid = disparity_io.read_disparity(path, scale)
  _check_shape(disparity, shape, path, 'disparity')
  return disparity, valid


def _read_optional_mask(path: Optional[str], shape: Tuple[int, int]) -> np.ndarray:
  if path is None:
    return np.ones(shape, bool)
  mask = disparity_io.read_mask(path)
  _check_shape(mask, shape, path, 'mask')
  return mask


def _load(sample: records.StereoSample) -> Dict[str, np.ndarray]:
  left_path, right_path = image_io.find_image(sample.left), image_io.find_image(sample.right)
  left, right = image_io.read_image(left_path), image_io.read_image(right_path)
  if left.shape != right.shape:
    raise ValueError(f'left {left_path} is {left.shape[1]}x{left.shape[0]} but right '
                     f'{right_path} is {right.shape[1]}x{right.shape[0]}')
  shape = left.shape[:2]
  disparity_left, valid_left = _read_gt(sample.disparity_left, sample.disparity_scale, shape)
  disparity_right, valid_right = _read_gt(sample.disparity_right, sample.disparity_scale,
                                          shape)
  valid_left &= _read_optional_mask(sample.all_left, shape)
  nonocc_left = valid_left & _read_optional_mask(sample.nonocc_left, shape)
  # Unlike the other masks, a missing discontinuity mask selects no pixel: treating every
  # pixel as 'near a discontinuity' would make a disc column repeat the all-pixel one.
  disc_left = (valid_left & _read_optional_mask(sample.disc_left, shape)
               if sample.disc_left else np.zeros(shape, bool))
  disparity_left = np.where(valid_left, disparity_left, 0).astype(np.float32)
  return {
      'left': left,
      'right': right,
      'disparity_left': disparity_left,
      'disparity_right': disparity_right,
      'valid_left': valid_left,
      'valid_right': valid_right,
      'nonocc_left': nonocc_left,
      'disc_left': disc_left,
  }


def fit_factor(largest: float, max_disparity: int) -> int:
  """The smallest integer k >= 1 with largest / k <= max_disparity - 1."""
  if max_disparity < 2:
    raise ValueError(f'fit_disparity must be >= 2, got {max_disparity}.')
  return max(1, int(np.ceil(largest / (max_disparity - 1.0))))


def _block(array: np.ndarray, factor: int, reduce) -> np.ndarray:
  """`reduce` over k x k blocks of [H, W, ...] (the last H % k rows, W % k columns go)."""
  h, w = array.shape[0] // factor, array.shape[1] // factor
  blocks = array[:h * factor, :w * factor].reshape(h, factor, w, factor, *array.shape[2:])
  return reduce(blocks, axis=(1, 3))


def shrink(loaded: Dict[str, np.ndarray], factor: int) -> Dict[str, np.ndarray]:
  """A loaded pair `factor` times smaller: views by k x k means; ground truth / k where the
  whole block is known (else 0, unknown); masks true where the whole block is."""
  if factor == 1:
    return loaded
  out = {key: np.rint(_block(loaded[key], factor, np.mean)).astype(np.uint8)
         for key in ('left', 'right')}
  for view in ('left', 'right'):
    valid = _block(loaded[f'valid_{view}'], factor, np.all)
    mean = _block(loaded[f'disparity_{view}'].astype(np.float64), factor, np.mean)
    out[f'valid_{view}'] = valid
    out[f'disparity_{view}'] = np.where(valid, mean / factor, 0).astype(np.float32)
  out['nonocc_left'] = _block(loaded['nonocc_left'], factor, np.all) & out['valid_left']
  out['disc_left'] = _block(loaded['disc_left'], factor, np.any) & out['valid_left']
  return out


def load_file_sample(sample: records.StereoSample) -> Dict[str, np.ndarray]:
  """Loads a file-backed sample into arrays with exactly the keys of `records.LOADED_KEYS`.

  valid_left = GT known AND inside `all_left` (when given); nonocc_left = valid_left AND
  `nonocc_left` (when given), else valid_left; disc_left = valid_left AND `disc_left` (when
  given), else all False. Disparity outside the validity masks is 0. With
  `sample.fit_disparity`, the pair is then shrunk to fit that many levels (`shrink`).
  Missing ground truth gives zero disparity and all-False masks. Image paths go through
  `find_image`, so a .jpg entry also finds a .png file.

  Raises:
    ValueError: a file is missing or unreadable, or sizes differ; the message names the
      file(s) and `sample.source`.
  """
  try:
    loaded = _load(sample)
    if sample.fit_disparity:
      largest = max(float(loaded['disparity_left'].max()),
                    float(loaded['disparity_right'].max()))
      loaded = shrink(loaded, fit_factor(largest, sample.fit_disparity))
    return loaded
  except ValueError as e:
    raise ValueError(f'{sample.source or sample.name}: {e}') from None
