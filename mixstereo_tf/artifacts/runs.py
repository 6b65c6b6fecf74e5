"""The training run directory: its `config.json` schema, `RunInfo` and checkpoint lookup.

A run directory (`--model_dir` of training) holds:
  * `config.json`: one JSON object with a section per frozen config of the run (`train`,
    `model`, `loss`, `data`, `pipeline`; each `dataclasses.asdict` of its config). Readers
    need only `model` (the architecture, `models.ModelConfig.to_dict`) and `pipeline`
    (`mixture`, `crop_height`, `crop_width`);
  * `flags.txt`: the command line that made it;
  * TensorFlow checkpoints `ckpt-<step>` and their `checkpoint` index file.
Every tool that takes a trained model (`--checkpoint`) accepts a run directory (its newest
checkpoint) or a checkpoint prefix such as `runs/demo/ckpt-7000` (its folder is the run).
"""

import dataclasses
import json
import os
import re
from typing import Any, Dict, Iterator, Optional, Tuple

import tensorflow as tf
from tensorflow.core.protobuf import trackable_object_graph_pb2

from mixstereo_tf import models
from mixstereo_tf.core import mixtures

CONFIG_FILE = 'config.json'
FLAGS_FILE = 'flags.txt'


@dataclasses.dataclass(frozen=True)
class RunInfo:
  """What a trained model expects: its mixture operator, training crop and architecture;
  `mode` what its run trained (`objective.MODES`; separation_only leaves the stereo network
  at its initial weights)."""
  mixture: str
  crop_height: int
  crop_width: int
  model_config: models.ModelConfig
  mode: str = 'joint'

  @property
  def mixtures(self) -> Tuple[str, ...]:
    """The encodings the model was trained on (`mixture` may list several, comma-separated,
    or be 'anaglyphs'; the first is its default; `mixtures.parse_names`)."""
    return mixtures.parse_names(self.mixture)

  def to_dict(self) -> Dict[str, object]:
    return {'mixture': self.mixture, 'crop_height': self.crop_height,
            'crop_width': self.crop_width, 'model': self.model_config.to_dict(),
            'mode': self.mode}


def to_json(**configs: Any) -> str:
  """Serialises configs (section name -> dataclass or plain value) as `config.json` text."""
  out: Dict[str, Any] = {}
  for name, config in configs.items():
    out[name] = dataclasses.asdict(config) if dataclasses.is_dataclass(config) else config
  return json.dumps(out, indent=2, sort_keys=True, default=str)


class RunDirError(ValueError):
  """A run directory or checkpoint that cannot take this run (a file, another run's
  checkpoints, weights of another architecture)."""


# Fields of any section a resumed run may change: how long and how it runs, not what it
# trains (the architecture, data, loss, optimizer and seed must stay).
RESUMABLE_FIELDS = frozenset({
    'num_steps', 'model_dir', 'log_every', 'checkpoint_every', 'summary_every',
    'image_summary_every', 'jit_compile', 'strategy', 'init_checkpoint', 'init_from',
    # Drops pairs whose files cannot be read: what an unreadable pair's error advises.
    'skip_bad_pairs'})


def _changes(old: Any, new: Any, path: str = '') -> Iterator[str]:
  """'section.field: old -> new' of every leaf that differs, RESUMABLE_FIELDS aside."""
  if isinstance(old, dict) and isinstance(new, dict):
    for key in sorted(set(old) | set(new)):
      if key not in RESUMABLE_FIELDS:
        yield from _changes(old.get(key), new.get(key), f'{path}.{key}' if path else key)
  elif old != new:
    yield f'{path}: {old!r} -> {new!r}'


def check_resumable(model_dir: str, **configs: Any) -> None:
  """Raises RunDirError when `model_dir` holds a checkpoint of a run whose `config.json`
  differs from `configs` beyond RESUMABLE_FIELDS (a resumed run would train something
  else under the old label), naming every difference."""
  path = os.path.join(model_dir, CONFIG_FILE)
  if tf.train.latest_checkpoint(model_dir) is None or not tf.io.gfile.exists(path):
    return
  with tf.io.gfile.GFile(path) as f:
    try:
      old = json.load(f)
    except json.JSONDecodeError:
      return  # Nothing to compare: the run is rewritten from these configs.
  changed = list(_changes(old, json.loads(to_json(**configs))))
  # 'train.learning_rate' as 'TrainConfig.learning_rate': the tools name its flag.
  classes = {name: type(config).__name__ for name, config in configs.items()
             if dataclasses.is_dataclass(config)}
  changed = [re.sub(r'^(\w+)\.(\w+):', lambda m: f'{classes.get(m[1], m[1])}.{m[2]}:', c)
             for c in changed]
  if changed:
    raise RunDirError(f'{model_dir} holds checkpoints of another run configuration; resuming '
                     f'would change {"; ".join(changed)}. Give these flags as that run did, '
                     'or another --model_dir.')


def write_run_files(model_dir: str, flags_text: Optional[str], **configs: Any) -> None:
  """Creates `model_dir` and writes `config.json` (the configs) and `flags.txt`.

  Raises:
    RunDirError: `model_dir` is a file, or holds checkpoints of another configuration
      (`check_resumable`).
  """
  if tf.io.gfile.exists(model_dir) and not tf.io.gfile.isdir(model_dir):
    raise RunDirError(f'--model_dir={model_dir} is an existing file, not a folder.')
  check_resumable(model_dir, **configs)
  tf.io.gfile.makedirs(model_dir)
  if flags_text is not None:
    with tf.io.gfile.GFile(os.path.join(model_dir, FLAGS_FILE), 'w') as f:
      f.write(flags_text)
  with tf.io.gfile.GFile(os.path.join(model_dir, CONFIG_FILE), 'w') as f:
    f.write(to_json(**configs))


# The config.json sections of the stage trainers' runs, named as their --architecture.
_STAGE_SECTIONS = ('refiner', 'features')


def read_run_info(model_dir: str) -> RunInfo:
  """Reads the `RunInfo` of a run directory from its `config.json`.

  Raises:
    ValueError: the file is missing, not JSON, or lacks an entry; the message names it.
  """
  path = os.path.join(model_dir, CONFIG_FILE)
  if not tf.io.gfile.exists(path):
    raise ValueError(f'No {CONFIG_FILE} at {path}: not a training run directory.')
  with tf.io.gfile.GFile(path) as f:
    try:
      config = json.load(f)
    except json.JSONDecodeError as e:
      raise ValueError(f'{path} is not valid JSON: {e}') from None
  stage = next((name for name in _STAGE_SECTIONS if name in config), None)
  if stage and 'model' not in config:
    raise ValueError(
        f'{model_dir} is a {stage} run (--architecture={stage}), not a joint '
        'network: package it with `mixstereo-export --checkpoint='
        f'{model_dir} --as_pretrained --export_dir=FOLDER` and give --pretrained=FOLDER.')
  try:
    pipeline = config['pipeline']
    return RunInfo(mixture=str(pipeline['mixture']), crop_height=int(pipeline['crop_height']),
                   crop_width=int(pipeline['crop_width']),
                   model_config=models.ModelConfig.from_dict(config['model']),
                   mode=str(config.get('train', {}).get('mode', 'joint')))
  except (KeyError, TypeError) as e:
    raise ValueError(f'{path} lacks the entry {e} (expected sections "model" and '
                     '"pipeline" with mixture, crop_height, crop_width).') from None


def resolve_checkpoint(path: str) -> Tuple[str, str]:
  """(run directory, checkpoint prefix) of a run directory or a checkpoint prefix.

  A directory gives its newest checkpoint; a prefix (`runs/demo/ckpt-7000`) must exist
  (its `.index` file) and its folder is the run directory.

  Raises:
    ValueError: a directory without a checkpoint, or a prefix that does not exist.
  """
  if tf.io.gfile.isdir(path):
    prefix = tf.train.latest_checkpoint(path)
    if prefix is None:
      raise ValueError(f'No checkpoint in {path} (no "checkpoint" index file).')
    return path, prefix
  if not tf.io.gfile.exists(path + '.index'):
    raise ValueError(f'{path} is neither a run directory nor a checkpoint prefix (no '
                     f'{path}.index).')
  return os.path.dirname(path) or '.', path


def _stored_variable_count(checkpoint: str, root_child: str) -> int:
  """Variables the checkpoint's object graph reaches from the root's `root_child` node.

  Counted on the graph, not on key names: a variable shared with the optimizer may be
  stored under the optimizer's path.
  """
  graph = trackable_object_graph_pb2.TrackableObjectGraph()
  graph.ParseFromString(tf.train.load_checkpoint(checkpoint).get_tensor(
      '_CHECKPOINTABLE_OBJECT_GRAPH'))
  start = [c.node_id for c in graph.nodes[0].children if c.local_name == root_child]
  seen, stack = set(), list(start)
  while stack:
    node = stack.pop()
    if node not in seen:
      seen.add(node)
      stack.extend(c.node_id for c in graph.nodes[node].children)
  return sum(1 for n in seen
             if any(a.name == 'VARIABLE_VALUE' for a in graph.nodes[n].attributes))


def restore_model_weights(model: tf.keras.Model, checkpoint: str) -> None:
  """Reads a model's weights (not the optimizer's) from a checkpoint prefix.

  Raises:
    ValueError: the checkpoint does not hold every weight of this model.
  """
  status = tf.train.Checkpoint(model=model).read(checkpoint)
  try:
    status.assert_existing_objects_matched()
  except AssertionError as e:
    raise ValueError(f'Checkpoint {checkpoint} does not hold this model\'s weights: '
                     f'{str(e)[:300]}') from None
  status.expect_partial()  # The optimizer's slots are not needed.
  # The check above only covers objects the checkpoint graph reaches from the model; a
  # checkpoint written while layers were untracked (Keras 3 list attributes) lacks some.
  stored = _stored_variable_count(checkpoint, 'model')
  if stored < len(model.variables):
    raise ValueError(f'Checkpoint {checkpoint} holds {stored} of the model\'s '
                     f'{len(model.variables)} weights; it cannot restore this model.')


def load_run(path: str) -> Tuple[models.MixStereoNet, RunInfo]:
  """Builds the model of a training run and restores its weights.

  Args:
    path: a run directory (its newest checkpoint) or a checkpoint prefix.

  Returns:
    (model, run_info).

  Raises:
    ValueError: missing config.json / checkpoint, or weights that do not fit the model.
  """
  model_dir, checkpoint = resolve_checkpoint(path)
  run_info = read_run_info(model_dir)
  model = models.build_model(run_info.model_config)  # Creates the variables.
  restore_model_weights(model, checkpoint)
  return model, run_info
