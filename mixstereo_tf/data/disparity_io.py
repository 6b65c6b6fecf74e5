"""Readers of ground-truth files: disparity maps (PFM, 16-bit KITTI PNG, 8-bit Middlebury) and
evaluation masks.

Disparity is float32 `[H, W]` in pixels with 0 = unknown, plus a boolean validity mask.
Bad input raises `ValueError` naming the file.
"""

import re
from typing import Tuple

import numpy as np

from mixstereo_tf.data import image_io


def read_pfm(path: str) -> np.ndarray:
  """Reads a PFM file as float32 `[H, W]` ('Pf') or `[H, W, 3]` ('PF'), top row first.

  PFM stores rows bottom-to-top; a negative header scale means little-endian samples.
  Values are returned unchanged (inf/NaN included).

  Raises:
    ValueError: missing file, malformed header or truncated data.
  """
  image_io.check_file(path)
  with open(path, 'rb') as f:
    data = f.read()
  # The header is three whitespace-separated fields after the magic: width, height, scale,
  # ended by exactly one whitespace byte before the binary samples.
  match = re.match(rb'(P[Ff])\s+(\d+)\s+(\d+)\s+([-+0-9.eE]+)\s', data)
  if match is None:
    raise ValueError(f'Malformed PFM header in {path}')
  channels = 3 if match.group(1) == b'PF' else 1
  width, height = int(match.group(2)), int(match.group(3))
  try:
    scale = float(match.group(4))
  except ValueError:
    raise ValueError(f'Malformed PFM scale {match.group(4)!r} in {path}') from None
  count = width * height * channels
  body = data[match.end():]
  if len(body) < 4 * count:
    raise ValueError(f'Truncated PFM data in {path}: expected {count} floats for '
                     f'{width}x{height}x{channels}, found {len(body) // 4}')
  dtype = '<f4' if scale < 0 else '>f4'
  array = np.frombuffer(body, dtype=dtype, count=count).astype(np.float32)
  shape = (height, width) if channels == 1 else (height, width, 3)
  return np.ascontiguousarray(np.flipud(array.reshape(shape)))


def _single_channel(array: np.ndarray, path: str) -> np.ndarray:
  """Returns a 2-D map; 3/4-channel files are accepted only when their colours are equal."""
  if array.ndim == 2:
    return array
  if array.ndim == 3 and array.shape[2] == 1:
    return array[:, :, 0]
  if array.ndim == 3 and np.all(array[:, :, :3] == array[:, :, :1]):
    return array[:, :, 0]
  raise ValueError(f'Expected a single-channel map in {path}, got shape {array.shape}')


def read_disparity(path: str, scale: float = 1.0) -> Tuple[np.ndarray, np.ndarray]:
  """Reads ground-truth disparity in pixels: stored value / `scale`.

  Formats: .pfm floats (Middlebury 2014, Scene Flow; scale normally 1); 16-bit PNG (KITTI,
  scale 256); 8-bit PNG/PGM (Middlebury 2001/2003, scale 16/8/4). Stored 0, negative, inf
  and NaN values are unknown.

  Returns:
    (disparity float32 [H, W] with unknown pixels set to 0, valid bool [H, W]).

  Raises:
    ValueError: missing/unreadable file, more than one channel, scale <= 0, or an 8-bit
      file with a scale above 16 (a KITTI map saved as 8 bits).
  """
  if not scale > 0:
    raise ValueError(f'Disparity scale must be positive for {path}, got {scale}')
  if path.lower().endswith('.pfm'):
    stored = read_pfm(path)
  else:
    stored = image_io.read_raw(path)
    if stored.dtype not in (np.uint8, np.uint16):
      raise ValueError(f'Unsupported disparity sample type {stored.dtype} in {path}')
    if stored.dtype == np.uint8 and scale > 16:  # Middlebury's 8-bit maps use 4, 8 or 16.
      raise ValueError(f'{path} is an 8-bit image, but disparities stored as {scale:g} d '
                       'need 16 bits (KITTI PNGs are uint16): it would read as at most '
                       f'{255 / scale:.2f} px.')
  stored = _single_channel(stored, path).astype(np.float32)
  valid = np.isfinite(stored) & (stored > 0)
  disparity = np.where(valid, stored / np.float32(scale), 0).astype(np.float32)
  return disparity, valid


def read_mask(path: str) -> np.ndarray:
  """Reads an evaluation mask as bool `[H, W]`.

  8-bit masks: True only where white (255). This matches the Middlebury 2001/2003 masks
  (`nonocc.png`, `all.png`: 255 = evaluated) and Middlebury 2014 `mask0nocc.png` (255 =
  non-occluded, 128 = occluded, 0 = invalid). 16-bit files are KITTI disparity maps used as
  masks (`disp_noc` as the non-occluded mask): True where the value is > 0. Colour masks are
  white only where all colour channels are 255.
  """
  array = image_io.read_raw(path)
  if array.ndim == 3:
    array = array[:, :, :3].min(axis=2)
  if array.dtype == np.uint16:
    return array > 0
  if array.dtype == np.uint8:
    return array == 255
  raise ValueError(f'Unsupported mask sample type {array.dtype} in {path}')
