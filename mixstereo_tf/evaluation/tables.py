"""Plain-text and Markdown result tables.

Rows are dicts keyed by column name (missing keys print as '-') or sequences in column
order. Floats print with `digits` decimals; values in `percent_columns` are already in
percent (5.96 -> '5.96%': multiply the fractions from `metrics` by 100); None prints as
'-', NaN as 'nan'; anything else via str().
"""

import math
from typing import Any, Collection, Mapping, Optional, Sequence, Union

Row = Union[Mapping[str, Any], Sequence[Any]]


def format_value(value: Any, percent: bool = False, digits: int = 2) -> str:
  """One cell's text (see the module docstring)."""
  if value is None:
    return '-'
  if isinstance(value, float) or (percent and isinstance(value, int)):
    if math.isnan(value):
      return 'nan'
    return f'{value:.{digits}f}' + ('%' if percent else '')
  return str(value)


def _cells(columns: Sequence[str], rows: Sequence[Row], percent_columns: Collection[str],
           digits: int):
  """Rows as lists of cell strings, plus per-column 'is numeric' flags for alignment."""
  table, numeric = [], [True] * len(columns)
  for row in rows:
    if isinstance(row, Mapping):
      values = [row.get(name) for name in columns]
    else:
      values = list(row)
      if len(values) != len(columns):
        raise ValueError(f'Row {values!r} has {len(values)} values for {len(columns)} '
                         f'columns {list(columns)}.')
    for i, value in enumerate(values):
      if value is not None and not isinstance(value, (int, float)):
        numeric[i] = False
    table.append([format_value(v, name in percent_columns, digits)
                  for name, v in zip(columns, values)])
  return table, numeric


def format_table(title: Optional[str], columns: Sequence[str], rows: Sequence[Row],
                 percent_columns: Collection[str] = (), digits: int = 2) -> str:
  """An aligned plain-text table: title line, header, rule, rows (numbers right-aligned)."""
  table, numeric = _cells(columns, rows, percent_columns, digits)
  widths = [max([len(name)] + [len(r[i]) for r in table]) for i, name in enumerate(columns)]

  def line(cells):
    return '  '.join(c.rjust(w) if num else c.ljust(w)
                     for c, w, num in zip(cells, widths, numeric)).rstrip()

  lines = [title] if title else []
  lines += [line(columns), '  '.join('-' * w for w in widths)]
  lines += [line(r) for r in table]
  return '\n'.join(lines) + '\n'


def markdown_table(title: Optional[str], columns: Sequence[str], rows: Sequence[Row],
                   percent_columns: Collection[str] = (), digits: int = 2) -> str:
  """The same table as GitHub Markdown (a bold title paragraph, numbers right-aligned)."""
  table, numeric = _cells(columns, rows, percent_columns, digits)
  lines = [f'**{title}**', ''] if title else []
  lines.append('| ' + ' | '.join(columns) + ' |')
  lines.append('| ' + ' | '.join('---:' if num else '---' for num in numeric) + ' |')
  lines += ['| ' + ' | '.join(r) + ' |' for r in table]
  return '\n'.join(lines) + '\n'
