"""Texture images for the procedural scenes and the photo warps: scikit-image's bundled
images (split into training and held-out sources) or a folder of photographs, stacked into
one atlas so that a rendered view needs a single cv2.remap."""

import functools
import os
from typing import Sequence

import cv2
import numpy as np

# Colour images (and grey ones, tinted per layer) that ship inside scikit-image, so no download
# is needed. Train and held-out scenes never share a texture source.
TEXTURE_SPLITS = {
    'train': ('astronaut', 'coffee', 'chelsea', 'rocket', 'brick', 'grass', 'camera', 'coins'),
    'heldout': ('immunohistochemistry', 'gravel', 'clock', 'moon'),
}

class TextureAtlas:
  """Texture sources stacked into one float32 image so a view needs a single cv2.remap.

  Texture i occupies rows [row_offsets[i], row_offsets[i] + h_i) and columns [0, w_i);
  lookups mirror coordinates into each texture (reflect-101), so any (u, v) is valid.
  """

  def __init__(self, images: Sequence[np.ndarray]):
    """images: [h, w, 3] (or grey [h, w]) arrays in 0-255, each at least 2x2."""
    if not images:
      raise ValueError('A TextureAtlas needs at least one texture image.')
    images = [np.asarray(i, np.float32) for i in images]
    images = [np.repeat(i[..., None], 3, -1) if i.ndim == 2 else i[..., :3] for i in images]
    if any(i.shape[0] < 2 or i.shape[1] < 2 for i in images):
      raise ValueError(f'Texture images must be at least 2x2, got {[i.shape for i in images]}.')
    self.sizes = np.array([i.shape[:2] for i in images], np.float32)  # [N, 2] (h, w)
    self.row_offsets = np.cumsum([0] + [i.shape[0] + 1 for i in images[:-1]]).astype(np.float32)
    self.image = np.zeros((int(self.row_offsets[-1]) + images[-1].shape[0],
                           max(i.shape[1] for i in images) + 1, 3), np.float32)
    for image, row in zip(images, self.row_offsets.astype(int)):
      self.image[row:row + image.shape[0], :image.shape[1]] = image

  def __len__(self) -> int:
    return len(self.sizes)

  def lookup(self, index: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Bilinear colours float32 [..., 3] of texture `index` at column u, row v (per pixel)."""
    height, width = self.sizes[index, 0], self.sizes[index, 1]
    map_u = _reflect(u, width - 1)
    map_v = _reflect(v, height - 1) + self.row_offsets[index]
    return cv2.remap(self.image, map_u, map_v, cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_REPLICATE)


def _reflect(coordinate: np.ndarray, last: np.ndarray) -> np.ndarray:
  """Mirrors real coordinates into [0, last] (reflect-101, period 2 * last)."""
  period = 2 * last
  t = coordinate - period * np.floor(coordinate / period)
  return np.minimum(t, period - t)


@functools.lru_cache(maxsize=None)
def load_textures(split: str, sigma: float = 1.0) -> TextureAtlas:
  """The blurred texture sources of a split (scikit-image data), cached in-process."""
  if split not in TEXTURE_SPLITS:
    raise ValueError(f'Unknown texture split {split!r}; valid: {sorted(TEXTURE_SPLITS)}.')
  import skimage.data  # pylint: disable=g-import-not-at-top
  images = []
  for name in TEXTURE_SPLITS[split]:
    image = np.asarray(getattr(skimage.data, name)(), np.float32)
    images.append(cv2.GaussianBlur(image, (0, 0), sigma) if sigma > 0 else image)
  return TextureAtlas(images)


@functools.lru_cache(maxsize=4)
def load_texture_dir(folder: str, sigma: float = 1.0, long_side: int = 800) -> TextureAtlas:
  """Every image of a folder of photographs (JPEG, PNG, ...) as textures, cached.

  Each is read as RGB, reduced so its longer side is at most `long_side`, and blurred by
  `sigma` like the built-in textures.

  Raises:
    ValueError: the folder holds no readable image.
  """
  names = sorted(n for n in os.listdir(folder) if os.path.splitext(n)[1].lower() in
                 ('.jpg', '.jpeg', '.png', '.ppm', '.bmp', '.tif', '.tiff', '.webp'))
  images = []
  for name in names:
    image = cv2.imread(os.path.join(folder, name), cv2.IMREAD_COLOR)
    if image is None:
      continue
    scale = long_side / max(image.shape[:2])
    if scale < 1:
      image = cv2.resize(image, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    image = image[..., ::-1].astype(np.float32)
    images.append(cv2.GaussianBlur(image, (0, 0), sigma) if sigma > 0 else image)
  if not images:
    raise ValueError(f'No readable image in the texture folder {folder}.')
  return TextureAtlas(images)
