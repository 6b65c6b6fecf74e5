"""KITTI raw Eigen test split: monocular depth against Velodyne points (paper Table 6).

Depth = f · 0.54 m / d with f = P_rect_02[0, 0] of the drive's calibration; the seven depth
metrics of `metrics.DEPTH_METRIC_NAMES` on the Garg crop at every cap of
`EvalConfig.depth_caps` (ground truth in (1e-3, cap), predictions clamped to [1e-3, cap]),
one table per cap with the paper's Table 6 rows of that cap (`paper_numbers.EIGEN_CAPS`:
Godard, Garg and the paper's own at 50 m, Zhou at 80 m). Row keys: `<metric>_cap<cap>`.
"""

import os
from typing import Dict, List

import numpy as np

from mixstereo_tf.data import records
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import paper_numbers
from mixstereo_tf.evaluation import protocol
from mixstereo_tf.evaluation import results
from mixstereo_tf.data import velodyne


def metric_key(name: str, cap: float) -> str:
  """The row key of a depth metric at a cap, e.g. ('abs_rel', 50.0) -> 'abs_rel_cap50'."""
  return f'{name}_cap{cap:g}'


def check_record(record: records.StereoSample) -> None:
  """ValueError naming the list line and the file when a frame lacks its calibration or
  Velodyne scan (KITTI raw's `<date>/calib_*_to_cam.txt`, `velodyne_points/data/*.bin`)."""
  if not record.calib:
    raise ValueError(f'{record.source}: no calibration folder (the date folder holding '
                     f'{", ".join(velodyne.CALIB_FILES)}) for {record.left}.')
  if not record.velodyne:
    raise ValueError(f'{record.source}: {record.left} is not in the raw-drive layout '
                     '(.../image_02/data/<frame>), so it has no Velodyne scan.')
  needed = [os.path.join(record.calib, name) for name in velodyne.CALIB_FILES]
  missing = [path for path in needed + [record.velodyne] if not os.path.isfile(path)]
  if missing:
    raise ValueError(f'{record.source}: the Eigen ground truth of {record.left} needs '
                     f'{" and ".join(missing)}, not found (KITTI raw\'s calibration and '
                     'Velodyne downloads).')


def score(config: results.EvalConfig, record: records.StereoSample,
          data: Dict[str, np.ndarray], pred: np.ndarray) -> Dict[str, float]:
  """The depth metrics of one frame against its projected Velodyne scan, at every cap."""
  del data
  check_record(record)
  height, width = pred.shape
  gt = velodyne.eigen_ground_truth(record.calib, record.velodyne, height, width)
  focal = velodyne.rectified_focal_length(record.calib, height, width)
  depth = metrics.prediction_to_kitti_depth(pred, height, width, focal)
  row = {}
  for cap in config.depth_caps:
    values = metrics.depth_metrics(depth, gt, max_depth=cap)
    row.update({metric_key(name, cap): value for name, value in values.items()})
  return row


def tables(result: results.EvalResult) -> List[protocol.Table]:
  """Per cap: the seven depth metrics with the paper's Table 6 rows of that cap."""
  names = metrics.DEPTH_METRIC_NAMES
  mixture = result.config.mixture
  out = []
  for cap in result.config.depth_caps:
    rows = [{'Method': protocol.ours_label(result),
             **{n: result.averages.get(metric_key(n, cap)) for n in names}}]
    for method in paper_numbers.methods('eigen', mixture):
      if paper_numbers.EIGEN_CAPS.get(method) == cap:
        rows.append({'Method': protocol.PAPER_LABELS[method],
                     **paper_numbers.lookup('eigen', mixture, method)})
    title = (f'Eigen split depth, cap {cap:g} m (Garg crop, 1e-3..{cap:g} m), {mixture}: '
             f'lower is better for abs_rel..rmse_log, higher for a1..a3; {result.coverage}')
    out.append((title, ('Method',) + tuple(names), rows, (), 3))
  return out


protocol.register(protocol.Protocol(
    name='eigen', dataset='kitti_raw', score=score, tables=tables,
    default_split_list='kitti/eigen_test_files.txt', check_record=check_record,
    description='KITTI raw Eigen test split (697 frames): depth metrics'))
