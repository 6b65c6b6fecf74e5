"""The embedded default data source `sample`: trains and evaluates with nothing downloaded.

Training pairs are procedural layered scenes (`synthetic.py`) rendered on demand from
virtual URIs `synthetic://<split>/<index>?h=<height>&w=<width>&d=<max_disparity>` (the
left/right records carry the fragments `#left` / `#right`). Train and held-out scenes use
disjoint texture sources and disjoint seeds (train: seed = index < 2**31; held-out:
seed = 2**31 + index).

The held-out split adds one real pair, `skimage://motorcycle?factor=<k>`: the Middlebury
2014 Motorcycle pair shipped with scikit-image (500x741, already 1/4 of the benchmark's
resolution; left disparity from ~7 to ~60 px, inf where unknown; the left pixel x matches
the right pixel x - d, checked photometrically). When its largest disparity does not fit
below max_disparity - 1, images and disparities are shrunk by the smallest integer factor k
that makes it fit (k x k block means; disparities divided by k; a block is valid only if all
its pixels are). Its right disparity is unknown (zeros, all False). No source has a
near-discontinuity mask (`disc_left` all False).
"""

import dataclasses
import functools
import os
from typing import Dict, List, Optional
import urllib.parse

import numpy as np
import tensorflow as tf

from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import records
from mixstereo_tf.data import synthetic
from mixstereo_tf.data import texture_atlas

SPLITS = ('train', 'heldout')
DEFAULT_TRAIN_SCENES = 2000
HELDOUT_SCENES = 8
HELDOUT_SEED_OFFSET = 2**31
MOTORCYCLE_URI = 'skimage://motorcycle'
# Occlusion rule for real left-only ground truth (see `occlusion_from_disparity`).
OCCLUSION_TOLERANCE = 1.0


def scene_seed(split: str, index: int) -> int:
  """The render seed of scene `index` of `split`; train and held-out ranges are disjoint."""
  if split not in SPLITS:
    raise ValueError(f'Unknown sample split {split!r}; valid: {SPLITS}.')
  if not 0 <= index < HELDOUT_SEED_OFFSET:
    raise ValueError(f'Scene index {index} outside [0, 2**31).')
  return index + (HELDOUT_SEED_OFFSET if split == 'heldout' else 0)


def motorcycle_factor(max_disparity: int) -> int:
  """Smallest integer k with (largest Motorcycle disparity) / k <= max_disparity - 1."""
  if max_disparity < 2:
    raise ValueError(f'max_disparity must be >= 2, got {max_disparity}.')
  largest = float(motorcycle()[2].max())
  return max(1, int(np.ceil(largest / (max_disparity - 1.0))))


def sample_records(split: str, *, max_disparity: int, num_scenes: Optional[int] = None,
                   height: Optional[int] = None, width: Optional[int] = None,
                   texture_dir: Optional[str] = None, realistic: bool = False
                   ) -> List[records.StereoSample]:
  """Lists the pairs of the embedded source.

  Args:
    split: 'train' or 'heldout'.
    num_scenes: procedural scenes (default DEFAULT_TRAIN_SCENES for train, HELDOUT_SCENES
      for held-out).
    height, width: scene size (default: `synthetic.SceneConfig`'s); the Motorcycle pair
      keeps its own size.
    max_disparity: the network's disparity range; all ground truth stays below it.
    texture_dir: a folder of photographs to texture the scenes with (`synthetic.
      load_texture_dir`; training only: held-out scenes keep their own textures) instead of
      the split's scikit-image pictures.
    realistic: scenes with the structures of real ones (`synthetic.SceneConfig.realistic`).

  Returns:
    Train: the scenes. Held-out: the scenes, then the Motorcycle pair.

  Raises:
    ValueError: unknown split, non-positive num_scenes, or an unusable size/range.
  """
  if split not in SPLITS:
    raise ValueError(f'Unknown sample split {split!r}; valid: {SPLITS}.')
  if num_scenes is None:
    num_scenes = DEFAULT_TRAIN_SCENES if split == 'train' else HELDOUT_SCENES
  if not 0 < num_scenes <= HELDOUT_SEED_OFFSET:
    raise ValueError(f'num_scenes must be in [1, 2**31], got {num_scenes}.')
  defaults = synthetic.SceneConfig(max_disparity=max_disparity)
  config = dataclasses.replace(defaults, height=height or defaults.height,
                               width=width or defaults.width)
  query = f'h={config.height}&w={config.width}&d={config.max_disparity}'
  if realistic:
    query += '&r=1'
  if texture_dir:
    if split != 'train':
      raise ValueError('A texture folder textures training scenes only: the held-out scenes '
                       'keep textures no training scene uses.')
    query += '&' + urllib.parse.urlencode({'tex': os.path.abspath(texture_dir)})
  samples = []
  for index in range(num_scenes):
    uri = f'synthetic://{split}/{index}?{query}'
    samples.append(records.StereoSample(
        name=f'synthetic_{split}_{index:05d}', left=uri + '#left', right=uri + '#right',
        source=f'sample:{split}'))
  if split == 'heldout':
    factor = motorcycle_factor(max_disparity)
    uri = f'{MOTORCYCLE_URI}?factor={factor}'
    samples.append(records.StereoSample(
        name=f'motorcycle_div{factor}', left=uri + '#left', right=uri + '#right',
        source='skimage.data.stereo_motorcycle'))
  return samples


def _parse(sample: records.StereoSample):
  """(scheme, netloc, path, {key: int}) of the sample's URI; ValueError names the record."""
  parts = urllib.parse.urlsplit(sample.left)
  try:
    query = {k: v if k == 'tex' else int(v)
             for k, v in urllib.parse.parse_qsl(parts.query, strict_parsing=True)}
  except ValueError as error:
    raise ValueError(f'Bad virtual URI {sample.left!r} ({sample.source}): {error}') from None
  return parts.scheme, parts.netloc, parts.path.strip('/'), query


def load_virtual(sample: records.StereoSample) -> Dict[str, np.ndarray]:
  """Renders or loads a virtual sample into exactly `records.LOADED_KEYS`.

  Raises:
    ValueError: the URI is malformed (the message names it and `sample.source`).
  """
  scheme, netloc, path, query = _parse(sample)
  if scheme == 'synthetic' and netloc in SPLITS and path.isdigit() and {
      'h', 'w', 'd'} <= set(query) <= {'h', 'w', 'd', 'r', 'tex'}:
    config = synthetic.SceneConfig(height=query['h'], width=query['w'],
                                   max_disparity=query['d'], realistic=bool(query.get('r')))
    if 'tex' in query:
      textures = texture_atlas.load_texture_dir(query['tex'], config.texture_sigma)
    else:
      textures = texture_atlas.load_textures(netloc, config.texture_sigma)
    scene = synthetic.render_scene(scene_seed(netloc, int(path)), config, textures)
    full = np.ones(scene['nonocc_left'].shape, bool)
    scene.update(valid_left=full, valid_right=full.copy(), disc_left=np.zeros_like(full))
    return {key: scene[key].astype(dtype, copy=False)
            for key, dtype in records.LOADED_KEYS.items()}
  if scheme == 'skimage' and netloc == 'motorcycle' and set(query) == {'factor'}:
    return _load_motorcycle(query['factor'])
  raise ValueError(f'Unknown virtual URI {sample.left!r} ({sample.source}); expected '
                   "'synthetic://train|heldout/<index>?h=..&w=..&d=..[&r=1][&tex=..]' or "
                   "'skimage://motorcycle?factor=<k>'.")


@functools.lru_cache(maxsize=1)
def motorcycle():
  """(left, right, disparity with unknown = 0) at scikit-image's size, cached."""
  import skimage.data  # pylint: disable=g-import-not-at-top
  left, right, disparity = skimage.data.stereo_motorcycle()
  disparity = np.where(np.isfinite(disparity), disparity, 0).astype(np.float32)
  return left, right, disparity


def _block_mean(array: np.ndarray, factor: int) -> np.ndarray:
  """k x k block means of [H, W, ...], dropping the last H % k rows and W % k columns."""
  h, w = array.shape[0] // factor, array.shape[1] // factor
  blocks = array[:h * factor, :w * factor].reshape(h, factor, w, factor, *array.shape[2:])
  return blocks.mean(axis=(1, 3), dtype=np.float64)


def _load_motorcycle(factor: int) -> Dict[str, np.ndarray]:
  """The Motorcycle pair shrunk by `factor` (see the module docstring)."""
  if factor < 1:
    raise ValueError(f'Motorcycle factor must be >= 1, got {factor}.')
  left, right, disparity = motorcycle()
  valid = disparity > 0
  if factor > 1:
    left = np.rint(_block_mean(left, factor)).astype(np.uint8)
    right = np.rint(_block_mean(right, factor)).astype(np.uint8)
    valid = _block_mean(valid, factor) == 1.0
    disparity = np.where(valid, _block_mean(disparity, factor) / factor, 0).astype(np.float32)
  nonocc = valid & ~occlusion_from_disparity(disparity, valid)
  return {'left': left.copy(), 'right': right.copy(), 'disparity_left': disparity.copy(),
          'disparity_right': np.zeros_like(disparity), 'valid_left': valid,
          'valid_right': np.zeros_like(valid), 'nonocc_left': nonocc,
          'disc_left': np.zeros_like(valid)}


def occlusion_from_disparity(disparity_left: np.ndarray, valid: np.ndarray,
                             tolerance: float = OCCLUSION_TOLERANCE) -> np.ndarray:
  """Left pixels hidden in the right view, from the left disparity alone.

  The left pixel x matches the right position m(x) = x - d_L(x). Every valid left pixel is
  splatted to the columns floor(m) and ceil(m) of its row in the right view, keeping the
  largest disparity (a z-buffer; both columns so slanted surfaces leave no cracks). The pixel
  is occluded when m(x) is outside [0, W - 1] or the z-buffer at round(m(x)) exceeds d_L(x)
  by more than `tolerance`: a nearer surface covers its match. Surfaces visible only in the
  right view (beyond the left image's border) are unknown to this rule.

  Args:
    disparity_left: float [H, W] pixels, positive.
    valid: bool [H, W], where the disparity is known (others never occlude).
    tolerance: pixels of disparity.

  Returns:
    bool [H, W], True where occluded (meaningful at valid pixels).
  """
  height, width = disparity_left.shape
  match = np.arange(width, dtype=np.float32) - disparity_left
  rows = np.broadcast_to(np.arange(height)[:, None], (height, width))
  zbuffer = np.full((height, width + 2), -np.inf, np.float32)
  for rounding in (np.floor, np.ceil):
    column = np.clip(rounding(match).astype(np.int64), -1, width) + 1
    np.maximum.at(zbuffer, (rows[valid], column[valid]), disparity_left[valid])
  inside = (match >= 0) & (match <= width - 1)
  nearest = np.clip(np.rint(match), 0, width - 1).astype(np.int64) + 1
  hidden = np.take_along_axis(zbuffer, nearest, axis=1) > disparity_left + tolerance
  return ~inside | hidden


def preview_images(sample: records.StereoSample, mixture: str,
                   max_disparity: float) -> Dict[str, np.ndarray]:
  """uint8 images to look at: left, right, mixture (RGB) and the two disparities (grey,
  255 = max_disparity, black = unknown)."""
  loaded = load_virtual(sample)
  views = [image_range.u8_to_signed(tf.constant(loaded[k])) for k in ('left', 'right')]
  out = {'left': loaded['left'], 'right': loaded['right'],
         'mixture': image_range.signed_to_u8(mixtures.mix(mixture, *views)).numpy()}
  for key in ('disparity_left', 'disparity_right'):
    scaled = loaded[key] * (255.0 / max_disparity)
    out[key] = np.clip(np.rint(scaled), 0, 255).astype(np.uint8)
  return out
