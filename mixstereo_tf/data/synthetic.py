"""Procedural layered stereo scenes with exact ground truth (the embedded `sample` source).

A scene is a stack of textured planar layers: a background plane covering everything and
several foreground shapes (ellipse, rotated rectangle, convex polygon). Layer k is defined
in left-view coordinates (x_L, y): its shape is an analytic region, its texture coordinates
are an affine function of (x_L, y), and its disparity is a slanted plane
d_k(x_L, y) = a + b x_L + c y (pixels, positive). The left view shows layer point x_L at
column x_L, the right view at x_R = x_L - d_k(x_L, y); since this is linear in x_L, a right
pixel inverts in closed form: x_L = (x_R + a + c y) / (1 - b).

Both views are rendered by inverse mapping (each pixel finds its layer point, the texture is
sampled bilinearly with cv2.remap) and z-buffered independently: the covering layer with the
largest disparity wins. Hence warping the right view by d_L reproduces the left view up to
interpolation error, and d_R(x - d_L(x)) = d_L(x) wherever the left pixel is visible.
Pixel centres sit at integer coordinates.
"""

import dataclasses
from typing import Dict, List, Sequence, Tuple

import cv2
import numpy as np

from mixstereo_tf.data import texture_atlas

SHAPES = ('ellipse', 'rectangle', 'polygon')


@dataclasses.dataclass(frozen=True)
class SceneConfig:
  """Size and depth range of a procedural scene.

  Attributes:
    max_disparity: the network's disparity range; every disparity stays in
      [min_disparity, near_fraction * max_disparity] (at most max_disparity - 1).
    height: image height in pixels.
    width: image width in pixels.
    min_disparity: the farthest disparity (pixels, > 0 so 0 can mean 'unknown').
    near_fraction: the nearest layers reach this fraction of max_disparity.
    min_layers: fewest layers, background plane included.
    max_layers: most layers, background plane included.
    texture_sigma: Gaussian blur (pixels) applied to the texture sources; keeps bilinear
      resampling close to exact so the two views agree to within ~1/255.
    realistic: add the structures of real scenes (`random_layers`): a ground plane that
      comes nearer towards the bottom (p = 0.6), thin poles (p = 0.5, 1-3 of them) and more
      layers (4-9).
  """
  max_disparity: int
  height: int = 128
  width: int = 256
  min_disparity: float = 1.0
  near_fraction: float = 0.8
  min_layers: int = 3
  max_layers: int = 6
  texture_sigma: float = 1.0
  realistic: bool = False

  def __post_init__(self):
    if self.height < 8 or self.width < 8:
      raise ValueError(f'SceneConfig height/width must be >= 8, got {self.height}x{self.width}.')
    if not 0 < self.min_disparity < self.far_limit < self.near_limit:
      raise ValueError(f'SceneConfig: need 0 < min_disparity ({self.min_disparity}) and '
                       f'near_fraction * max_disparity ({self.near_limit}) well above it; '
                       f'max_disparity={self.max_disparity} is too small.')
    if not 2 <= self.min_layers <= self.max_layers:
      raise ValueError(f'SceneConfig: need 2 <= min_layers ({self.min_layers}) <= max_layers '
                       f'({self.max_layers}).')

  @property
  def near_limit(self) -> float:
    """Largest disparity in a scene."""
    return min(self.near_fraction * self.max_disparity, self.max_disparity - 1.0)

  @property
  def far_limit(self) -> float:
    """Largest disparity of the background plane; foreground layers lie above it."""
    return self.min_disparity + 0.25 * (self.near_limit - self.min_disparity)


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


def _plane_for_box(rng, low, high, box, max_slope):
  """A plane whose value stays in [low, high] over box = (x0, x1, y0, y1)."""
  x0, x1, y0, y1 = box
  b, c = rng.uniform(-max_slope, max_slope, size=2)
  spread = abs(b) * (x1 - x0) / 2 + abs(c) * (y1 - y0) / 2
  scale = min(1.0, 0.45 * (high - low) / max(spread, 1e-6))  # Keep room for the centre.
  b, c, spread = b * scale, c * scale, spread * scale
  centre = rng.uniform(low + spread, high - spread)
  a = centre - b * (x0 + x1) / 2 - c * (y0 + y1) / 2
  return (float(a), float(b), float(c))


def _random_shape(rng, height, width, extent):
  """A random foreground shape and its bounding box (x0, x1, y0, y1), left coordinates."""
  kind = SHAPES[rng.integers(len(SHAPES))]
  cx, cy = rng.uniform(0, extent), rng.uniform(0, height)
  size = min(height, width)
  rx, ry = rng.uniform(0.1, 0.35, size=2) * size
  angle = rng.uniform(0, np.pi)
  if kind == 'polygon':
    angles = np.sort(rng.uniform(0, 2 * np.pi, size=rng.integers(3, 8)))
    points = np.stack([cx + rx * np.cos(angles), cy + ry * np.sin(angles)], -1)
    hull = cv2.convexHull(points.astype(np.float32), clockwise=False)[:, 0]
    params = tuple(float(v) for v in hull.reshape(-1))
  else:
    params = (float(cx), float(cy), float(rx), float(ry), float(angle))
  radius = float(np.hypot(rx, ry))  # Covers every rotation of the shape.
  return kind, params, (cx - radius, cx + radius, cy - radius, cy + radius)


def _textured(rng, shape, params, plane, num_textures) -> Layer:
  texture_affine = (float(rng.uniform(0, 512)), float(rng.uniform(0, 512)),
                    float(rng.uniform(0.6, 1.25)), float(rng.uniform(-np.pi, np.pi)))
  return Layer(shape, params, plane, int(rng.integers(num_textures)), texture_affine,
               tuple(float(g) for g in rng.uniform(0.6, 1.2, size=3)),
               tuple(float(o) for o in rng.uniform(-30, 30, size=3)))


def _real_structures(rng, config: SceneConfig, num_textures: int) -> List[Layer]:
  """A ground plane and thin poles (SceneConfig.realistic), in left coordinates."""
  h, w = config.height, config.width
  extent, pad = w + config.near_limit, 0.1 * h
  layers = []
  if rng.uniform() < 0.6:
    horizon = rng.uniform(0.35, 0.7) * h
    far = rng.uniform(config.min_disparity, config.far_limit)
    near = rng.uniform(0.5, 0.9) * config.near_limit
    slope = (near - far) / (h - horizon)
    params = (-pad, horizon, extent + pad, horizon, extent + pad, h + pad, -pad, h + pad)
    layers.append(_textured(rng, 'polygon', params, (float(far - slope * horizon), 0.0,
                                                     float(slope)), num_textures))
  if rng.uniform() < 0.5:
    for _ in range(int(rng.integers(1, 4))):
      half_width, half_height = rng.uniform(0.7, 4.0), rng.uniform(0.2, 0.6) * h
      params = (float(rng.uniform(0, extent)), float(rng.uniform(0, h)), float(half_width),
                float(half_height), float(rng.uniform(-0.15, 0.15)))
      d = rng.uniform(config.far_limit, config.near_limit)
      layers.append(_textured(rng, 'rectangle', params, (float(d), 0.0, 0.0), num_textures))
  return layers


def random_layers(seed: int, config: SceneConfig, num_textures: int) -> List[Layer]:
  """The layers of scene `seed`, background plane first; deterministic in seed."""
  rng = np.random.default_rng(seed)
  h, w = config.height, config.width
  extent = w + config.near_limit  # Right-view pixels see left coordinates up to W + d.
  low_count, high_count = (4, 9) if config.realistic else (config.min_layers,
                                                           config.max_layers)
  count = int(rng.integers(low_count, high_count + 1))
  layers = []
  for index in range(count):
    if index == 0:
      shape, params, box = 'full', (), (0.0, extent, 0.0, float(h))
      low, high = config.min_disparity, config.far_limit
    else:
      shape, params, box = _random_shape(rng, h, w, extent)
      low, high = config.far_limit, config.near_limit
    plane = _plane_for_box(rng, low, high, box, max_slope=0.15)
    layers.append(_textured(rng, shape, params, plane, num_textures))
    if index == 0 and config.realistic:
      layers.extend(_real_structures(rng, config, num_textures))
  return layers


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


def render_scene(seed: int, config: SceneConfig, textures) -> Dict[str, np.ndarray]:
  """Renders the random scene `seed` (see `render_layers` for textures and the result)."""
  if not isinstance(textures, texture_atlas.TextureAtlas):
    textures = texture_atlas.TextureAtlas(textures)
  layers = random_layers(seed, config, len(textures))
  return render_layers(layers, textures, config.height, config.width)
