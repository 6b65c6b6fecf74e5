"""How an experiment writes its Markdown report: one place for every results file."""

import os
from typing import Sequence


def write(path: str, lines: Sequence[str]) -> None:
  """Writes `lines` to `path` (its folder made when missing), one per line and the file
  ending with exactly one newline, and prints them."""
  text = '\n'.join(lines).rstrip('\n') + '\n'
  os.makedirs(os.path.dirname(path) or '.', exist_ok=True)
  with open(path, 'w') as handle:
    handle.write(text)
  print(text, end='')
