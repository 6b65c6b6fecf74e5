"""Result tables laid out like the paper's, with its published rows beside ours.

  middlebury: per scene (PSNR L / R, bad-1 %; paper Tables 2-3 rows for Tsukuba, Venus,
    Cones, Teddy, matched case-insensitively) and the mean;
  kitti2015 / kitti2012: averages (PSNR L / R, D1-all %; paper rows for the mixture,
    e.g. Joulin and Williem for anaglyph, Li et al. and the oracle for diplopia), plus the
    separation ablation (paper Table 1, mean PSNR) for kitti2015;
  eigen: the seven depth metrics (paper Table 6: ours, Godard, Garg, Zhou);
  sample: per scene and the mean, bad-1 / bad-3 % and EPE.
Every table also has the trivial baseline: the mixture itself taken as each view.
"""

import csv
import statistics
from typing import Any, Dict, List, Optional, Sequence, Tuple

from mixstereo_tf import mixtures
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import paper_numbers
from mixstereo_tf.evaluation import runner
from mixstereo_tf.evaluation import tables

PAPER_LABELS = {
    'ours': 'paper: Zhong et al.', 'joulin': 'paper: Joulin & Kang',
    'williem': 'paper: Williem et al.', 'li': 'paper: Li & Brown (layer sep.)',
    'oracle': 'paper: oracle (clean pair)', 'godard': 'paper: Godard et al.',
    'garg': 'paper: Garg et al.', 'zhou': 'paper: Zhou et al.',
    'separation_only': 'paper: separation only', 'joint': 'paper: joint',
}
TRIVIAL_LABEL = 'mixture as each view'
PSNR_COLUMNS = ('PSNR L', 'PSNR R')
_PERCENT = ('bad-1', 'bad-1 nonocc', 'bad-3', 'D1-all', 'D1-noc')

# (title, columns, rows, percent columns, decimals); rows are dicts keyed by column.
Table = Tuple[str, Sequence[str], List[Dict[str, Any]], Sequence[str], int]


def _percent(value: Optional[float]) -> Optional[float]:
  return None if value is None else 100.0 * value


def _ours_label(result: runner.EvalResult) -> str:
  return f'this run ({result.config.method})'


def _trivial(row: Dict[str, Any]) -> Dict[str, Any]:
  return {'PSNR L': row.get('mixture_psnr_left'), 'PSNR R': row.get('mixture_psnr_right')}


def _paper_row(label: str, numbers: Dict[str, float]) -> Dict[str, Any]:
  """A paper entry in table columns (paper percentages are printed as percent already)."""
  names = {'psnr_left': 'PSNR L', 'psnr_right': 'PSNR R', 'psnr': 'PSNR', 'bad1': 'bad-1',
           'd1_all': 'D1-all'}
  row = {'Method': label}
  for key, value in numbers.items():
    row[names.get(key, key)] = value
  return row


def middlebury_table(result: runner.EvalResult) -> Table:
  """Per-scene PSNR and bad-1 with the paper's rows for its four scenes (anaglyph)."""
  columns = ('Scene', 'Method', 'PSNR L', 'PSNR R', 'bad-1', 'bad-1 nonocc')
  by_lower = {s.lower(): s for s in paper_numbers.MIDDLEBURY_SCENES}
  mixture, rows, matched = result.config.mixture, [], False
  for row in result.rows:
    rows.append({'Scene': row['name'], 'Method': _ours_label(result),
                 'PSNR L': row.get('psnr_left'), 'PSNR R': row.get('psnr_right'),
                 'bad-1': _percent(row['bad1_all']),
                 'bad-1 nonocc': _percent(row['bad1_nonocc'])})
    rows.append({'Scene': '', 'Method': TRIVIAL_LABEL, **_trivial(row)})
    scene = by_lower.get(row['name'].lower())
    for method in paper_numbers.methods('middlebury', mixture) if scene else ():
      numbers = paper_numbers.lookup('middlebury', mixture, method, scene)
      if numbers:
        matched = True
        rows.append({'Scene': '', **_paper_row(PAPER_LABELS[method], numbers)})
  means = result.averages
  rows.append({'Scene': 'mean', 'Method': _ours_label(result),
               'PSNR L': means.get('psnr_left'), 'PSNR R': means.get('psnr_right'),
               'bad-1': _percent(means.get('bad1_all')),
               'bad-1 nonocc': _percent(means.get('bad1_nonocc'))})
  for method in paper_numbers.methods('middlebury', mixture) if matched else ():
    numbers = paper_numbers.lookup('middlebury', mixture, method, 'mean')
    rows.append({'Scene': '', **_paper_row(PAPER_LABELS[method], numbers)})
  title = (f'Middlebury, {mixture}: PSNR (dB) and bad-1 (1 px, all / non-occluded '
           f'GT pixels), {result.coverage}')
  return title, columns, rows, _PERCENT, 2


def kitti_tables(result: runner.EvalResult) -> List[Table]:
  """Averaged PSNR and D1 with the paper's rows; kitti2015 adds the ablation table.

  Raises:
    ValueError: a partial kitti2015 run without allow_partial (`runner.check_coverage`).
  """
  config = result.config
  runner.check_coverage(config, result.count)
  means = result.averages
  columns = ('Method', 'PSNR L', 'PSNR R', 'D1-all', 'D1-noc', 'EPE (px)')
  rows = [{'Method': _ours_label(result), 'PSNR L': means.get('psnr_left'),
           'PSNR R': means.get('psnr_right'), 'D1-all': _percent(means.get('d1_all')),
           'D1-noc': _percent(means.get('d1_noc')), 'EPE (px)': means.get('epe')},
          {'Method': TRIVIAL_LABEL, 'PSNR L': means.get('mixture_psnr_left'),
           'PSNR R': means.get('mixture_psnr_right')}]
  if config.protocol == 'kitti2015':
    for method in paper_numbers.methods('kitti2015', config.mixture):
      rows.append(_paper_row(PAPER_LABELS[method],
                             paper_numbers.lookup('kitti2015', config.mixture, method)))
  name = 'KITTI 2015' if config.protocol == 'kitti2015' else 'KITTI 2012'
  out = [(f'{name}, {config.mixture}: mean PSNR (dB) and D1 over images, {result.coverage}',
          columns, rows, _PERCENT, 2)]
  if config.protocol == 'kitti2015' and config.method != 'oracle':
    ablation = [{'Method': _ours_label(result), 'PSNR': means.get('psnr')}]
    for method in paper_numbers.methods('kitti2015_ablation', None):
      ablation.append(_paper_row(PAPER_LABELS[method],
                                 paper_numbers.lookup('kitti2015_ablation', None, method)))
    # The paper's Table 1 compares the separation network's own outputs; restored views
    # copy the mixture's exact channels and so are not comparable with it.
    restored = config.restore_colour
    if restored is None:
      restored = mixtures.get_mixture(config.mixture).is_channel_anaglyph
    out.append((f'Separation ablation (paper Table 1; its mixture is not stated): mean PSNR '
                f'of both views (dB), colour restoration {"on" if restored else "off"}, '
                f'{result.coverage}', ('Method', 'PSNR'), ablation, (), 4))
  return out


def eigen_table(result: runner.EvalResult) -> Table:
  """The seven depth metrics with the paper's Table 6 rows (monocular)."""
  names = metrics.DEPTH_METRIC_NAMES
  rows = [{'Method': _ours_label(result), **{n: result.averages.get(n) for n in names}}]
  mixture = result.config.mixture
  for method in paper_numbers.methods('eigen', mixture):
    rows.append({'Method': PAPER_LABELS[method],
                 **paper_numbers.lookup('eigen', mixture, method)})
  title = (f'Eigen split depth (Garg crop, 1e-3..80 m), {mixture}: lower is better for '
           f'abs_rel..rmse_log, higher for a1..a3; {result.coverage}')
  return title, ('Method',) + tuple(names), rows, (), 3


def sample_table(result: runner.EvalResult) -> Table:
  """Per scene and the mean; the trivial baseline as the last row."""
  columns = ('Scene', 'Method', 'PSNR L', 'PSNR R', 'bad-1', 'bad-3', 'EPE (px)')

  def values(source):
    return {'PSNR L': source.get('psnr_left'), 'PSNR R': source.get('psnr_right'),
            'bad-1': _percent(source.get('bad1')), 'bad-3': _percent(source.get('bad3')),
            'EPE (px)': source.get('epe')}

  label = _ours_label(result)
  rows = [{'Scene': row['name'], 'Method': label, **values(row)} for row in result.rows]
  rows.append({'Scene': 'mean', 'Method': label, **values(result.averages)})
  rows.append({'Scene': 'mean', 'Method': TRIVIAL_LABEL, **_trivial(result.averages)})
  title = (f'Sample held-out set, {result.config.mixture}: PSNR (dB), bad-1 / bad-3 and '
           f'EPE over valid pixels, {result.coverage}')
  return title, columns, rows, _PERCENT, 2


def result_tables(result: runner.EvalResult) -> List[Table]:
  """The tables of the result's protocol."""
  protocol = result.config.protocol
  if protocol == 'middlebury':
    return [middlebury_table(result)]
  if protocol in ('kitti2015', 'kitti2012'):
    return kitti_tables(result)
  if protocol == 'eigen':
    return [eigen_table(result)]
  return [sample_table(result)]


def _footer(result: runner.EvalResult) -> str:
  seconds = sorted(row['seconds'] for row in result.rows)
  timing = '-'
  if seconds:
    timing = (f'{statistics.mean(seconds):.3f} s mean, {statistics.median(seconds):.3f} s '
              'median (the first image includes graph tracing)')
  return (f'{result.coverage}; method {result.config.method}; prediction time per image: '
          f'{timing}.')


def format_report(result: runner.EvalResult) -> str:
  """Plain-text tables and a timing line."""
  parts = [tables.format_table(*table) for table in result_tables(result)]
  return '\n'.join(parts) + _footer(result) + '\n'


def markdown_report(result: runner.EvalResult) -> str:
  """The same tables as GitHub Markdown."""
  parts = [tables.markdown_table(*table) for table in result_tables(result)]
  return '\n'.join(parts) + '\n' + _footer(result) + '\n'


def write_markdown(path: str, result: runner.EvalResult) -> None:
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
