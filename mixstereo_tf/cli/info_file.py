"""An input's side-car `<name>_info.json`: what was done (`write_info`) and what was asked.

`mixstereo-unmix` and the batch pipeline record under `request` the predictor's settings
(`media.OutputOptions.settings`: the PredictorConfig as the flags gave it, `mixture='auto'`
included, and the identity of the weights it loads, so that a checkpoint retrained at the
same path counts as another request) and how the results are written (layout, stereo
formats, colour-map span). A batch run skips an input whose complete results were asked
for in the same way, and refuses (a dead letter naming the differences) results asked for
otherwise, which it would otherwise keep silently beside this run's.
"""

import dataclasses
import json
import os
from typing import Dict, FrozenSet, List, Optional

from mixstereo_tf.cli import input_listing
from mixstereo_tf.cli import media
from mixstereo_tf.unmixing import predictors


def describe(options: media.OutputOptions) -> Dict[str, object]:
  """The JSON form of what `options` ask for (tuples as lists, as they read back)."""
  return json.loads(json.dumps({
      'settings': options.settings, 'layout': options.layout,
      'output_formats': list(options.formats),
      'max_display_disparity': options.max_display_disparity}))


def _flat(request: Dict[str, object]) -> Dict[str, object]:
  """{name: value}: the settings' fields beside the output options (the stereo formats as
  a sorted list: their order writes the same files)."""
  flat = dict(request.get('settings') or {})
  flat.update((key, value) for key, value in request.items() if key != 'settings')
  if isinstance(flat.get('output_formats'), list):
    flat['output_formats'] = sorted(map(str, flat['output_formats']))
  return flat


def differences(recorded: Optional[object], current: Dict[str, object]) -> List[str]:
  """'name: recorded -> current' for every field `current` (`describe`'s) asks otherwise
  than the `recorded` request of an info file; [] when they agree or nothing is recorded
  (results written before requests were recorded). A field the recorded request lacks
  (written before the field was recorded, e.g. `weights`) is not compared."""
  if not isinstance(recorded, dict):
    return []
  new = _flat(current)
  old = _default_named(_flat(recorded), new)
  return [f'{key}: {old.get(key)!r} -> {new.get(key)!r}'
          for key in sorted(old) if old[key] != new.get(key)]


def _default_named(old: Dict[str, object], new: Dict[str, object]) -> Dict[str, object]:
  """A recorded request for the shipped default that does not name it (written before runs
  named the model they load, `predictors.with_weights_named`) read as naming the model
  `new` names, where that is the same default: upgrading does not make every earlier
  result a difference."""
  if old.get('method') != 'model' or any(old.get(key) for key in
                                         ('pretrained', 'checkpoint', 'saved_model')):
    return old
  config = predictors.PredictorConfig('model', mixture=old.get('mixture'))
  named = predictors.with_weights_named(config).pretrained
  if named is None or named != new.get('pretrained'):
    return old
  return dict(old, pretrained=named, weights=new.get('weights'))


def input_stamp(path: str) -> Dict[str, int]:
  """{'input_size', 'input_mtime_ns'} of an input file, recorded in its info file: a batch
  rerun redoes an input replaced since (`changed`)."""
  stat = os.stat(path)
  return {'input_size': stat.st_size, 'input_mtime_ns': stat.st_mtime_ns}


def changed(info: Dict[str, object], path: str) -> bool:
  """Whether the input at `path` differs in size or modification time from the one an
  info file recorded (False where it recorded none, or the file is gone)."""
  if 'input_size' not in info or not os.path.exists(path):
    return False
  return {key: info.get(key) for key in ('input_size', 'input_mtime_ns')} != input_stamp(path)


INFO_SUFFIX = '_info.json'
# Written before an input's results and removed with its info written (`begin_outputs`).
UNFINISHED_SUFFIX = '_unfinished.json'


@dataclasses.dataclass(frozen=True)
class Earlier:
  """What earlier runs into an output folder left (`read_earlier`).

  Attributes:
    names: {real path of an input: its output name}.
    outputs: real paths of the files their info files list (the info files included):
      never inputs of a later run, whose glob over a tree holding the folder matches them.
  """
  names: Dict[str, str] = dataclasses.field(default_factory=dict)
  outputs: FrozenSet[str] = frozenset()


def read_json(path: str) -> Optional[Dict[str, object]]:
  """The JSON object a file holds; None when it cannot be read or parsed, or holds no
  object (a half-written or foreign file)."""
  try:
    with open(path, encoding='utf-8') as f:
      value = json.load(f)
  except (OSError, ValueError):
    return None
  return value if isinstance(value, dict) else None


def _named_for(file_name: str, name: str) -> bool:
  """Whether `file_name` is named as a result of the input named `name`: `<name>_*` or
  `<name>.*` (`media.write_image_outputs`, `stereo_formats`, the video jobs)."""
  return file_name.startswith((name + '_', name + '.'))


def read_earlier(output_dir: str) -> Earlier:
  """The `Earlier` of the info files in `output_dir` (empty when it does not exist;
  unreadable files skipped)."""
  if not os.path.isdir(output_dir):
    return Earlier()
  names, outputs = {}, set()
  listing = sorted(os.listdir(output_dir))
  for file_name in listing:
    if file_name.endswith(UNFINISHED_SUFFIX):
      _unfinished(output_dir, file_name, listing, names, outputs)
    if not file_name.endswith(INFO_SUFFIX):
      continue
    path = os.path.join(output_dir, file_name)
    info = read_json(path)
    if info is None:
      continue
    source, files = info.get('input'), info.get('files')
    if isinstance(source, str):
      names[os.path.realpath(source)] = file_name[:-len(INFO_SUFFIX)]
    outputs.add(os.path.realpath(path))
    outputs.update(os.path.realpath(os.path.join(output_dir, name)) for name in
                   (files if isinstance(files, list) else []) if isinstance(name, str))
  return Earlier(names, frozenset(outputs))


def begin_outputs(output_dir: str, item: input_listing.MediaItem) -> None:
  """Writes `<name>_unfinished.json` (the input's path) before an input's results are
  written; `write_info` removes it. A run killed meanwhile leaves results that no info
  lists: `read_earlier` then takes that name's files (`<name>_*`, `<name>.*`) for results,
  so a rerun over a tree holding the output folder redoes the input instead of refusing
  them as inputs its outputs could overwrite (`input_listing.prepare_output_dir`)."""
  with open(os.path.join(output_dir, item.name + UNFINISHED_SUFFIX), 'w',
            encoding='utf-8') as f:
    json.dump({'input': os.path.abspath(item.path)}, f)


def _unfinished(output_dir: str, file_name: str, listing: List[str], names: Dict[str, str],
                outputs: set) -> None:
  """Adds an unfinished input's name and files (`begin_outputs`) to `read_earlier`'s."""
  name = file_name[:-len(UNFINISHED_SUFFIX)]
  source = (read_json(os.path.join(output_dir, file_name)) or {}).get('input')
  if isinstance(source, str):
    names.setdefault(os.path.realpath(source), name)
  outputs.update(os.path.realpath(os.path.join(output_dir, other)) for other in listing
                 if _named_for(other, name))


def _stale_files(path: str, name: str, files: List[str]) -> List[str]:
  """The files an earlier `<name>_info.json` at `path` lists that are not in `files`:
  plain names of that input's outputs (`<name>_*` or `<name>.*`), nothing else."""
  earlier = (read_json(path) or {}).get('files')
  if not isinstance(earlier, list):
    return []
  return [old for old in earlier if isinstance(old, str) and old not in files
          and os.path.basename(old) == old and old not in ('.', '..')
          and _named_for(old, name)]


def write_info(output_dir: str, item: input_listing.MediaItem, info: Dict[str, object],
               request: Optional[Dict] = None) -> str:
  """Writes `<name>_info.json` beside an input's results: what was done to which file (its
  absolute path: a rerun from another folder reads it alike; its size and modification
  time, `input_stamp`; the mixture used and detected, with its confidence, the disparity
  range searched, the network's shift and scale, the method, the seconds spent), the files
  written and what was asked (`describe`). Files an earlier run's info listed for this name
  and this run did not write (another layout, a `disparity16` not written now) are removed
  first, so that the folder holds one run's results and its info describes all of them.
  The file is replaced at once (two runs into one folder left a corrupt one)."""
  path = os.path.join(output_dir, item.name + INFO_SUFFIX)
  for stale in _stale_files(path, item.name, list(info.get('files', []))):
    if os.path.isfile(os.path.join(output_dir, stale)):
      os.remove(os.path.join(output_dir, stale))
  with open(path + '.tmp', 'w', encoding='utf-8') as f:  # Replaced at once: never half written.
    json.dump(dict(info, input=os.path.abspath(item.path), **input_stamp(item.path),
                   **({'request': request} if request else {})), f, indent=2, sort_keys=True)
  os.replace(path + '.tmp', path)
  unfinished = os.path.join(output_dir, item.name + UNFINISHED_SUFFIX)
  if os.path.exists(unfinished):
    os.remove(unfinished)
  return path
