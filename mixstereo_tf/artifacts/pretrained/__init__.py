"""Trained models shipped as package data, one folder per model.

A model folder holds `info.json` (its kind, architecture config, the mixtures it unmixes,
the recipe that trained it and its held-out numbers) and `weights.npz` (every weight of the
model in `model.weights` order, stored as float16: half the bytes, and its rounding moves a
disparity by far less than the metrics' 1-pixel thresholds). Kinds:
  * 'joint': the paper's network (`models.MixStereoNet`, config `models.ModelConfig`);
  * 'refiner': the hybrid that refines the classical result (`models.refiner`);
  * 'features': the learned matching features of anaglyphs' eyes
    (`models.matching_features`), run by `unmixing/learned_matching.py`;
  * 'echo_features': the learned echo features of double images
    (`models.matching_features.EchoFeatures`), run by `unmixing/learned_diplopia.py`.
`--pretrained=NAME` picks one (or a folder holding such files); `--pretrained=list` lists
them; with no model flag at all, the tools take the first shipped model that unmixes the
mixture asked for (`choose`).
"""

import dataclasses
import json
import os
from typing import Any, Callable, Dict, Mapping, Optional, Tuple

import numpy as np
import tensorflow as tf

from mixstereo_tf import models
from mixstereo_tf.artifacts import runs
from mixstereo_tf.core import mixtures
from mixstereo_tf.models import matching_features
from mixstereo_tf.models import refiner

FOLDER = os.path.dirname(os.path.abspath(__file__))
INFO_FILE = 'info.json'
WEIGHTS_FILE = 'weights.npz'
LIST = 'list'

# kind -> builder of the model (with its variables) from the config dict.
_BUILDERS: Dict[str, Callable[[Mapping[str, Any]], tf.keras.Model]] = {
    'joint': lambda config: models.build_model(models.ModelConfig.from_dict(config)),
    'refiner': lambda config: refiner.build_refiner(refiner.RefinerConfig.from_dict(config)),
    'features': lambda config: matching_features.build_features(
        matching_features.FeatureConfig.from_dict(config)),
    'echo_features': lambda config: matching_features.build_echo_features(
        matching_features.FeatureConfig.from_dict(config)),
}
# kind -> the config.json section of a training run that holds its architecture.
_SECTIONS = {'refiner': 'refiner', 'features': 'features', 'echo_features': 'features',
             'joint': 'model'}
KINDS = tuple(_BUILDERS)


@dataclasses.dataclass(frozen=True)
class Pretrained:
  """One shipped model.

  Attributes:
    name: its folder name.
    folder: where its files are.
    kind: a name of KINDS.
    mixture: the mixtures it unmixes (`mixtures.parse_names` text; the first is its default).
    config: the architecture config dict of its kind.
    recipe: how to retrain it (a command).
    results: its held-out numbers, a short text.
    crop: its training crop (height, width).
    default: the tools' model for the mixtures it unmixes (`choose`; chosen by the
      evaluation of its `results`).
    base: a refiner's first stage, the shipped model it was trained on and runs on (its
      examples' `refiner_data.ExampleConfig.base`); '' the classical method.
  """
  name: str
  folder: str
  kind: str
  mixture: str
  config: Mapping[str, Any]
  recipe: str = ''
  results: str = ''
  crop: Tuple[int, int] = (0, 0)
  default: bool = False
  base: str = ''

  @property
  def mixtures(self) -> Tuple[str, ...]:
    return mixtures.parse_names(self.mixture)


def read(folder: str) -> Pretrained:
  """The model described by `folder`/info.json.

  Raises:
    ValueError: a missing or malformed info.json, naming the file.
  """
  path = os.path.join(folder, INFO_FILE)
  if not os.path.exists(path):
    raise ValueError(f'No {INFO_FILE} in {folder}: not a pretrained model folder.')
  try:
    with open(path, encoding='utf-8') as f:
      info = json.load(f)
    entry = Pretrained(name=os.path.basename(os.path.normpath(folder)), folder=folder,
                       kind=info['kind'], mixture=info['mixture'], config=info['config'],
                       recipe=info.get('recipe', ''), results=info.get('results', ''),
                       crop=tuple(info.get('crop', (0, 0))),
                       default=bool(info.get('default', False)),
                       base=str(info.get('base') or ''))
  except (json.JSONDecodeError, KeyError, TypeError) as e:
    raise ValueError(f'{path} is not a valid pretrained model description: {e!r}') from None
  if entry.kind not in _BUILDERS:
    raise ValueError(f'{path}: unknown kind {entry.kind!r}; valid: {", ".join(KINDS)}.')
  return entry


def available() -> Tuple[Pretrained, ...]:
  """The shipped models, by name."""
  return tuple(read(os.path.join(FOLDER, name)) for name in sorted(os.listdir(FOLDER))
               if os.path.exists(os.path.join(FOLDER, name, INFO_FILE)))


def get(name: str) -> Pretrained:
  """A shipped model by name, or the model in a folder path.

  Raises:
    ValueError: no such model; the message lists the shipped ones.
  """
  if os.path.isdir(name):
    return read(name)
  for entry in available():
    if entry.name == name:
      return entry
  raise ValueError(f'No pretrained model {name!r}; shipped: '
                   f'{", ".join(e.name for e in available()) or "none"}.')


def choose(name: Optional[str], mixture: Optional[str]) -> Pretrained:
  """The model named, else the shipped default (`Pretrained.default`; otherwise the first by
  name) among those that unmix `mixture` ('auto' and None: the anaglyph model).

  Raises:
    ValueError: none fits; the message lists what the shipped models unmix.
  """
  if name:
    return get(name)
  wanted = 'anaglyph' if mixture in (None, 'auto') else mixtures.served_name(mixture)
  fitting = [entry for entry in available() if wanted in entry.mixtures]
  if fitting:
    return next((entry for entry in fitting if entry.default), fitting[0])
  raise ValueError(f'No shipped model unmixes {wanted!r} mixtures; shipped: ' + '; '.join(
      f'{e.name} ({", ".join(e.mixtures)})' for e in available()) + '.')


def describe() -> str:
  """Text for `--pretrained=list`: each model, what it unmixes, its recipe and numbers."""
  lines = []
  for entry in available():
    lines += [f'{entry.name}: {entry.kind} model for {", ".join(entry.mixtures)}'
              + (f' on {entry.base}' if entry.base else '')
              + (' (the default)' if entry.default else ''),
              f'  recipe: {entry.recipe}', f'  held-out: {entry.results}', '']
  return '\n'.join(lines) or 'No pretrained models are installed.'


def load_model(entry: Pretrained) -> tf.keras.Model:
  """Builds the model of `entry` and sets its weights.

  Raises:
    ValueError: the weights file does not fit the architecture.
  """
  model = _BUILDERS[entry.kind](entry.config)
  path = os.path.join(entry.folder, WEIGHTS_FILE)
  with np.load(path) as stored:
    values = [stored[f'w{i:04d}'] for i in range(len(stored.files))]
  shapes = [tuple(v.shape) for v in model.weights]
  if [tuple(v.shape) for v in values] != shapes:
    raise ValueError(f'{path} holds {len(values)} weights that do not fit the {entry.kind} '
                     f'model of {entry.folder} ({len(shapes)} weights).')
  model.set_weights([v.astype(np.float32) for v in values])
  return model


def save(model: tf.keras.Model, folder: str, kind: str, mixture: str,
         config: Mapping[str, Any], recipe: str, results: str,
         crop: Tuple[int, int] = (0, 0), base: str = '') -> Pretrained:
  """Writes `model` as a pretrained folder (float16 weights); returns its entry. `base`:
  the shipped stage a refiner runs on (`Pretrained.base`)."""
  if kind not in _BUILDERS:
    raise ValueError(f'Unknown kind {kind!r}; valid: {", ".join(KINDS)}.')
  os.makedirs(folder, exist_ok=True)
  np.savez_compressed(os.path.join(folder, WEIGHTS_FILE),
                      **{f'w{i:04d}': np.asarray(v, np.float16)
                         for i, v in enumerate(model.get_weights())})
  info = {'kind': kind, 'mixture': mixture, 'config': dict(config), 'recipe': recipe,
          'results': results, 'crop': list(crop)}
  if base:
    info['base'] = base
  with open(os.path.join(folder, INFO_FILE), 'w', encoding='utf-8') as f:
    json.dump(info, f, indent=2, sort_keys=True)
  return read(folder)


def from_run(path: str, folder: str, recipe: str, results: str) -> Pretrained:
  """Writes the newest checkpoint of a training run (or a checkpoint prefix) as a
  pretrained folder: a joint run (`config.json` section 'model'), a refiner run (section
  'refiner') or a matching-features run (section 'features'; echo features when trained on
  double images).

  Raises:
    ValueError: not a run, or weights that do not fit its architecture.
  """
  model_dir, prefix = runs.resolve_checkpoint(path)
  with open(os.path.join(model_dir, runs.CONFIG_FILE), encoding='utf-8') as f:
    sections = json.load(f)
  kind = next(k for k in ('refiner', 'features', 'joint') if _SECTIONS[k] in sections)
  if kind == 'features' and not all(mixtures.get_mixture(n).is_anaglyph for n in
                                    mixtures.parse_names(sections['train']['mixtures'])):
    kind = 'echo_features'  # The features of double images (`feature_loop.kind_name`).
  config = sections[_SECTIONS[kind]]
  model = _BUILDERS[kind](config)
  runs.restore_model_weights(model, prefix)
  if kind in ('features', 'echo_features'):  # Whole warped pairs: no network crop.
    return save(model, folder, kind, sections['train']['mixtures'], config, recipe, results)
  pipeline = sections['pipeline']
  return save(model, folder, kind, pipeline['mixture'], config, recipe, results,
              (int(pipeline['crop_height']), int(pipeline['crop_width'])),
              sections.get('examples', {}).get('base') or '')
