"""File writers the tests use to build tiny datasets."""

import cv2
import numpy as np


def write_pfm(path: str, array: np.ndarray) -> None:
  """Writes float32 `[H, W]` or `[H, W, 3]` (top row first) as a little-endian PFM."""
  array = np.asarray(array, dtype=np.float32)
  if array.ndim == 3 and array.shape[2] == 1:
    array = array[:, :, 0]
  if array.ndim not in (2, 3) or (array.ndim == 3 and array.shape[2] != 3):
    raise ValueError(f'write_pfm({path}): expected [H, W] or [H, W, 3], got {array.shape}')
  magic = 'PF' if array.ndim == 3 else 'Pf'
  header = f'{magic}\n{array.shape[1]} {array.shape[0]}\n-1.0\n'.encode('ascii')
  with open(path, 'wb') as f:
    f.write(header)
    f.write(np.flipud(array).astype('<f4').tobytes())


def write_image(path, array: np.ndarray) -> str:
  """cv2.imwrite(path, array) (BGR order, format from the extension), asserted; the path."""
  assert cv2.imwrite(str(path), array), path
  return str(path)


def random_rgb(height: int = 8, width: int = 12, seed: int = 0) -> np.ndarray:
  """A uint8 [height, width, 3] image of uniform random values."""
  return np.random.default_rng(seed).integers(0, 256, (height, width, 3), dtype=np.uint8)
