"""Sparse ground-truth depth from KITTI Velodyne scans (Eigen split evaluation).

A scan is projected into a rectified camera of the raw calibration (`calib_velo_to_cam.txt`,
`calib_cam_to_cam.txt`): P = P_rect_0c · R_rect_00 · [R | T], with R_rect and [R | T]
padded to 4x4. A point X (metres, velodyne frame: x forward, y left,
z up) maps to (u·z, v·z, z) = P · [X, 1]; z is the depth along the camera axis.

Rasterisation choices:
  * points with velodyne x < 0 (behind the sensor) or camera depth <= 0 are dropped;
  * pixel = round(u) - 1, round(v) - 1: the KITTI calibration is treated as 1-based (MATLAB
    devkit) like monodepth's ground truth, so our depth maps match the ones behind the
    published Eigen-split numbers;
  * several points on one pixel keep the nearest (smallest depth);
  * 0 = no point.
"""

import os
from typing import Dict, Union

import numpy as np

# The raw calibration files of a drive's date folder the projection reads.
CALIB_FILES = ('calib_cam_to_cam.txt', 'calib_velo_to_cam.txt')

CalibValue = Union[np.ndarray, str]


def _is_number(token: str) -> bool:
  try:
    float(token)
  except ValueError:
    return False
  return True


def read_calib_file(path: str) -> Dict[str, CalibValue]:
  """Reads a KITTI calibration text file of `key: v1 v2 ...` lines.

  Works for the raw-data files (`calib_cam_to_cam.txt`, `calib_velo_to_cam.txt`) and the
  object benchmark's `calib.txt`. Blank lines are skipped.

  Returns:
    {key: float64 1-D array}, or {key: str} for values that are not numbers at all (e.g.
    `calib_time: 09-Jan-2012 13:57:47`).

  Raises:
    ValueError naming the file and line for a line without `key:` or with a partly
    numeric value.
  """
  calib = {}
  with open(path, 'r', encoding='utf-8') as f:
    for number, line in enumerate(f, start=1):
      line = line.strip()
      if not line:
        continue
      key, sep, value = line.partition(':')
      key = key.strip()
      if not sep or not key:
        raise ValueError(f'{path}:{number}: expected "key: values", got {line!r}.')
      tokens = value.split()
      numeric = [_is_number(t) for t in tokens]
      if all(numeric):
        calib[key] = np.array([float(t) for t in tokens], dtype=np.float64)
      elif not numeric[0]:
        calib[key] = value.strip()
      else:
        raise ValueError(f'{path}:{number}: non-numeric value in {key!r}: {value.strip()!r}.')
  return calib


def read_velodyne(path: str) -> np.ndarray:
  """Reads a Velodyne `.bin` scan: float32 [N, 4] (x, y, z in metres, reflectance)."""
  data = np.fromfile(path, dtype=np.float32)
  if data.size % 4:
    raise ValueError(f'{path}: {data.size} float32 values is not a multiple of 4 '
                     '(x, y, z, reflectance).')
  return data.reshape(-1, 4)


def _matrix(calib: Dict[str, CalibValue], key: str, rows: int, cols: int) -> np.ndarray:
  if key not in calib:
    raise ValueError(f'Calibration has no {key!r}; keys: {sorted(calib)}.')
  value = calib[key]
  if isinstance(value, str) or value.size != rows * cols:
    raise ValueError(f'Calibration {key!r} must hold {rows}x{cols} numbers, got {value!r}.')
  return np.asarray(value, dtype=np.float64).reshape(rows, cols)


def _homogeneous(matrix: np.ndarray) -> np.ndarray:
  """Pads a 3x3 or 3x4 matrix to 4x4 with [0, 0, 0, 1] as the last row."""
  out = np.eye(4)
  out[:3, :matrix.shape[1]] = matrix
  return out


def velo_to_camera_projection(cam_to_cam: Dict[str, CalibValue],
                              velo_to_cam: Dict[str, CalibValue],
                              camera: int = 2) -> np.ndarray:
  """[3, 4] projection P_rect_0c · R_rect_00 · [R | T] from the KITTI raw calibration.

  Args:
    cam_to_cam: `read_calib_file('calib_cam_to_cam.txt')`.
    velo_to_cam: `read_calib_file('calib_velo_to_cam.txt')`.
    camera: 0..3; 2 is the left colour camera (`image_02`), 3 the right one.
  """
  rigid = np.hstack([_matrix(velo_to_cam, 'R', 3, 3), _matrix(velo_to_cam, 'T', 3, 1)])
  rectify = _homogeneous(_matrix(cam_to_cam, 'R_rect_00', 3, 3))
  project = _matrix(cam_to_cam, f'P_rect_{camera:02d}', 3, 4)
  return project @ rectify @ _homogeneous(rigid)


def project_velodyne_to_depth(points: np.ndarray, projection: np.ndarray, height: int,
                              width: int) -> np.ndarray:
  """Rasterises Velodyne points into a sparse float32 [height, width] depth map (metres).

  Args:
    points: [N, 3] or [N, 4] velodyne-frame points (a 4th column, reflectance, is ignored).
    projection: [3, 4] velodyne -> image projection (see the module docstring).
    height, width: image size in pixels.

  Returns:
    Depth along the camera axis at pixel (round(v) - 1, round(u) - 1), the nearest point
    where several land on one pixel, 0 where none does.
  """
  points = np.asarray(points, dtype=np.float64)
  projection = np.asarray(projection, dtype=np.float64)
  if points.ndim != 2 or points.shape[1] not in (3, 4):
    raise ValueError(f'points must be [N, 3] or [N, 4], got shape {points.shape}.')
  if projection.shape != (3, 4):
    raise ValueError(f'projection must be [3, 4], got shape {projection.shape}.')
  points = points[points[:, 0] >= 0, :3]
  image = np.hstack([points, np.ones((len(points), 1))]) @ projection.T
  image = image[image[:, 2] > 0]
  depth = image[:, 2]
  # 1-based calibration -> 0-based pixel indices (see the module docstring).
  cols = np.round(image[:, 0] / depth).astype(np.int64) - 1
  rows = np.round(image[:, 1] / depth).astype(np.int64) - 1
  inside = (cols >= 0) & (cols < width) & (rows >= 0) & (rows < height)
  nearest = np.full((height, width), np.inf)
  np.minimum.at(nearest, (rows[inside], cols[inside]), depth[inside])
  return np.where(np.isfinite(nearest), nearest, 0.0).astype(np.float32)


def rectified_focal_length(calib_dir: str, image_height: int, image_width: int,
                           camera: int = 2) -> float:
  """Focal length in pixels of a rectified KITTI raw camera: P_rect_0c[0, 0].

  Read from the date folder's `calib_cam_to_cam.txt`, like the projection of the ground
  truth, so depth from disparity uses the drive's own focal length (2011_09_26: 721.5377 px
  at 1242 px width; 2011_09_30: 707.0912 px at 1226 px).

  Args:
    calib_dir: the drive date folder holding `calib_cam_to_cam.txt`.
    image_height, image_width: size of the image the focal length is used for.
    camera: 2 (left colour) or 3 (right colour).

  Raises:
    ValueError naming the file: P_rect_0c missing or malformed, or S_rect_0c (the
    rectified size, when the file has it) differs from the image size, which would make
    both the focal length and the projected ground truth wrong for this image.
  """
  path = os.path.join(calib_dir, 'calib_cam_to_cam.txt')
  calib = read_calib_file(path)
  try:
    focal = float(_matrix(calib, f'P_rect_{camera:02d}', 3, 4)[0, 0])
    size_key = f'S_rect_{camera:02d}'
    if size_key in calib:
      width, height = _matrix(calib, size_key, 1, 2)[0]
      if (height, width) != (image_height, image_width):
        raise ValueError(f'{size_key} is {width:g}x{height:g} but the image is '
                         f'{image_width}x{image_height}; evaluate the rectified images '
                         'at their original size.')
  except ValueError as error:
    raise ValueError(f'{path}: {error}') from error
  return focal


def eigen_ground_truth(calib_dir: str, velodyne_bin: str, image_height: int,
                       image_width: int, camera: int = 2) -> np.ndarray:
  """Sparse GT depth [image_height, image_width] for one KITTI raw frame.

  Args:
    calib_dir: the drive date folder holding `calib_cam_to_cam.txt` and
      `calib_velo_to_cam.txt` (e.g. `.../2011_09_26`).
    velodyne_bin: the frame's `velodyne_points/data/*.bin`.
    image_height, image_width: size of the camera image the depth is for.
    camera: 2 (left colour) or 3 (right colour).
  """
  cam_path, velo_path = (os.path.join(calib_dir, name) for name in CALIB_FILES)
  try:
    projection = velo_to_camera_projection(read_calib_file(cam_path),
                                           read_calib_file(velo_path), camera)
  except ValueError as error:
    raise ValueError(f'{calib_dir}: {error}') from error
  return project_velodyne_to_depth(read_velodyne(velodyne_bin), projection, image_height,
                                   image_width)
