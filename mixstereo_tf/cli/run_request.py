"""What an input's results were asked for with, recorded in its `<name>_info.json`.

`mixstereo-unmix` and the batch pipeline record under `request` the predictor's settings
(`media.OutputOptions.settings`: the PredictorConfig as the flags gave it, `mixture='auto'`
included) and how the results are written (layout, stereo formats, colour-map span). A
batch run skips an input whose complete results were asked for in the same way, and
refuses (a dead letter naming the differences) results asked for otherwise, which it would
otherwise keep silently beside this run's.
"""

import json
from typing import Dict, List, Optional

from mixstereo_tf.cli import media


def describe(options: media.OutputOptions) -> Dict[str, object]:
  """The JSON form of what `options` ask for (tuples as lists, as they read back)."""
  return json.loads(json.dumps({
      'settings': options.settings, 'layout': options.layout,
      'output_formats': list(options.formats),
      'max_display_disparity': options.max_display_disparity}))


def _flat(request: Dict[str, object]) -> Dict[str, object]:
  """{name: value}: the settings' fields beside the output options."""
  flat = dict(request.get('settings') or {})
  flat.update((key, value) for key, value in request.items() if key != 'settings')
  return flat


def differences(recorded: Optional[object], current: Dict[str, object]) -> List[str]:
  """'name: recorded -> current' for every field `current` (`describe`'s) asks otherwise
  than the `recorded` request of an info file; [] when they agree or nothing is recorded
  (results written before requests were recorded)."""
  if not isinstance(recorded, dict):
    return []
  old, new = _flat(recorded), _flat(current)
  return [f'{key}: {old.get(key)!r} -> {new.get(key)!r}'
          for key in sorted(set(old) | set(new)) if old.get(key) != new.get(key)]
