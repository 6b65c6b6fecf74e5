"""Training examples of the hybrid refiner: realistic scenes, published-style mixtures and
the classical method's result on them, computed once and kept in shards.

One example (`make_example`):
  1. a `sample` training scene with real-scene structures (`synthetic.render_scene`,
     `realistic=True`; textures from scikit-image's training photographs or a
     `texture_dir`), rendered `max_disparity` px wider than kept;
  2. one encoding of `mixtures`, drawn uniformly;
  3. for anaglyphs, window alignment with probability `window_probability`: the right view
     moves so a fraction U[0, 0.7] of the disparity range becomes negative (every
     disparity d - s); a double image's views stay ordered by positive disparity;
  4. the mixture, `degrade.degrade` (noise, blur, JPEG, vignetting, channel imbalance)
     except with probability `clean_probability` (anaglyphs made digitally from clean
     pairs, as FFmpeg or StereoPhoto Maker make them), and 8-bit quantisation;
  5. the classical stage on it by inference's own route (`classical_stage`: the range
     planned by `steps.estimate_range`, then `steps.classical_unmix`), with the matcher
     pinned to one SGM strip (`ONE_STRIP`); with `base`, the shipped stage of that name
     instead (`base_stage`: the stage as serving runs it, `shipped.stage`), so a refiner
     learns to correct the stage it will run on;
  6. for encodings that may mix the eyes unequally (`families.Family.weighted`: double
     images), with probability `weighted_probability` the mixture is a L + (1 - a) R
     with a drawn uniformly from `weight_range` (else a = 1/2), and the classical stage
     estimates a itself, as `--mixing_weight=auto` does at inference;
  7. with probability `large_probability`, steps 1-6 happen on a scene `large_factor`
     times as high, wide and deep, and a random height x width window of everything is
     kept: the network sees disparities, occlusions and classical errors of photo-sized
     images (as it does in a tile of one at inference) in an example of the usual size.
Seeds: example i draws everything from seed i and its weight from seed (i, 1) (scenes:
the `sample` training seeds; the held-out scenes use other textures and seeds 2^31 + i).
Shards `shard_<k>.npz` of `shard_size` examples each are written atomically, so an
interrupted build resumes.
"""

import dataclasses
import os
from typing import Dict, Optional, Tuple, Union

import numpy as np
import tensorflow as tf

from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.core import hints
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import degrade
from mixstereo_tf.data import photo_warps
from mixstereo_tf.data import synthetic
from mixstereo_tf.data import texture_atlas
from mixstereo_tf.unmixing import families
from mixstereo_tf.unmixing import shipped
from mixstereo_tf.unmixing import steps

# One SGM strip: the matcher's strips otherwise follow the core count, and so would the
# examples (the aggregation differs near strip borders).
ONE_STRIP = hints.FrameHint(matcher_strips=1)
KEYS = ('mixture', 'classical_left', 'classical_right', 'classical_disparity_left',
        'classical_disparity_right', 'left', 'right', 'disparity_left', 'disparity_right')


@dataclasses.dataclass(frozen=True)
class ExampleConfig:
  """How refiner training examples are made.

  Attributes:
    mixtures: encodings drawn from (comma-separated names for `mixtures.parse_names`).
    height, width: example size in pixels.
    max_disparity: scene depth range (`synthetic.SceneConfig.max_disparity`), pixels.
    window_probability: chance of a window-aligned (signed) example.
    degrade: pass each mixture through `degrade.degrade` ...
    clean_probability: ... except this share of them, left clean.
    texture_dir: a folder of photographs for the scenes (None: scikit-image's).
    large_probability: chance of an example cut from a larger scene (step 7) ...
    large_factor: ... this many times the size and disparity range.
    weighted_probability: chance that a double image mixes its eyes with a != 1/2 ...
    weight_range: ... drawn uniformly from this (low, high), 0 < low <= high < 1.
    base: the shipped stage (`artifacts/pretrained` name) the examples' first stage is
      (step 5); '' the classical method.
  """
  mixtures: str = 'anaglyphs'
  height: int = 160
  width: int = 320
  max_disparity: int = 64
  window_probability: float = 0.7
  degrade: bool = True
  clean_probability: float = 0.0
  texture_dir: Optional[str] = None
  large_probability: float = 0.0
  large_factor: int = 2
  weighted_probability: float = 0.0
  weight_range: Tuple[float, float] = (0.3, 0.7)
  base: str = ''

  def __post_init__(self):
    mixtures.parse_names(self.mixtures)  # ValueError naming an unknown encoding.
    synthetic.SceneConfig(self.max_disparity, self.height, self.width + self.max_disparity)
    if self.large_factor < 1:
      raise ValueError(f'ExampleConfig.large_factor must be >= 1, got {self.large_factor}.')
    if self.base:
      entry = pretrained.get(self.base)  # ValueError listing the shipped models.
      if entry.kind == 'refiner' or any(m not in entry.mixtures
                                        for m in mixtures.parse_names(self.mixtures)):
        raise ValueError(f'ExampleConfig.base {self.base!r} ({entry.kind} for '
                         f'{entry.mixture}) is no first stage of {self.mixtures!r}.')
    low, high = self.weight_range
    if not 0.0 < low <= high < 1.0:
      raise ValueError(f'ExampleConfig.weight_range needs 0 < low <= high < 1, got '
                       f'{self.weight_range}.')
    for field in ('window_probability', 'clean_probability', 'large_probability',
                  'weighted_probability'):
      if not 0.0 <= getattr(self, field) <= 1.0:
        raise ValueError(f'ExampleConfig.{field} must be in [0, 1], got '
                         f'{getattr(self, field)}.')


def _textures(config: ExampleConfig) -> texture_atlas.TextureAtlas:
  if config.texture_dir:
    photo_warps.refuse_evaluation_photos(config.texture_dir)
    return texture_atlas.load_texture_dir(config.texture_dir)
  return texture_atlas.load_textures('train')


def _window_aligned(scene: Dict[str, np.ndarray], shift: int, width: int):
  """Left columns [shift, shift + width), right [0, width) of a scene rendered wider:
  every disparity becomes d - shift (left x' = x - shift matches right x - d)."""
  return {'left': scene['left'][:, shift:shift + width],
          'right': scene['right'][:, :width],
          'disparity_left': scene['disparity_left'][:, shift:shift + width] - shift,
          'disparity_right': scene['disparity_right'][:, :width] - shift}


def mixing_weight(index: int, name: str, config: ExampleConfig) -> Optional[float]:
  """Example `index`'s left-eye weight a (step 6), or None for the exact a = 1/2 route:
  drawn from its own seed (index, 1), so the other draws, and with
  `weighted_probability` = 0 every example, stay those of earlier recipes."""
  if not families.of(name).weighted:
    return None
  rng = np.random.default_rng([index, 1])
  if rng.uniform() >= config.weighted_probability:
    return None
  return float(rng.uniform(*config.weight_range))


def _mix(name: str, left: np.ndarray, right: np.ndarray, weight: Optional[float]):
  """uint8 views -> the mixture in [0, 1]: encoding `name`, or a L + (1 - a) R."""
  left, right = image_range.u8_to_signed(left), image_range.u8_to_signed(right)
  mixed = (mixtures.mix(name, left, right) if weight is None else
           mixtures.mix_double(left, right, weight))
  return image_range.signed_to_unit(mixed)


def base_stage(config: ExampleConfig) -> Optional[shipped.Stage]:
  """The shipped stage `config.base` (step 5), or None for the classical method."""
  return shipped.stage(pretrained.get(config.base)) if config.base else None


def make_example(index: int, config: ExampleConfig, textures: texture_atlas.TextureAtlas,
                 stage: Optional[shipped.Stage] = None) -> Dict[str, np.ndarray]:
  """Example `index` (module docstring): uint8 images, float32 disparities, str 'name',
  bool 'clean' (whether the mixture was left undegraded). `stage`: `base_stage(config)`
  (built once by the caller; None: the classical method)."""
  rng = np.random.default_rng(index)
  window = rng.uniform() < config.window_probability
  fraction = rng.uniform(0.0, 0.7) if window else 0.0
  names = mixtures.parse_names(config.mixtures)
  name = names[rng.integers(len(names))]
  clean = rng.uniform() < config.clean_probability
  # Drawn after the others: with p = 0 the examples of earlier recipes stay the same.
  factor = config.large_factor if rng.uniform() < config.large_probability else 1
  height, width = factor * config.height, factor * config.width
  example = _whole_example(index, name, window, fraction, clean, factor, config, textures,
                           stage)
  y0, x0 = rng.integers(height - config.height + 1), rng.integers(width - config.width + 1)
  window_of = lambda a: a[y0:y0 + config.height, x0:x0 + config.width]
  return dict({key: window_of(example[key]) for key in KEYS}, name=name,
              clean=bool(clean or not config.degrade))


def _whole_example(index, name, window, fraction, clean, factor, config, textures, stage):
  """Steps 1-6 on a scene `factor` times the configured size (all of KEYS)."""
  max_disparity = factor * config.max_disparity
  width = factor * config.width
  scene_config = synthetic.SceneConfig(max_disparity, factor * config.height,
                                       width + max_disparity, realistic=True)
  scene = synthetic.render_scene(index, scene_config, textures)
  shift = 0
  if window and families.of(name).signed:
    low, high = np.percentile(scene['disparity_left'], [1.0, 99.0])
    shift = int(round(low + fraction * (high - low)))
  pair = _window_aligned(scene, shift, width)
  weight = mixing_weight(index, name, config)
  mixed = _mix(name, pair['left'], pair['right'], weight)
  if config.degrade and not clean:
    mixed = degrade.degrade(mixed, tf.constant([index, 7], tf.int32))
  mixture = image_range.unit_to_u8(np.asarray(mixed))
  base = classical_stage(mixture, name, None if weight is None else 'auto', stage)
  return {'mixture': mixture,
          'classical_left': base['left'], 'classical_right': base['right'],
          'classical_disparity_left': base['disparity_left'].astype(np.float32),
          'classical_disparity_right': base['disparity_right'].astype(np.float32),
          'left': pair['left'], 'right': pair['right'],
          'disparity_left': pair['disparity_left'].astype(np.float32),
          'disparity_right': pair['disparity_right'].astype(np.float32)}


def classical_stage(mixture: np.ndarray, name: str, weight: Union[None, float, str] = None,
                    stage: Optional[shipped.Stage] = None) -> Dict[str, np.ndarray]:
  """The classical method's result on a uint8 mixture as inference computes it (the
  range estimated from the image, `steps.estimate_range`; `steps.classical_unmix`; or
  `stage`'s range planning and solver in their place), with the matcher pinned to one
  strip (`ONE_STRIP`); `weight`: a double image's mixing weight
  (`hints.FrameHint.mixing_weight`: None 1/2, 'auto' estimated, or a number)."""
  default = families.of(name).classical_range()
  hint = dataclasses.replace(ONE_STRIP, mixing_weight=weight)
  search = steps.estimate_range(mixture, name, None, default, hint, stage and stage.plan)
  return (stage.solve if stage else steps.classical_unmix)(mixture, name, search, hint)


def _shard_path(folder: str, shard: int) -> str:
  return os.path.join(folder, f'shard_{shard:04d}.npz')


def build_shard(folder: str, shard: int, shard_size: int, config: ExampleConfig) -> str:
  """Writes shard `shard` (examples shard * shard_size ...) unless it exists; its path."""
  path = _shard_path(folder, shard)
  if os.path.exists(path):
    return path
  textures, stage = _textures(config), base_stage(config)
  examples = [make_example(i, config, textures, stage)
              for i in range(shard * shard_size, (shard + 1) * shard_size)]
  arrays = {key: np.stack([e[key] for e in examples]) for key in KEYS}
  arrays['name'] = np.array([e['name'] for e in examples])
  os.makedirs(folder, exist_ok=True)
  partial = path + '.partial.npz'
  np.savez(partial, **arrays)
  os.replace(partial, path)
  return path


def load_shards(folder: str, count: int) -> Dict[str, np.ndarray]:
  """The first `count` shards of `folder`, concatenated per key.

  Raises:
    ValueError: fewer than `count` shards exist.
  """
  paths = [_shard_path(folder, k) for k in range(count)]
  missing = [p for p in paths if not os.path.exists(p)]
  if missing:
    raise ValueError(f'Missing refiner example shards: {missing[:3]} ({len(missing)} of '
                     f'{count}); build them first (`build_shard`).')
  parts = []
  for path in paths:
    with np.load(path) as shard:
      parts.append({key: shard[key] for key in KEYS + ('name',)})
  return {key: np.concatenate([p[key] for p in parts]) for key in KEYS + ('name',)}
