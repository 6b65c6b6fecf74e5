"""Middlebury scene folders: PSNR of both views and bad-1 (paper Tables 2-3).

Per scene: PSNR L / R and bad-1 (1 px, on the GT scaled to pixels) over all GT pixels
(inside `all.png` when present) and over the non-occluded ones, with the paper's rows for
Tsukuba, Venus, Cones and Teddy (matched case-insensitively) and the mean.
"""

from typing import Dict, List

import numpy as np

from mixstereo_tf.data import records
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import paper_numbers
from mixstereo_tf.evaluation import protocol
from mixstereo_tf.evaluation import results


def score(config: results.EvalConfig, record: records.StereoSample,
          data: Dict[str, np.ndarray], pred: np.ndarray) -> Dict[str, float]:
  """bad-1 over all GT pixels and over the non-occluded ones (NaN for a scene without a
  non-occluded mask: its mask would be all GT pixels)."""
  del config
  bad = metrics.middlebury_bad(pred, data['disparity_left'],
                               {'all': data['valid_left'], 'nonocc': data['nonocc_left']},
                               threshold=1.0)
  return {'bad1_all': bad['all'],
          'bad1_nonocc': bad['nonocc'] if record.nonocc_left else float('nan')}


def tables(result: results.EvalResult) -> List[protocol.Table]:
  """Per-scene PSNR and bad-1 with the paper's rows for its four scenes (anaglyph)."""
  columns = ('Scene', 'Method', 'PSNR L', 'PSNR R', 'bad-1', 'bad-1 nonocc')
  by_lower = {s.lower(): s for s in paper_numbers.MIDDLEBURY_SCENES}
  mixture, rows, matched = result.config.mixture, [], set()
  ours = protocol.ours_label(result)
  for row in result.rows:
    rows.append({'Scene': row['name'], 'Method': ours,
                 'PSNR L': row.get('psnr_left'), 'PSNR R': row.get('psnr_right'),
                 'bad-1': protocol.percent(row['bad1_all']),
                 'bad-1 nonocc': protocol.percent(row['bad1_nonocc'])})
    rows.append({'Scene': '', 'Method': protocol.TRIVIAL_LABEL, **protocol.trivial(row)})
    scene = by_lower.get(row['name'].lower())
    for method in paper_numbers.methods('middlebury', mixture) if scene else ():
      numbers = paper_numbers.lookup('middlebury', mixture, method, scene)
      if numbers:
        matched.add(scene)
        rows.append({'Scene': '', **protocol.paper_row(protocol.PAPER_LABELS[method],
                                                       numbers)})
  means = result.averages
  rows.append({'Scene': 'mean', 'Method': ours,
               'PSNR L': means.get('psnr_left'), 'PSNR R': means.get('psnr_right'),
               'bad-1': protocol.percent(means.get('bad1_all')),
               'bad-1 nonocc': protocol.percent(means.get('bad1_nonocc'))})
  # The paper's mean is over its four scenes: beside a mean over all of them only, every
  # one with ground truth.
  scored = result.counts.get('bad1_all', len(result.rows))
  every = (matched == set(paper_numbers.MIDDLEBURY_SCENES) and
           len(result.rows) == len(matched) == scored)
  for method in paper_numbers.methods('middlebury', mixture) if every else ():
    numbers = paper_numbers.lookup('middlebury', mixture, method, 'mean')
    rows.append({'Scene': '', **protocol.paper_row(protocol.PAPER_LABELS[method], numbers)})
  title = (f'Middlebury, {mixture}: PSNR (dB) and bad-1 (1 px) over all GT pixels and over '
           f'the non-occluded ones (the paper does not say which pixels its bad-1 counts), '
           f'{result.coverage}')
  if scored < len(result.rows):
    title += f'; bad-1 over the {scored} scenes with ground truth'
  masked = result.counts.get('bad1_nonocc', scored)
  if masked < scored:
    title += f'; bad-1 nonocc over the {masked} with a non-occluded mask'
  if matched and not every:
    title += (f"; the paper's means (over {', '.join(paper_numbers.MIDDLEBURY_SCENES)}) "
              'are left out: this mean is not over exactly those scenes')
  return [(title, columns, rows, protocol.PERCENT_COLUMNS, 2)]


protocol.register(protocol.Protocol(
    name='middlebury', dataset='middlebury', score=score, tables=tables,
    description='Middlebury scene folders (2001-2021 layouts): PSNR and bad-1'))
