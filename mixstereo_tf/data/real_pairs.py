"""Real stereo pairs with ground truth as training crops of the matching features (not in
the paper; issue 27's "real pairs at hand", beside the photograph warps of `photo_warps`).

A source (one `--real_pairs` entry) is
  * 'motorcycle': scikit-image's Middlebury 2014 Motorcycle (500 x 741, left ground truth
    where finite);
  * a folder with left.png, right.png and disp_left.pfm (the SceneFlow layout; an
    occ_left.png, when present, marks occluded left pixels non-zero);
  * a folder with left.png, right.png, calib.txt and lidar.bin (a KITTI object frame:
    `kitti_object_frame`, sparse ground truth).
Where no occlusion mask comes with the truth, a left pixel counts as visible unless a valid
pixel to its right lands at or left of its match in the right view (`occluded_left`: the
ordering constraint, which only a nearer surface breaks).

Evaluation data is never training data: `refuse_evaluation_source` refuses the paper's
test scenes and the KITTI 2015 training frames by name. Motorcycle, the project's own
held-out real pair (`middlebury.EVALUATION_SCENES` protects it from the Middlebury
training lists), is allowed here, as are the other sources the project evaluates on, so
that a leave-one-source-out run can train on them: a model trained on a source is judged
only on the sources it left out.
Crops (`crop`) are made like the warps: disparities in [0, 0.8 max] after a random scale,
window-aligned with a given chance; left x matches right x - d.
"""

import os
import re
from typing import Dict

import cv2
import numpy as np

from mixstereo_tf.data import disparity_io
from mixstereo_tf.data import image_io
from mixstereo_tf.data import middlebury
from mixstereo_tf.data import sample
from mixstereo_tf.data import velodyne

MOTORCYCLE = 'motorcycle'
# KITTI 2015 training frames (the paper's test frames), by folder or file name.
_KITTI_2015 = re.compile(r'kitti[_-]?2015|^\d{6}_1[01]$')
# The paper's Middlebury test scenes (Motorcycle allowed: module docstring).
_PAPER_SCENES = frozenset(middlebury.EVALUATION_SCENES) - {MOTORCYCLE}


def refuse_evaluation_source(source: str) -> None:
  """Raises ValueError naming `source` when it looks like evaluation data: a Middlebury
  scene of the paper's tables or a KITTI 2015 frame."""
  name = os.path.basename(os.path.normpath(source)).lower()
  words = set(re.split(r'[^a-z]+', name)) | {middlebury.scene_key(name)}
  if words & _PAPER_SCENES or _KITTI_2015.search(name):
    raise ValueError(f'--real_pairs: {source} looks like evaluation data (the paper\'s '
                     'test scenes, KITTI 2015); evaluation data is never training data.')


def occluded_left(disparity: np.ndarray, valid: np.ndarray) -> np.ndarray:
  """bool [H, W]: valid left pixels x whose match x - d(x) some valid x' > x reaches or
  passes (x' - d(x') <= x - d(x)): hidden in the right view by a nearer surface.

  Args:
    disparity: float [H, W], pixels (left x matches right x - d).
    valid: bool [H, W], where `disparity` is known (sparse truth is fine).
  """
  width = disparity.shape[1]
  match = np.where(valid, np.arange(width)[None, :] - disparity, np.inf)
  # Smallest match among the pixels strictly to the right of each pixel.
  after = np.minimum.accumulate(match[:, ::-1], axis=1)[:, ::-1]
  after = np.concatenate([after[:, 1:], np.full_like(after[:, :1], np.inf)], axis=1)
  return valid & (after <= match)


def kitti_object_frame(folder: str) -> Dict[str, np.ndarray]:
  """The KITTI object frame of `folder` with sparse ground truth: its Velodyne points
  projected into the left colour camera (P2 R0_rect Tr_velo_to_cam), disparity = (P2 - P3)
  translation x / depth, pixels (left x matches right x - d)."""
  calib = velodyne.read_calib_file(os.path.join(folder, 'calib.txt'))
  left = image_io.read_image(os.path.join(folder, 'left.png'))
  pad = lambda m: np.vstack([np.hstack([m, np.zeros((3, 4 - m.shape[1]))]), [0, 0, 0, 1]])
  p2, p3 = (np.reshape(calib[k], (3, 4)) for k in ('P2', 'P3'))
  projection = p2 @ pad(np.reshape(calib['R0_rect'], (3, 3))) @ pad(
      np.reshape(calib['Tr_velo_to_cam'], (3, 4)))
  depth = velodyne.project_velodyne_to_depth(
      velodyne.read_velodyne(os.path.join(folder, 'lidar.bin')), projection, *left.shape[:2])
  valid = depth > 0
  disparity = np.where(valid, (p2[0, 3] - p3[0, 3]) / np.where(valid, depth, 1.0), 0.0)
  return {'left': left, 'right': image_io.read_image(os.path.join(folder, 'right.png')),
          'disparity_left': disparity.astype(np.float32), 'valid_left': valid}


def _folder_pair(folder: str) -> Dict[str, np.ndarray]:
  if os.path.isfile(os.path.join(folder, 'lidar.bin')):
    return kitti_object_frame(folder)
  path = os.path.join(folder, 'disp_left.pfm')
  if not os.path.isfile(path):
    raise ValueError(f'--real_pairs: {folder} has neither disp_left.pfm nor calib.txt and '
                     'lidar.bin (data/real_pairs.py lists the layouts).')
  disparity = disparity_io.read_pfm(path).astype(np.float32)
  pair = {'left': image_io.read_image(os.path.join(folder, 'left.png')),
          'right': image_io.read_image(os.path.join(folder, 'right.png')),
          'disparity_left': disparity, 'valid_left': np.isfinite(disparity) & (disparity > 0)}
  occlusion = os.path.join(folder, 'occ_left.png')
  if os.path.isfile(occlusion):
    pair['nonocc_left'] = pair['valid_left'] & (cv2.imread(occlusion, cv2.IMREAD_UNCHANGED) == 0)
  return pair


def load(source: str) -> Dict[str, np.ndarray]:
  """The pair of one source (module docstring): 'left', 'right' uint8 [H, W, 3],
  'disparity_left' float32 [H, W], 'nonocc_left' bool [H, W] (valid and visible).

  Raises:
    ValueError: an evaluation source, or a folder of no known layout (named).
  """
  refuse_evaluation_source(source)
  if source.lower() == MOTORCYCLE:
    left, right, disparity = sample.motorcycle()  # Unknown = 0.
    pair = {'left': left, 'right': right, 'disparity_left': disparity,
            'valid_left': disparity > 0}
  else:
    pair = _folder_pair(source)
  if 'nonocc_left' not in pair:
    pair['nonocc_left'] = pair['valid_left'] & ~occluded_left(pair['disparity_left'],
                                                              pair['valid_left'])
  del pair['valid_left']
  if not pair['nonocc_left'].any():
    raise ValueError(f'--real_pairs: {source} has no visible pixel with ground truth.')
  pair['disparity_left'] = np.where(pair['nonocc_left'], pair['disparity_left'], 0.0)
  return pair


def crop(rng: np.random.Generator, pair: Dict[str, np.ndarray], height: int, width: int,
         max_disparity: int, window_probability: float) -> Dict[str, np.ndarray]:
  """A training crop of `pair` (`load`), as `photo_warps.warped_pair` returns one.

  The pair is scaled by s drawn log-uniformly in [h / 2, h] with h = min(1, 0.8 max /
  the 99.5th percentile of its disparities), never below the crop size; with p =
  `window_probability` the right view is cut c px further left, c the disparity a share
  U[0, 0.7] up its range, so that disparities become d - c; the crop is centred on a
  random pixel with ground truth.

  Returns:
    'left', 'right' uint8 [height, width, 3], 'disparity_left' float32 (pixels, signed),
    'nonocc_left' bool.
  """
  known = pair['disparity_left'][pair['nonocc_left']]
  low, top = np.percentile(known, [0.5, 99.5])
  rows, cols = pair['disparity_left'].shape
  high = min(1.0, 0.8 * max_disparity / max(top, 1.0))
  scale = max(high * 2.0 ** -rng.uniform(0.0, 1.0), height / rows, (width + 1) / cols)
  size = (int(round(cols * scale)), int(round(rows * scale)))
  left, right = (cv2.resize(pair[k], size, interpolation=cv2.INTER_AREA)
                 for k in ('left', 'right'))
  nearest = lambda a: cv2.resize(a, size, interpolation=cv2.INTER_NEAREST)
  valid = nearest(pair['nonocc_left'].astype(np.uint8)) > 0
  disparity = nearest(pair['disparity_left'] * np.float32(scale))
  shift = 0
  if rng.uniform() < window_probability:
    shift = int(round(scale * (low + rng.uniform(0.0, 0.7) * (top - low))))
  shift = min(max(shift, 0), size[0] - width)
  ys, xs = np.nonzero(valid)
  if len(ys):
    pick = int(rng.integers(len(ys)))
    y, x = ys[pick], xs[pick]
  else:  # Sparse truth lost in the scaling: the centre.
    y, x = size[1] // 2, size[0] // 2
  y0 = int(np.clip(y - height // 2, 0, size[1] - height))
  x0 = int(np.clip(x - width // 2, shift, size[0] - width))
  window = (slice(y0, y0 + height), slice(x0, x0 + width))
  return {'left': left[window], 'right': right[y0:y0 + height, x0 - shift:x0 - shift + width],
          'disparity_left': (disparity[window] - shift).astype(np.float32),
          'nonocc_left': valid[window]}
