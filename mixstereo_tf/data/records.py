"""The stereo sample record every dataset reader returns, and its loader.

A reader (KITTI, Middlebury, the embedded `sample` source) turns a dataset root or a split
list into a list of `StereoSample`s; `sources.load_sample` turns one into NumPy arrays with
the keys of `LOADED_KEYS`. File-backed samples hold paths; samples of the embedded source
hold virtual URIs (`synthetic://...`, `skimage://motorcycle`) that
`mixstereo_tf.data.sample` renders on demand.
"""

import dataclasses
from typing import Mapping, Optional

import numpy as np

VIRTUAL_SCHEMES = ('synthetic://', 'skimage://')


@dataclasses.dataclass(frozen=True)
class StereoSample:
  """One stereo pair and its optional ground truth.

  Attributes:
    name: a short unique name (scene or frame id) used in tables and output files.
    left: path (or virtual URI) of the left image.
    right: path (or virtual URI) of the right image.
    disparity_left: optional path of the left ground-truth disparity.
    disparity_right: optional path of the right ground-truth disparity.
    disparity_scale: stored value / disparity_scale = pixels (KITTI 256, Tsukuba 16, ...).
    nonocc_left: optional path of a non-occluded mask for the left view (white = evaluated).
    all_left: optional path of the 'all' evaluation mask for the left view (white = evaluated).
    disc_left: optional path of the near-discontinuity evaluation mask for the left view
      (Middlebury `disc.png`, white = evaluated).
    calib: optional path of a calibration file (KITTI raw: the date folder).
    velodyne: optional path of the frame's Velodyne scan (KITTI raw).
    source: where the sample was listed, as 'file:line' or the scene folder, for errors.
    fit_disparity: when set, loading shrinks the pair by the smallest integer k with (largest
      ground-truth disparity) / k <= fit_disparity - 1 (`sample_files.shrink`), so a scene
      deeper than a network's levels (Middlebury 2014 at full size) fits them.
  """
  name: str
  left: str
  right: str
  disparity_left: Optional[str] = None
  disparity_right: Optional[str] = None
  disparity_scale: float = 1.0
  nonocc_left: Optional[str] = None
  all_left: Optional[str] = None
  disc_left: Optional[str] = None
  calib: Optional[str] = None
  velodyne: Optional[str] = None
  source: str = ''
  fit_disparity: Optional[int] = None

  @property
  def is_virtual(self) -> bool:
    return self.left.startswith(VIRTUAL_SCHEMES)


# Keys and dtypes of `sources.load_sample`'s result; the tf.data pipeline relies on them.
LOADED_KEYS: Mapping[str, type] = {
    'left': np.uint8,             # [H, W, 3] RGB
    'right': np.uint8,            # [H, W, 3] RGB
    'disparity_left': np.float32,   # [H, W] pixels, 0 = unknown
    'disparity_right': np.float32,  # [H, W] pixels, 0 = unknown
    'valid_left': np.bool_,       # [H, W] ground truth known (and inside the 'all' mask)
    'valid_right': np.bool_,      # [H, W]
    'nonocc_left': np.bool_,      # [H, W] valid and not occluded
    'disc_left': np.bool_,        # [H, W] valid and near a discontinuity; False if unknown
}

