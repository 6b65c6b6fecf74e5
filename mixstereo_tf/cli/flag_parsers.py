"""Parsers of flag values that need more than absl's types: --swap_eyes (a boolean or
'auto'), --output_format (names, repeated or comma-separated), --mixing_weight ('auto' or a
number in (0, 1)), --descreen ('auto', 'off' or a period) and --middlebury_scale items
(scene:scale). Each raises an error naming the flag and the value at fault.
"""

from typing import Optional, Sequence, Tuple

from absl import app
from absl import flags

from mixstereo_tf.classical import diplopia_weight
from mixstereo_tf.classical import halftone
from mixstereo_tf.unmixing import eye_order


class SwapEyesParser(flags.ArgumentParser):
  """--swap_eyes: a boolean flag (--swap_eyes, --noswap_eyes) that also takes 'auto'."""

  def parse(self, argument):
    """False, True or eye_order.AUTO from absl's boolean spellings or 'auto'."""
    if isinstance(argument, str) and argument.strip().lower() == eye_order.AUTO:
      return eye_order.AUTO
    try:
      return flags.BooleanParser().parse(argument)
    except ValueError:
      raise ValueError(f'expected true, false or {eye_order.AUTO!r}, got {argument!r}') from None

  def flag_type(self):
    return 'bool or auto'


class NameListParser(flags.ArgumentParser):
  """One occurrence of a repeatable flag that also takes comma-separated names
  (--output_format=mpo,jps as --output_format=mpo --output_format=jps): the list of its
  names, each one of `names`; the flag's value is a list of such lists (`flattened`)."""

  def __init__(self, names: Sequence[str]):
    super().__init__()
    self.names = tuple(names)

  def parse(self, argument):
    """[name, ...] of 'name[,name...]' (a list given as a default is checked as it is)."""
    items = argument if isinstance(argument, (list, tuple)) else str(argument).split(',')
    items = [str(item).strip() for item in items]
    for item in items:
      if item not in self.names:
        raise ValueError(f'{item!r} is not one of {", ".join(self.names)}')
    return items

  def flag_type(self):
    return 'comma-separated list of ' + '|'.join(self.names)


def flattened(value: Sequence[Sequence[str]]) -> Tuple[str, ...]:
  """The names of a NameListParser flag's value, in the order given."""
  return tuple(name for names in value for name in names)


def parse_mixing_weight(text: Optional[str]):
  """--mixing_weight: None (unset: 1/2), 'auto', or a number in (0, 1); UsageError naming
  the flag otherwise."""
  if text is None or text.strip().lower() == diplopia_weight.AUTO:
    return None if text is None else diplopia_weight.AUTO
  try:
    return diplopia_weight.check_weight(float(text))
  except ValueError as e:
    raise app.UsageError(f"--mixing_weight: expected 'auto' or a number in (0, 1), got "
                         f'{text!r} ({e})') from None


def parse_descreen(text: str):
  """--descreen: 'auto', 'off' or a period in pixels (> 1); UsageError naming the flag."""
  if text.strip().lower() in (halftone.AUTO, halftone.OFF):
    return text.strip().lower()
  try:
    return halftone.check_period(float(text))
  except ValueError:
    raise app.UsageError(f"--descreen: expected 'auto', 'off' or a screen period in pixels "
                         f'above 1, got {text!r}.') from None


def parse_scene_scales(items: Sequence[str]) -> Tuple[Tuple[str, float], ...]:
  """Parses `scene:scale` items (['tsukuba:16', 'venus:8']) into (scene, scale) pairs.

  Scales are checked by the configs (positive, each scene once).

  Raises:
    app.UsageError: an item is not `scene:scale` with a number as scale, naming the item.
  """
  pairs = []
  for item in items:
    scene, _, value = item.rpartition(':')
    try:
      scale = float(value)
    except ValueError:
      raise app.UsageError(f'--middlebury_scale: expected scene:scale with a number as scale '
                           f'(e.g. tsukuba:16), got {item!r}.') from None
    pairs.append((scene.strip(), scale))
  return tuple(pairs)
