"""Validation pairs shared by the experiments that choose parameters: photographs warped by
drawn disparity fields with seeds training never draws (`photo_warps.warped_pair`, seeds
10^9 on). Never an evaluation scene: the photographs are the training ones
(experiments/get_photos.sh), the fields new.

The flag is declared here once for every experiment that takes it.
"""

import dataclasses
import os
from typing import Callable, Dict, Iterator, List, Sequence, TypeVar

from absl import app
from absl import flags
import numpy as np

from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.data import photo_warps
from mixstereo_tf.data import texture_atlas
from mixstereo_tf.evaluation import metrics

flags.DEFINE_string('photo_dir', '', 'Photographs of the warped validation pairs '
                    '(experiments/get_photos.sh).')
FLAGS = flags.FLAGS

PHOTO_SEED = 10 ** 9
NOISE_SIGMA = 2.0  # Grey levels of `noisy`.
Parsed = TypeVar('Parsed')


def photo_pairs(config: photo_warps.WarpConfig, count: int,
                atlas: texture_atlas.TextureAtlas) -> Iterator[Dict[str, np.ndarray]]:
  """The first `count` validation pairs of `config` (`photo_warps.warped_pair`'s dicts)."""
  for seed in range(PHOTO_SEED, PHOTO_SEED + count):
    yield photo_warps.warped_pair(seed, config, atlas)


def noisy(pair, seed):
  """The pair with independent Gaussian noise (NOISE_SIGMA grey levels) on each view, uint8:
  a rendered pair shows the same texture, its noise and quantisation included, in both
  views, which no camera pair does (experiments/channel_information.py)."""
  rng = np.random.default_rng(seed)
  out = dict(pair)
  for key in ('left', 'right'):
    image = pair[key].astype(np.float32) + rng.normal(0, NOISE_SIGMA, pair[key].shape)
    out[key] = np.clip(np.round(image), 0, 255).astype(np.uint8)
  return out


def required_atlas(**load) -> texture_atlas.TextureAtlas:
  """The photographs of --photo_dir (`load`: keywords of `texture_atlas.load_texture_dir`);
  a usage error naming the flag when it is empty."""
  if not FLAGS.photo_dir:
    raise app.UsageError('--photo_dir is required (experiments/get_photos.sh).')
  return texture_atlas.load_texture_dir(FLAGS.photo_dir, **load)


def parse_all(items: Sequence[str], parse: Callable[[str], Parsed]) -> List[Parsed]:
  """[parse(item)] of a list flag's items; a usage error with parse's message."""
  try:
    return [parse(item) for item in items]
  except ValueError as e:
    raise app.UsageError(str(e)) from None


def scores(disparity: np.ndarray, pair: Dict[str, np.ndarray], scored: np.ndarray,
           left: np.ndarray, right: np.ndarray) -> Dict[str, float]:
  """bad1: share of `scored` pixels whose left disparity is off by more than 1 px;
  psnr_left, psnr_right: RGB PSNR of the views (0..255 floats or uint8) against pair's."""
  error = np.abs(disparity - pair['disparity_left'])[scored]
  return {'bad1': float(np.mean(error > 1.0)),
          'psnr_left': metrics.psnr(np.asarray(left, np.float64),
                                    pair['left'].astype(np.float64)),
          'psnr_right': metrics.psnr(np.asarray(right, np.float64),
                                     pair['right'].astype(np.float64))}


def _boolean(value: str) -> bool:
  """'true' / '1' or 'false' / '0' (any case), else ValueError."""
  if value.lower() not in ('true', '1', 'false', '0'):
    raise ValueError(value)
  return value.lower() in ('true', '1')


def numeric_fields(config_class) -> Dict[str, type]:
  """{name: parser} of a dataclass's int, float and bool fields (bools as true / false)."""
  kinds = {int: int, 'int': int, float: float, 'float': float, bool: _boolean,
           'bool': _boolean}
  return {f.name: kinds[f.type] for f in dataclasses.fields(config_class)
          if f.type in kinds}


def field_values(flag: str, item: str, parts: Sequence[str],
                 types: Dict[str, type]) -> Dict[str, object]:
  """{field: typed value} of `parts` 'field=value' (types: `numeric_fields`).

  Raises:
    ValueError: naming `flag`, the item and the part at fault and the valid fields.
  """
  values = {}
  for part in parts:
    field, _, value = part.partition('=')
    try:
      values[field] = types[field](value)
    except (KeyError, ValueError):
      raise ValueError(f'{flag}: {item!r}: {part!r} is not field=value of '
                       f'{", ".join(types)}.') from None
  return values


def model_entry(path: str, folder: str) -> pretrained.Pretrained:
  """The model of `path`: a pretrained folder (holding info.json) as it is, or a training
  run's newest checkpoint written to `folder` in the pretrained format."""
  if os.path.exists(os.path.join(path, 'info.json')):
    return pretrained.read(path)
  return pretrained.from_run(path, folder, '', '')
