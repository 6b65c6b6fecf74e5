"""Rendering of planar textured layers into a rectified stereo pair with exact disparities.

Layer k is defined in left-view coordinates (x_L, y): its shape is an analytic region, its
texture coordinates are an affine function of (x_L, y), and its disparity is a slanted
plane d_k(x_L, y) = a + b x_L + c y (pixels, positive). The left view shows layer point
x_L at column x_L, the right view at x_R = x_L - d_k(x_L, y); since this is linear in x_L,
a right pixel inverts in closed form: x_L = (x_R + a + c y) / (1 - b).

Both views are rendered by inverse mapping (each pixel finds its layer point, the texture is
sampled bilinearly with cv2.remap) and z-buffered independently: the covering layer with the
largest disparity wins. Hence warping the right view by d_L reproduces the left view up to
interpolation error, and d_R(x - d_L(x)) = d_L(x) wherever the left pixel is visible.
Pixel centres sit at integer coordinates.
"""

import dataclasses
from typing import Dict, Sequence, Tuple

import numpy as np

from mixstereo_tf.data import texture_atlas

SHAPES = ('ellipse', 'rectangle', 'polygon')


@dataclasses.dataclass(frozen=True)
class Layer:
  """One planar textured layer, all coordinates in the left view (pixels).

  Attributes:
    shape: 'full' (background), 'ellipse', 'rectangle' or 'polygon'.
    params: for ellipse/rectangle (cx, cy, half_width, half_height, angle_rad); a rectangle
      covers -half <= local < half (half-open, so pixel counts are exact); for polygon the
      flattened vertices (x0, y0, x1, y1, ...) of a convex polygon, either orientation.
    plane: (a, b, c) with d(x_L, y) = a + b x_L + c y; |b| < 1.
    texture: index into the texture list.
    texture_affine: (u0, v0, scale, angle_rad): texture point of (x_L, y) is
      (u0, v0) + scale * R(angle) (x_L, y).
    gain: per-channel factor applied to the texture (tints grey sources).
    offset: per-channel offset added after the gain (0-255 units).
  """
  shape: str
  params: Tuple[float, ...]
  plane: Tuple[float, float, float]
  texture: int
  texture_affine: Tuple[float, float, float, float] = (0.0, 0.0, 1.0, 0.0)
  gain: Tuple[float, float, float] = (1.0, 1.0, 1.0)
  offset: Tuple[float, float, float] = (0.0, 0.0, 0.0)


def shape_mask(layer: Layer, x: np.ndarray, y: np.ndarray) -> np.ndarray:
  """Whether the layer's shape covers the left-view points (x, y) (any real coordinates)."""
  if layer.shape == 'full':
    return np.ones(np.broadcast(x, y).shape, bool)
  if layer.shape == 'polygon':
    vertices = np.asarray(layer.params, np.float64).reshape(-1, 2)
    edges = np.roll(vertices, -1, axis=0) - vertices
    # Orientation-free: a point is inside when it lies on the interior side of every edge.
    orientation = np.sign(np.sum(vertices[:, 0] * edges[:, 1] - vertices[:, 1] * edges[:, 0]))
    inside = np.ones(np.broadcast(x, y).shape, bool)
    for (x0, y0), (ex, ey) in zip(vertices, edges):
      ex, ey = float(orientation * ex), float(orientation * ey)
      inside &= ex * (y - float(y0)) - ey * (x - float(x0)) >= 0
    return inside
  cx, cy, rx, ry, angle = layer.params
  cos, sin = float(np.cos(angle)), float(np.sin(angle))
  u = (x - cx) * cos + (y - cy) * sin
  v = (y - cy) * cos - (x - cx) * sin
  if layer.shape == 'ellipse':
    return (u / rx) ** 2 + (v / ry) ** 2 <= 1.0
  if layer.shape == 'rectangle':
    return (u >= -rx) & (u < rx) & (v >= -ry) & (v < ry)
  raise ValueError(f'Unknown layer shape {layer.shape!r}; valid: full, {", ".join(SHAPES)}.')


def _right_to_left(layer: Layer, x_right: np.ndarray, y: np.ndarray) -> np.ndarray:
  """Left coordinate x_L of the layer point seen at right coordinate x_R (closed form)."""
  a, b, c = layer.plane
  return (x_right + (a + c * y)) / (1.0 - b)


def _row_range(layer: Layer, height: int) -> slice:
  """The image rows the layer can cover (rows are shared by both rectified views)."""
  if layer.shape == 'full':
    return slice(0, height)
  if layer.shape == 'polygon':
    ys = layer.params[1::2]
    top, bottom = min(ys), max(ys)
  else:
    cx, cy, rx, ry, _ = layer.params  # pylint: disable=unused-variable
    top, bottom = cy - np.hypot(rx, ry), cy + np.hypot(rx, ry)
  return slice(int(np.clip(np.floor(top), 0, height)), int(np.clip(np.ceil(bottom) + 1, 0, height)))


def _zbuffer(layers, x_left_of, y):
  """Winning layer index, its disparity and its x_L; x_left_of(layer, rows) gives x_L."""
  best_d = np.full(y.shape, -np.inf, np.float32)
  best = np.zeros(y.shape, np.int32)
  best_x = np.zeros(y.shape, np.float32)
  for k, layer in enumerate(layers):
    rows = _row_range(layer, y.shape[0])
    x_left, y_rows = x_left_of(layer, rows), y[rows]
    a, b, c = layer.plane
    d = a + b * x_left + c * y_rows
    wins = shape_mask(layer, x_left, y_rows) & (d > best_d[rows])
    np.copyto(best_d[rows], d, where=wins)
    np.copyto(best_x[rows], x_left, where=wins)
    best[rows][wins] = k
  return best, best_d, best_x


def _shade(layers, textures, winner, x_left, y):
  """Colours each pixel by bilinear texture lookup of its winning layer; uint8 [H, W, 3]."""
  table = []
  for layer in layers:
    u0, v0, scale, angle = layer.texture_affine
    table.append((u0, v0, scale * np.cos(angle), scale * np.sin(angle), layer.texture)
                 + layer.gain + layer.offset)
  per_pixel = np.moveaxis(np.asarray(table, np.float32)[winner], -1, 0)
  u0, v0, cos, sin, index = per_pixel[:5]
  gain, offset = np.moveaxis(per_pixel[5:8], 0, -1), np.moveaxis(per_pixel[8:], 0, -1)
  colour = textures.lookup(index.astype(np.int32), u0 + cos * x_left - sin * y,
                           v0 + sin * x_left + cos * y)
  return np.clip(np.rint(colour * gain + offset), 0, 255).astype(np.uint8)


def render_layers(layers: Sequence[Layer], textures, height: int,
                  width: int) -> Dict[str, np.ndarray]:
  """Renders both views of a layer stack with exact disparities and occlusions.

  Args:
    layers: the layers; the first must have shape 'full'; ties in disparity go to the
      earlier layer.
    textures: a TextureAtlas, or a list of [h, w, 3] images in 0-255, indexed by
      `Layer.texture`.
    height, width: output size.

  Returns:
    left, right: uint8 [H, W, 3]. disparity_left, disparity_right: float32 [H, W] pixels,
    positive; the left pixel x matches the right pixel x - d_L, the right pixel x matches the
    left pixel x + d_R. nonocc_left: bool [H, W], False where the match x - d_L lies outside
    [0, W - 1] or is hidden in the right view by a nearer layer.
  """
  if not layers or layers[0].shape != 'full':
    raise ValueError('The first layer must have shape "full" so that every pixel is covered.')
  if not isinstance(textures, texture_atlas.TextureAtlas):
    textures = texture_atlas.TextureAtlas(textures)
  bad = [l.texture for l in layers if not 0 <= l.texture < len(textures)]
  if bad:
    raise ValueError(f'Layer texture indices {bad} outside [0, {len(textures)}).')
  y, x = np.mgrid[0:height, 0:width].astype(np.float32)
  win_l, disp_l, x_l = _zbuffer(layers, lambda layer, rows: x[rows], y)
  win_r, disp_r, x_r = _zbuffer(
      layers, lambda layer, rows: _right_to_left(layer, x[rows], y[rows]), y)
  match = x - disp_l
  win_match, _, _ = _zbuffer(
      layers, lambda layer, rows: _right_to_left(layer, match[rows], y[rows]), y)
  nonocc = (match >= 0) & (match <= width - 1) & (win_match == win_l)
  return {
      'left': _shade(layers, textures, win_l, x_l, y),
      'right': _shade(layers, textures, win_r, x_r, y),
      'disparity_left': disp_l,
      'disparity_right': disp_r,
      'nonocc_left': nonocc,
  }
