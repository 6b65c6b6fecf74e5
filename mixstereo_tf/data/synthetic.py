"""Procedural layered stereo scenes with exact ground truth (the embedded `sample` source).

A scene is a stack of textured planar layers: a background plane covering everything and
several foreground shapes (ellipse, rotated rectangle, convex polygon), each with a
slanted disparity plane, drawn here at random (`random_layers`) and rendered with exact
disparities and occlusions by `layer_render`.
"""

import dataclasses
from typing import Dict, List

import cv2
import numpy as np

from mixstereo_tf.data import layer_render
from mixstereo_tf.data import texture_atlas


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
  kind = layer_render.SHAPES[rng.integers(len(layer_render.SHAPES))]
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


def _textured(rng, shape, params, plane, num_textures) -> layer_render.Layer:
  texture_affine = (float(rng.uniform(0, 512)), float(rng.uniform(0, 512)),
                    float(rng.uniform(0.6, 1.25)), float(rng.uniform(-np.pi, np.pi)))
  return layer_render.Layer(shape, params, plane, int(rng.integers(num_textures)), texture_affine,
               tuple(float(g) for g in rng.uniform(0.6, 1.2, size=3)),
               tuple(float(o) for o in rng.uniform(-30, 30, size=3)))


def _real_structures(rng, config: SceneConfig, num_textures: int) -> List[layer_render.Layer]:
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


def random_layers(seed: int, config: SceneConfig, num_textures: int) -> List[layer_render.Layer]:
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


def render_scene(seed: int, config: SceneConfig, textures) -> Dict[str, np.ndarray]:
  """Renders the random scene `seed` (`layer_render.render_layers`: its textures and
  result)."""
  if not isinstance(textures, texture_atlas.TextureAtlas):
    textures = texture_atlas.TextureAtlas(textures)
  layers = random_layers(seed, config, len(textures))
  return layer_render.render_layers(layers, textures, config.height, config.width)
