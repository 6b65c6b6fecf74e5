"""Fully convolutional networks on images of any size in bounded memory: overlapping tiles.

An image of at most `tile` x `tile` pixels in area (1280x720 for the default 1024) runs in
one pass (padded at the bottom / right to the network's multiple). A larger one is cut
into cores of `tile - 2 overlap` pixels; each core is run with `overlap` pixels of
context on every side (edge-replicated at the image border and padded at the bottom /
right to the network's multiple), and only the core of each result is kept. With
an overlap at least the network's receptive radius the result equals one pass over the
whole image (up to the padding of the last tile).
"""

from typing import Callable, Dict

import numpy as np

Network = Callable[[np.ndarray], Dict[str, np.ndarray]]


def _padded(array: np.ndarray, multiple: int) -> np.ndarray:
  """[1, h, w, C] float32: `array` edge-padded at the bottom / right to the multiple (no
  copy when it is float32 and needs no padding)."""
  height, width = array.shape[:2]
  if height % multiple or width % multiple:
    array = np.pad(array, ((0, -height % multiple), (0, -width % multiple), (0, 0)),
                   mode='edge')
  return array[None].astype(np.float32, copy=False)


def apply(network: Network, image: np.ndarray, multiple: int, tile: int = 1024,
          overlap: int = 64) -> Dict[str, np.ndarray]:
  """Runs `network` over `image` tile by tile (module docstring).

  Args:
    network: fn([1, h, w, C] float32, h and w multiples of `multiple`) -> dict of
      [1, h, w, c] arrays (tensors or NumPy).
    image: [H, W, C] float32.
    multiple: the network's size multiple.
    tile: one network input holds at most tile x tile pixels before padding: the whole
      image when it fits, else tiles of at most `tile` pixels a side.
    overlap: context pixels on each side of a core.

  Returns:
    The network's outputs over the whole image, each [H, W, c] float32.
  """
  if tile <= 2 * overlap:
    raise ValueError(f'tile ({tile}) must exceed twice the overlap ({overlap}).')
  height, width = image.shape[:2]
  if height * width <= tile * tile:  # Same memory as one tile; no tile overheads.
    outputs = network(_padded(image, multiple))
    return {key: np.asarray(value)[0, :height, :width].astype(np.float32)
            for key, value in outputs.items()}
  core = tile - 2 * overlap
  result: Dict[str, np.ndarray] = {}
  for y in range(0, height, core):
    for x in range(0, width, core):
      y0, x0 = max(0, y - overlap), max(0, x - overlap)
      y1, x1 = min(height, y + core + overlap), min(width, x + core + overlap)
      crop = image[y0:y1, x0:x1]
      outputs = network(_padded(crop, multiple))
      for key, value in outputs.items():
        value = np.asarray(value)[0]
        if key not in result:
          result[key] = np.zeros((height, width, value.shape[-1]), np.float32)
        result[key][y:y + core, x:x + core] = value[y - y0:y - y0 + core, x - x0:x - x0 + core][
            :min(core, height - y), :min(core, width - x)]
  return result
