"""Result reports: the protocol's tables as text or Markdown, a timing line, and CSV rows.

The tables themselves come from the run's protocol (`Protocol.tables`, laid out like the
paper's with its published rows beside ours; `evaluation/protocols/`).
"""

import csv
import os
import statistics
from typing import Any, Dict, Sequence

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


def markdown_report(result: results.EvalResult) -> str:
  """The same tables as GitHub Markdown."""
  parts = [tables.markdown_table(*table)
           for table in protocols.get(result.config.protocol).tables(result)]
  return '\n'.join(parts) + '\n' + _footer(result) + '\n'


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


def write_markdown(path: str, result: results.EvalResult) -> None:
  """Writes `markdown_report(result)` to `path`."""
  with open(path, 'w', encoding='utf-8') as f:
    f.write(markdown_report(result))


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
