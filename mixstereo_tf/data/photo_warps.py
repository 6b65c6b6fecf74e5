"""Stereo pairs from single photographs warped by drawn disparity fields.

Matching across an anaglyph's colour channels is a matter of appearance, not geometry, so
the learned matching features (`models/matching_features.py`) train on real photographs
with exact, synthetic correspondences (Watson et al., "Learning Stereo from Single
Images", ECCV 2020, shows that stereo synthesised from single images generalises better
than synthetic scenes):
  1. a disparity field is drawn as `synthetic.random_layers` draws a scene (a slanted
     background plane, foreground shapes on slanted planes, with p = `realistic_probability`
     a ground plane and thin poles), so it has depth edges and occlusions;
  2. every layer shows the SAME photograph at the same place (texture point of the
     left-view point (x_L, y) = (u0, v0) + zoom * (x_L, y)): the left view is a crop of the
     photograph, the right view the photograph warped by the field, hidden parts resolved
     by the z-buffer of `layer_render.render_layers`; with p = `object_probability` each
     foreground layer instead shows another part of a photograph (so that some depth
     edges are also colour edges, as at real object borders);
  3. with p = `window_probability` the pair is window-aligned (a share U[0, 0.7] of the
     disparity range becomes negative), as many published anaglyphs are.
Disparities are exact (float, left x matches right x - d_L); `nonocc_left` marks left
pixels whose match is visible in the right view.
"""

import dataclasses
import os
import re
from typing import Dict

import numpy as np

from mixstereo_tf.data import layer_render
from mixstereo_tf.data import middlebury
from mixstereo_tf.data import synthetic
from mixstereo_tf.data import texture_atlas

# Names of the project's evaluation images: KITTI frames (000151_10.png), Motorcycle and
# the SceneFlow frames of the real-world set, besides `middlebury.is_evaluation_scene`.
_EVALUATION_NAMES = re.compile(r'^\d{6}_1[01]$|motorcycle|kitti|sceneflow|middlebury')


@dataclasses.dataclass(frozen=True)
class WarpConfig:
  """Size and depth of the warped pairs.

  Attributes:
    height, width: pair size, pixels.
    max_disparity: disparities lie in [1, 0.8 * max_disparity] before window alignment.
    zoom_range: photograph pixels per view pixel, drawn log-uniformly from this range
      (scale changes: a texture seen nearer or farther).
    realistic_probability: chance of ground planes and poles (`SceneConfig.realistic`).
    object_probability: chance that foreground layers show other parts of a photograph.
    window_probability: chance of window alignment (signed disparities).
    photo_warps: step 2 on (the recipe); off, every layer keeps the texture, gain and
      offset `synthetic.random_layers` drew: the project's procedural scenes, textured
      from the same atlas (the ablation without warps of photographs).
  """
  height: int = 128
  width: int = 256
  max_disparity: int = 64
  zoom_range: tuple = (0.5, 2.0)
  realistic_probability: float = 0.5
  object_probability: float = 0.5
  window_probability: float = 0.5
  photo_warps: bool = True

  def __post_init__(self):
    synthetic.SceneConfig(self.max_disparity, self.height, self.width)
    low, high = self.zoom_range
    if not 0 < low <= high:
      raise ValueError(f'WarpConfig.zoom_range needs 0 < low <= high, got {self.zoom_range}.')
    for field in ('realistic_probability', 'object_probability', 'window_probability'):
      if not 0.0 <= getattr(self, field) <= 1.0:
        raise ValueError(f'WarpConfig.{field} must be in [0, 1], got '
                         f'{getattr(self, field)}.')


def refuse_evaluation_photos(folder: str) -> None:
  """Raises ValueError naming the first file of `folder` that looks like an evaluation
  image (a Middlebury evaluation scene, a KITTI frame, Motorcycle, SceneFlow): evaluation
  data is never training data."""
  for name in sorted(os.listdir(folder)):
    stem = os.path.splitext(name)[0].lower()
    words = set(re.split(r'[^a-z]+', stem)) & set(middlebury.EVALUATION_SCENES)
    if words or middlebury.is_evaluation_scene(stem) or _EVALUATION_NAMES.search(stem):
      raise ValueError(f'{os.path.join(folder, name)} looks like an evaluation image (the '
                       f"paper's test scenes, KITTI, Motorcycle, SceneFlow); evaluation data "
                       'is never training data: remove it from the photographs.')


def _photo_layers(rng, layers, atlas: texture_atlas.TextureAtlas, config: WarpConfig,
                  width: int):
  """The layers re-textured with one photograph (step 2), others for objects sometimes."""
  zoom = float(np.exp(rng.uniform(*np.log(config.zoom_range))))
  photo = int(rng.integers(len(atlas)))
  height_px, width_px = atlas.sizes[photo]
  u0 = float(rng.uniform(0, max(1.0, width_px - zoom * width)))
  v0 = float(rng.uniform(0, max(1.0, height_px - zoom * config.height)))
  objects = rng.uniform() < config.object_probability
  out = []
  for index, layer in enumerate(layers):
    texture, affine = photo, (u0, v0, zoom, 0.0)
    if objects and index > 0 and layer.shape != 'rectangle':
      texture = int(rng.integers(len(atlas)))
      affine = (float(rng.uniform(0, atlas.sizes[texture][1])),
                float(rng.uniform(0, atlas.sizes[texture][0])), zoom, 0.0)
    out.append(dataclasses.replace(layer, texture=texture, texture_affine=affine,
                                   gain=(1.0, 1.0, 1.0), offset=(0.0, 0.0, 0.0)))
  return out


def warped_pair(seed: int, config: WarpConfig,
                atlas: texture_atlas.TextureAtlas) -> Dict[str, np.ndarray]:
  """Pair `seed` (module docstring), deterministic in seed.

  Returns:
    'left', 'right': uint8 [H, W, 3]; 'disparity_left': float32 [H, W] signed pixels (the
    left pixel x matches the right pixel x - d); 'nonocc_left': bool [H, W].
  """
  rng = np.random.default_rng([seed, 1])
  realistic = bool(rng.uniform() < config.realistic_probability)
  wide = config.width + config.max_disparity  # Rendered wider so a window shift fits.
  scene = synthetic.SceneConfig(config.max_disparity, config.height, wide,
                                realistic=realistic)
  layers = synthetic.random_layers(seed, scene, len(atlas))
  if config.photo_warps:
    layers = _photo_layers(rng, layers, atlas, config, wide)
  pair = layer_render.render_layers(layers, atlas, config.height, wide)
  shift = 0
  if rng.uniform() < config.window_probability:
    low, high = np.percentile(pair['disparity_left'], [1.0, 99.0])
    shift = int(round(low + rng.uniform(0.0, 0.7) * (high - low)))
  # Left columns [shift, shift + W) against right [0, W): every disparity becomes d - shift.
  left_cols, right_cols = slice(shift, shift + config.width), slice(0, config.width)
  disparity = pair['disparity_left'][:, left_cols] - shift
  x = np.arange(config.width, dtype=np.float32)[None]
  inside = (x - disparity >= 0) & (x - disparity <= config.width - 1)
  return {'left': pair['left'][:, left_cols], 'right': pair['right'][:, right_cols],
          'disparity_left': disparity.astype(np.float32),
          'nonocc_left': pair['nonocc_left'][:, left_cols] & inside}
