"""Errors naming the flags the user typed instead of the config fields library code names.

Library code raises errors such as "PredictorConfig.checkpoint must ..."; the tools turn
them into "--checkpoint must ..." here, for every flag defined in the process.
"""

import re
from typing import Container, Dict, Iterable, List, Optional, Sequence

from absl import app
from absl import flags

# Config fields whose flag has another name; other fields map to the flag of their name.
RENAMED = {
    'DataConfig.middlebury_scales': 'middlebury_scale',
    'EvalConfig.middlebury_scales': 'middlebury_scale',
    'ModelConfig.separation_widths': 'unet_widths',
    'ModelConfig.stereo_residual_blocks': 'num_res_blocks',
    'ModelConfig.stereo_3d_widths': 'volume_features',
    'OutputOptions.formats': 'output_format',
}


def flag_names(message: str, renamed: Optional[Dict[str, str]] = None,
               known: Optional[Container[str]] = None) -> str:
  """`message` naming the flags the user typed instead of config fields.

  `Config.field` becomes `--flag` where `known` (default: every flag defined in this
  process) holds that flag: the flag named in `renamed` (a tool's own renamings) or
  `RENAMED`, else the flag of the field's name.
  """
  names = dict(RENAMED, **(renamed or {}))
  known = flags.FLAGS if known is None else known

  def flag(match: re.Match) -> str:
    key = f'{match.group(1)}.{match.group(2)}'
    name = names.get(key, match.group(2))
    return f'--{name}' if name in known else match.group(0)

  return re.sub(r'\b([A-Z]\w*(?:Config|Options))\.(\w+)\b', flag, message)


def usage_error(error: Exception, renamed: Optional[Dict[str, str]] = None) -> app.UsageError:
  """A UsageError whose message names flags instead of config fields (`flag_names`)."""
  return app.UsageError(flag_names(str(error), renamed))


def refuse_arguments(argv, glob_flag: Optional[str] = None, passed_on: bool = False) -> None:
  """Raises app.UsageError naming the arguments after the program name in `argv` that no
  flag took (`--input glob/*.png` unquoted: the shell expands the glob, the flag takes the
  first file and the others were ignored); `glob_flag` names the flag to quote.
  `passed_on`: `argv` keeps options for another parser (Beam's), so a value after an
  option without '=' (`--runner X`) is that option's."""
  extra = [arg for index, arg in enumerate(argv[1:]) if not arg.startswith('-') and not (
      passed_on and index and argv[index].startswith('-') and '=' not in argv[index])]
  if extra:
    hint = (f"; quote a pattern so that the shell does not expand it (--{glob_flag}='dir/*"
            f".png') or give a folder" if glob_flag else '')
    raise app.UsageError(f'Unexpected argument(s), taken by no flag: '
                         f'{" ".join(extra[:5])}{" ..." if len(extra) > 5 else ""}{hint}.')


def typed_flags(argv: Sequence[str], names: Iterable[str]) -> List[str]:
  """Those of `names` typed on the command line `argv` (not read from a --flagfile).

  E.g. (['prog', '--flagfile=f', '--num_steps=5'], ['num_steps', 'num_epochs']) ->
  ['num_steps']; '--name value', '--noname' and single-dash forms count as typed.
  """
  typed = set()
  for token in argv[1:]:
    if token == '--':
      break
    name = token.lstrip('-').split('=', 1)[0]
    if token.startswith('-'):
      typed.update({name, name[2:]} if name.startswith('no') else {name})
  return [name for name in names if name in typed]
