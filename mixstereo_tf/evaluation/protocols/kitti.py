"""KITTI stereo 2015 / 2012 training sets: PSNR of both views and D1 (paper Tables 1, 4, 5).

Tables: averaged PSNR L / R, D1-all, D1-noc and EPE, with the paper's rows for the mixture
(Joulin and Williem for anaglyph; Li et al. and the oracle for diplopia) for kitti2015,
plus the separation ablation (paper Table 1, mean PSNR) for kitti2015.
"""

from typing import Dict, List

import numpy as np

from mixstereo_tf.data import records
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import paper_numbers
from mixstereo_tf.evaluation import protocol
from mixstereo_tf.evaluation import results

KITTI2015_IMAGES = 200


def score(config: results.EvalConfig, record: records.StereoSample,
          data: Dict[str, np.ndarray], pred: np.ndarray) -> Dict[str, float]:
  """D1 over all GT pixels and over the non-occluded ones (NaN for a frame without its
  `disp_noc` file: its mask would be all GT pixels), and EPE (pixels)."""
  del config
  gt, valid = data['disparity_left'], data['valid_left']
  noc = (metrics.d1_error(pred, gt, data['nonocc_left']) if record.nonocc_left else
         float('nan'))
  return {'d1_all': metrics.d1_error(pred, gt, valid), 'd1_noc': noc,
          'epe': metrics.end_point_error(pred, gt, valid)}


def tables(result: results.EvalResult) -> List[protocol.Table]:
  """Averaged PSNR and D1 with the paper's rows; kitti2015 adds the ablation table.

  Raises:
    ValueError: a partial kitti2015 run without allow_partial (`protocol.check_coverage`).
  """
  config = result.config
  protocol.check_coverage(config, result.count)
  means = result.averages
  columns = ('Method', 'PSNR L', 'PSNR R', 'D1-all', 'D1-noc', 'EPE (px)')
  rows = [{'Method': protocol.ours_label(result), 'PSNR L': means.get('psnr_left'),
           'PSNR R': means.get('psnr_right'), 'D1-all': protocol.percent(means.get('d1_all')),
           'D1-noc': protocol.percent(means.get('d1_noc')), 'EPE (px)': means.get('epe')},
          {'Method': protocol.TRIVIAL_LABEL, 'PSNR L': means.get('mixture_psnr_left'),
           'PSNR R': means.get('mixture_psnr_right')}]
  is_2015 = config.protocol == 'kitti2015'
  if is_2015:
    for method in paper_numbers.methods('kitti2015', config.mixture):
      rows.append(protocol.paper_row(protocol.PAPER_LABELS[method],
                                     paper_numbers.lookup('kitti2015', config.mixture, method)))
  name = 'KITTI 2015' if is_2015 else 'KITTI 2012'
  scored = result.counts.get('d1_all', result.count)
  without = (f'; D1 and EPE over the {scored} with ground truth' if scored < result.count
             else '')
  masked = result.counts.get('d1_noc', result.count)
  if masked < scored:
    without += f'; D1-noc over the {masked} with a non-occluded map'
  out = [(f'{name}, {config.mixture}: mean PSNR (dB) and D1 over images, {result.coverage}'
          f'{without}', columns, rows, protocol.PERCENT_COLUMNS, 2)]
  if is_2015 and result.method != 'oracle':
    ablation = [{'Method': protocol.ours_label(result), 'PSNR': means.get('psnr')}]
    for method in paper_numbers.methods('kitti2015_ablation', None):
      ablation.append(protocol.paper_row(
          protocol.PAPER_LABELS[method],
          paper_numbers.lookup('kitti2015_ablation', None, method)))
    # The paper's Table 1 compares the separation network's own outputs; restored views
    # copy the mixture's exact channels and so are not comparable with it.
    out.append((f'Separation ablation (paper Table 1; its mixture is not stated): mean PSNR '
                f'of both views (dB), colour restoration '
                f'{"on" if result.restore_colour else "off"}, {result.coverage}',
                ('Method', 'PSNR'), ablation, (), 4))
  return out


for _name, _dataset, _full in (('kitti2015', 'kitti2015', KITTI2015_IMAGES),
                               ('kitti2012', 'kitti2012', None)):
  protocol.register(protocol.Protocol(
      name=_name, dataset=_dataset, score=score, tables=tables, full_count=_full,
      description=f'KITTI stereo {_name[-4:]} training frames (_10): PSNR and D1'))
