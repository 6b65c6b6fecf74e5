"""Result reports: the protocol's tables as text or Markdown, a timing line, and CSV rows.

The tables themselves come from the run's protocol (`Protocol.tables`, laid out like the
paper's with its published rows beside ours; `evaluation/protocols/`).
"""

import csv
import importlib.metadata
import os
import platform
import shlex
import statistics
import subprocess
from typing import Any, Dict, Optional, Sequence

from mixstereo_tf.evaluation import protocols
from mixstereo_tf.evaluation import results
from mixstereo_tf.evaluation import tables


def _footer(result: results.EvalResult) -> str:
  seconds = sorted(row['seconds'] for row in result.rows)
  timing = '-'
  if seconds:
    timing = (f'{statistics.mean(seconds):.3f} s mean, {statistics.median(seconds):.3f} s '
              'median (the first image includes graph tracing)')
  return f'{result.coverage}; method {result.method}; prediction time per image: {timing}.'


def format_report(result: results.EvalResult) -> str:
  """Plain-text tables and a timing line."""
  parts = [tables.format_table(*table)
           for table in protocols.get(result.config.protocol).tables(result)]
  return '\n'.join(parts) + _footer(result) + '\n'


def code_version() -> str:
  """'mixstereo_tf <version>', with the git commit of a source checkout it runs from
  ('commit 1a2b3c4d', '+ uncommitted changes' when the package's tracked files differ)."""
  try:
    text = f'mixstereo_tf {importlib.metadata.version("mixstereo_tf")}'
  except importlib.metadata.PackageNotFoundError:
    text = 'mixstereo_tf (not installed)'
  folder = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

  def git(*arguments):
    return subprocess.run(['git', '-C', folder, *arguments], capture_output=True, text=True,
                          timeout=10, check=True).stdout.strip()

  try:
    git('ls-files', '--error-unmatch', '__init__.py')  # A tracked package, not a copy.
    commit = git('rev-parse', '--short=8', 'HEAD')
    changed = git('status', '--porcelain', '--untracked-files=no', '--', '.')
  except (OSError, subprocess.SubprocessError):
    return text  # An installed copy, or no git.
  return f'{text}, commit {commit}' + (' + uncommitted changes' if changed else '')


def provenance(command: Sequence[str], weights: Optional[str]) -> str:
  """One Markdown line saying what wrote a report: the command (shell-quoted), the code
  (`code_version`), the machine (OS, architecture, CPU cores) and the weights' identity
  (`predictors.weights_identity`; None: no weights named, e.g. the classical method or a
  shipped default)."""
  machine = f'{platform.system()} {platform.machine()}, {os.cpu_count()} CPU cores'
  named = f'; weights {weights}' if weights else ''
  shown = shlex.join([os.path.basename(command[0]), *command[1:]]) if command else ''
  return f'Written by `{shown}` ({code_version()}) on {machine}{named}.'


def markdown_report(result: results.EvalResult, source: Optional[str] = None) -> str:
  """The same tables as GitHub Markdown, after `source` (`provenance`) when given."""
  parts = [tables.markdown_table(*table)
           for table in protocols.get(result.config.protocol).tables(result)]
  head = f'{source}\n\n' if source else ''
  return head + '\n'.join(parts) + '\n' + _footer(result) + '\n'


def prepare_path(path: str, name: str) -> None:
  """Makes the folder a report file `path` will be written in, before a long evaluation.

  Raises:
    ValueError: `path` is a folder, or its folder cannot be made; the message names `name`
      (the flag or keyword of the path).
  """
  if os.path.isdir(path):
    raise ValueError(f'{name}={path} is a folder; give a file name.')
  try:
    os.makedirs(os.path.dirname(path) or '.', exist_ok=True)
  except OSError as e:
    raise ValueError(f'{name}={path}: cannot make its folder ({e.strerror}).') from None


def write_markdown(path: str, result: results.EvalResult, source: Optional[str] = None) -> None:
  """Writes `markdown_report(result, source)` to `path`."""
  with open(path, 'w', encoding='utf-8') as f:
    f.write(markdown_report(result, source))


def write_csv(path: str, rows: Sequence[Dict[str, Any]]) -> None:
  """One CSV line per image; columns in first-seen order, rates as fractions, NaN as 'nan'."""
  columns = []
  for row in rows:
    columns += [key for key in row if key not in columns]
  with open(path, 'w', newline='', encoding='utf-8') as f:
    writer = csv.DictWriter(f, fieldnames=columns, restval='')
    writer.writeheader()
    for row in rows:
      writer.writerow(row)
