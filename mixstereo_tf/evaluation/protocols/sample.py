"""The embedded held-out set (procedural scenes + Motorcycle): PSNR, bad-1 / bad-3, EPE."""

from typing import Dict, List

import numpy as np

from mixstereo_tf.data import records
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import protocol
from mixstereo_tf.evaluation import results


def score(config: results.EvalConfig, record: records.StereoSample,
          data: Dict[str, np.ndarray], pred: np.ndarray) -> Dict[str, float]:
  """bad-1, bad-3 and EPE over the valid pixels."""
  del config, record
  gt, valid = data['disparity_left'], data['valid_left']
  return {'bad1': metrics.bad_pixel_rate(pred, gt, valid, 1.0),
          'bad3': metrics.bad_pixel_rate(pred, gt, valid, 3.0),
          'epe': metrics.end_point_error(pred, gt, valid)}


def tables(result: results.EvalResult) -> List[protocol.Table]:
  """Per scene and the mean; the trivial baseline as the last row."""
  columns = ('Scene', 'Method', 'PSNR L', 'PSNR R', 'bad-1', 'bad-3', 'EPE (px)')

  def values(source):
    return {'PSNR L': source.get('psnr_left'), 'PSNR R': source.get('psnr_right'),
            'bad-1': protocol.percent(source.get('bad1')),
            'bad-3': protocol.percent(source.get('bad3')), 'EPE (px)': source.get('epe')}

  label = protocol.ours_label(result)
  rows = [{'Scene': row['name'], 'Method': label, **values(row)} for row in result.rows]
  rows.append({'Scene': 'mean', 'Method': label, **values(result.averages)})
  rows.append({'Scene': 'mean', 'Method': protocol.TRIVIAL_LABEL,
               **protocol.trivial(result.averages)})
  title = (f'Sample held-out set, {result.config.mixture}: PSNR (dB), bad-1 / bad-3 and '
           f'EPE over valid pixels, {result.coverage}')
  return [(title, columns, rows, protocol.PERCENT_COLUMNS, 2)]


protocol.register(protocol.Protocol(
    name='sample', dataset='sample', score=score, tables=tables, needs_data_dir=False,
    description='embedded held-out procedural scenes and Motorcycle (nothing to download)'))
