"""Evaluation runs: list a protocol's pairs, unmix their mixtures, score every image.

For each pair the mixture is synthesised exactly as training does (uint8 views -> [-1, 1]
-> `mixtures.mix`) and then quantised to uint8: the predictor sees what an 8-bit mixture
image file would hold. The predictor is an `predictors.Unmixer`: a uint8 [H, W, 3] mixture
in, {'left', 'right': uint8 [H, W, 3], 'disparity_left', 'disparity_right': float32 [H, W]
pixels} out; one that `takes_pair` (the 'oracle') gets the clean (left, right) views and
returns disparities only, so its rows have no view PSNR.

Per-image rows (rates are FRACTIONS; tables print percent):
  name, height, width, seconds (the predictor's wall time);
  psnr_left, psnr_right, psnr (their mean; not for pair predictors);
  mixture_psnr_left / mixture_psnr_right: the trivial baseline, the mixture as each view;
  the protocol's disparity metrics (`Protocol.score`, `evaluation/protocols/`).
Dataset numbers are means over images; an image without evaluated pixels is left out of
that metric's mean (`metrics.Accumulator`).
"""

import time
from typing import Any, Callable, Dict, List, Optional

import numpy as np
import tensorflow as tf

from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import records
from mixstereo_tf.data import sources
from mixstereo_tf.data import split_lists
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import protocol as protocol_lib
from mixstereo_tf.evaluation import protocols
from mixstereo_tf.evaluation import results
from mixstereo_tf.unmixing import predictors

Progress = Callable[[int, int, Dict[str, Any]], None]


def data_config(config: results.EvalConfig) -> sources.DataConfig:
  """The `sources.DataConfig` of a run's held-out pairs.

  A partial run (`allow_partial`) skips list entries whose images are missing, with a
  warning naming their lines: a partial download evaluates what it holds.
  """
  protocol = protocols.get(config.protocol)
  if protocol.needs_data_dir and not config.data_dir:
    raise ValueError(f'Protocol {config.protocol!r} needs EvalConfig.data_dir.')
  if config.data_dir and not protocol.needs_data_dir:
    reading = ', '.join(n for n in protocols.names() if protocols.get(n).needs_data_dir)
    raise ValueError(f'EvalConfig.data_dir is given but EvalConfig.protocol='
                     f'{config.protocol!r} reads no files; name the benchmark it holds '
                     f'({reading}).')
  split_list = config.split_list
  if protocol.default_split_list:
    split_list = split_lists.resolve(split_list or protocol.default_split_list)
  return sources.DataConfig(
      dataset=protocol.dataset, data_dir=config.data_dir, split_list=split_list,
      heldout_scenes=config.heldout_scenes, max_disparity=config.max_disparity,
      middlebury_scales=config.middlebury_scales, skip_bad_pairs=config.allow_partial)


def list_samples(config: results.EvalConfig) -> List[records.StereoSample]:
  """The protocol's pairs in evaluation order (all of them; `max_images` is not applied)."""
  return sources.list_samples(data_config(config), split='heldout')


def synthesise_mixture(mixture: str, left_u8: np.ndarray, right_u8: np.ndarray) -> np.ndarray:
  """The uint8 [H, W, 3] mixture of two uint8 views, as training mixes them, quantised."""
  views = [image_range.u8_to_signed(tf.constant(v)) for v in (left_u8, right_u8)]
  return image_range.signed_to_u8(mixtures.mix(mixture, *views).numpy())


def _check_outputs(outputs: Dict[str, np.ndarray], height: int, width: int, name: str,
                   views: bool):
  expected = {'disparity_left': (height, width)}
  if views:
    expected.update(left=(height, width, 3), right=(height, width, 3))
  for key, shape in expected.items():
    if key not in outputs or np.shape(outputs[key]) != shape:
      got = np.shape(outputs[key]) if key in outputs else 'missing'
      raise ValueError(f'{name}: predictor output {key!r} should be {shape}, got {got}.')


def evaluate_sample(config: results.EvalConfig, record: records.StereoSample,
                    unmixer: predictors.Unmixer) -> Dict[str, Any]:
  """Loads, mixes, predicts and scores one pair; returns its row."""
  data = sources.load_sample(record)
  height, width = data['left'].shape[:2]
  mixture = synthesise_mixture(config.mixture, data['left'], data['right'])
  start = time.perf_counter()
  outputs = unmixer(data['left'], data['right']) if unmixer.takes_pair else unmixer(mixture)
  seconds = time.perf_counter() - start
  _check_outputs(outputs, height, width, record.name, views=not unmixer.takes_pair)
  row = {'name': record.name, 'height': height, 'width': width}
  if not unmixer.takes_pair:
    row['psnr_left'] = metrics.psnr(outputs['left'], data['left'])
    row['psnr_right'] = metrics.psnr(outputs['right'], data['right'])
    row['psnr'] = (row['psnr_left'] + row['psnr_right']) / 2.0
  row['mixture_psnr_left'] = metrics.psnr(mixture, data['left'])
  row['mixture_psnr_right'] = metrics.psnr(mixture, data['right'])
  pred = np.asarray(outputs['disparity_left'], np.float32)
  row.update(protocols.get(config.protocol).score(config, record, data, pred))
  row['seconds'] = seconds
  return row


def evaluate(config: results.EvalConfig, unmixer: predictors.Unmixer,
             progress: Optional[Progress] = None) -> results.EvalResult:
  """Runs `unmixer` over the protocol's pairs.

  Args:
    config: the run.
    unmixer: the predictor (module docstring).
    progress: optional callback(index, total, row) after each image.

  Raises:
    ValueError: unknown protocol or mixture, unreadable data, malformed predictor outputs,
      or a partial run of a protocol with a full count without `allow_partial` (raised
      before any image is evaluated).
  """
  protocol = protocols.get(config.protocol)
  mixtures.get_mixture(config.mixture)  # ValueError listing the names.
  samples = list_samples(config)
  expected = protocol.full_count or len(samples)
  if config.max_images is not None:
    samples = samples[:config.max_images]
  protocol_lib.check_coverage(config, len(samples))
  if protocol.check_record:
    for record in samples:
      protocol.check_record(record)
  rows, accumulator = [], metrics.Accumulator()
  for index, record in enumerate(samples):
    row = evaluate_sample(config, record, unmixer)
    rows.append(row)
    accumulator.add({k: v for k, v in row.items() if isinstance(v, float)})
    if progress:
      progress(index, len(samples), row)
  return results.EvalResult(config=config, method=unmixer.method,
                            restore_colour=unmixer.restore_colour, rows=rows,
                            averages=accumulator.means(), counts=accumulator.counts(),
                            expected=max(expected, len(rows)))
