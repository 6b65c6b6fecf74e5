"""Evaluation runs: list a benchmark's pairs, unmix their mixtures, score every image.

For each pair the mixture is synthesised exactly as training does (uint8 views -> [-1, 1]
-> `mixtures.mix`) and then quantised with `metrics.to_uint8`: the predictor sees what an
8-bit mixture image file would hold. A predictor maps that uint8 [H, W, 3] mixture to
{'left', 'right': uint8 [H, W, 3], 'disparity_left', 'disparity_right': float32 [H, W]
pixels} (an `inference.Unmixer`, `baselines.unmix_classical`, ...). Method 'oracle' (the
paper's diplopia reference: stereo on the clean pair) instead calls a pair predictor
(left_u8, right_u8) -> {'disparity_left', ...}; its rows have no view PSNR.

Per-image rows hold, by protocol (rates are FRACTIONS; tables print percent):
  every protocol: psnr_left, psnr_right, psnr (their mean; not for 'oracle'), mixture_psnr_left /
    mixture_psnr_right (the trivial baseline: the mixture itself as each view), seconds
    (the predictor's wall time);
  kitti2015 / kitti2012: d1_all (all GT pixels), d1_noc (non-occluded), epe;
  middlebury: bad1_all (GT pixels inside the 'all' mask), bad1_nonocc;
  sample: bad1, bad3, epe over the valid pixels;
  eigen: the depth metrics of `metrics.DEPTH_METRIC_NAMES` against Velodyne GT, depth =
    f · 0.54 m / d with f = P_rect_02[0, 0] of the drive's calibration.
Dataset numbers are means over images; an image without evaluated pixels is left out of
that metric's mean (`metrics.Accumulator`).
"""

import dataclasses
import os
import time
from typing import Any, Callable, Dict, List, Optional, Tuple, Union

import numpy as np
import tensorflow as tf

from mixstereo_tf import mixtures
from mixstereo_tf.data import kitti
from mixstereo_tf.data import middlebury
from mixstereo_tf.data import records
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import velodyne

PROTOCOLS = ('kitti2015', 'kitti2012', 'middlebury', 'eigen', 'sample')
METHODS = ('model', 'classical', 'oracle')
KITTI2015_IMAGES = 200
DEFAULT_EIGEN_LIST = os.path.join('data_lists', 'kitti', 'eigen_test_files.txt')
_REPO_ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

Predictor = Callable[[np.ndarray], Dict[str, np.ndarray]]
PairPredictor = Callable[[np.ndarray, np.ndarray], Dict[str, np.ndarray]]


@dataclasses.dataclass(frozen=True)
class EvalConfig:
  """What to evaluate.

  Attributes:
    protocol: one of PROTOCOLS.
    mixture: the mixture operator (a name of `mixtures.MIXTURE_NAMES`).
    data_dir: dataset root: KITTI stereo (holding `training/`), Middlebury scenes, or the
      KITTI raw root for 'eigen'; unused by 'sample'.
    method: 'model', 'classical' or 'oracle' (the caller builds the predictor; 'oracle'
      predictors take the clean pair, see the module docstring).
    allow_partial: accept a kitti2015 run over fewer than its 200 images.
    max_images: evaluate only the first N pairs (None = all).
    eigen_list: Eigen test split list; a relative path is tried from the working directory,
      then from the repository root.
    restore_colour: paper section 4.2 colour restoration of the predictor (recorded only).
    max_disparity: the model's disparity range ('sample' renders its GT below it).
    sample_scenes: procedural held-out scenes for 'sample' (None = the source's default).
    middlebury_scales: (scene, GT scale) pairs replacing the layout's disparity scale of
      those Middlebury scenes ('middlebury'; see `sources.parse_scene_scales`).
  """
  protocol: str
  mixture: str
  data_dir: Optional[str] = None
  method: str = 'model'
  allow_partial: bool = False
  max_images: Optional[int] = None
  eigen_list: str = DEFAULT_EIGEN_LIST
  restore_colour: Optional[bool] = None
  max_disparity: int = 96
  sample_scenes: Optional[int] = None
  middlebury_scales: Tuple[Tuple[str, float], ...] = ()

  def __post_init__(self):
    if self.protocol not in PROTOCOLS:
      raise ValueError(f'Unknown protocol {self.protocol!r}; valid: {", ".join(PROTOCOLS)}.')
    mixtures.get_mixture(self.mixture)  # ValueError listing the names.
    if self.method not in METHODS:
      raise ValueError(f'Unknown method {self.method!r}; valid: {", ".join(METHODS)}.')
    if self.max_images is not None and self.max_images <= 0:
      raise ValueError(f'max_images must be positive, got {self.max_images}.')
    if self.protocol != 'sample' and not self.data_dir:
      raise ValueError(f'Protocol {self.protocol!r} needs a data_dir.')
    if self.middlebury_scales and self.protocol != 'middlebury':
      raise ValueError('middlebury_scales apply to the middlebury protocol only, got '
                       f'{self.protocol!r}.')


@dataclasses.dataclass
class EvalResult:
  """Per-image rows, their means, and how much of the benchmark they cover.

  Attributes:
    config: the run's EvalConfig.
    rows: one dict per image (see the module docstring), in dataset order.
    averages: {metric: mean over images with a value}.
    counts: {metric: images with a value}.
    expected: images in the full benchmark (200 for kitti2015, else the listed count).
  """
  config: EvalConfig
  rows: List[Dict[str, Any]]
  averages: Dict[str, float]
  counts: Dict[str, int]
  expected: int

  @property
  def count(self) -> int:
    return len(self.rows)

  @property
  def partial(self) -> bool:
    return self.count < self.expected

  @property
  def coverage(self) -> str:
    """'N of M images', prefixed 'partial: ' when the benchmark was not covered."""
    text = f'{self.count} of {self.expected} images'
    return 'partial: ' + text if self.partial else text


def resolve_list_path(path: str) -> str:
  """A split list path as given, else relative to the repository root; ValueError if absent."""
  if os.path.isfile(path) or os.path.isabs(path):
    return path
  candidate = os.path.join(_REPO_ROOT, path)
  if os.path.isfile(candidate):
    return candidate
  raise ValueError(f'Split list not found: {path} (tried the working directory and '
                   f'{_REPO_ROOT}).')


def list_samples(config: EvalConfig) -> List[records.StereoSample]:
  """The protocol's pairs in evaluation order (all of them; `max_images` is not applied)."""
  if config.protocol in ('kitti2015', 'kitti2012'):
    return kitti.kitti_stereo_samples(config.data_dir, version=config.protocol[-4:])
  if config.protocol == 'middlebury':
    return middlebury.middlebury_samples(config.data_dir,
                                         scale_overrides=dict(config.middlebury_scales))
  if config.protocol == 'eigen':
    return kitti.read_split_list(resolve_list_path(config.eigen_list), config.data_dir).samples
  from mixstereo_tf.data import sample  # pylint: disable=g-import-not-at-top (textures)
  return sample.sample_records('heldout', num_scenes=config.sample_scenes,
                               max_disparity=config.max_disparity)


def synthesise_mixture(mixture: str, left_u8: np.ndarray, right_u8: np.ndarray) -> np.ndarray:
  """The uint8 [H, W, 3] mixture of two uint8 views, as training mixes them, quantised."""
  as_float = lambda u8: tf.constant(u8, tf.float32) / 127.5 - 1.0
  return metrics.to_uint8(mixtures.mix(mixture, as_float(left_u8), as_float(right_u8)).numpy())


def _check_outputs(outputs: Dict[str, np.ndarray], height: int, width: int, name: str,
                   views: bool):
  expected = {'disparity_left': (height, width)}
  if views:
    expected.update(left=(height, width, 3), right=(height, width, 3))
  for key, shape in expected.items():
    if key not in outputs or np.shape(outputs[key]) != shape:
      got = np.shape(outputs[key]) if key in outputs else 'missing'
      raise ValueError(f'{name}: predictor output {key!r} should be {shape}, got {got}.')


def _disparity_metrics(protocol: str, pred: np.ndarray, data: Dict[str, np.ndarray]
                       ) -> Dict[str, float]:
  gt, valid, nonocc = data['disparity_left'], data['valid_left'], data['nonocc_left']
  if protocol in ('kitti2015', 'kitti2012'):
    return {'d1_all': metrics.d1_error(pred, gt, valid),
            'd1_noc': metrics.d1_error(pred, gt, nonocc),
            'epe': metrics.end_point_error(pred, gt, valid)}
  if protocol == 'middlebury':
    bad = metrics.middlebury_bad(pred, gt, {'all': valid, 'nonocc': nonocc}, threshold=1.0)
    return {'bad1_all': bad['all'], 'bad1_nonocc': bad['nonocc']}
  return {'bad1': metrics.bad_pixel_rate(pred, gt, valid, 1.0),
          'bad3': metrics.bad_pixel_rate(pred, gt, valid, 3.0),
          'epe': metrics.end_point_error(pred, gt, valid)}


def _eigen_metrics(sample: records.StereoSample, pred: np.ndarray) -> Dict[str, float]:
  if not sample.calib:
    raise ValueError(f'{sample.source}: no calibration folder (the date folder holding '
                     f'calib_cam_to_cam.txt) for {sample.left}.')
  height, width = pred.shape
  gt = velodyne.eigen_ground_truth(sample.calib, kitti.velodyne_path(sample.left), height,
                                   width)
  focal = velodyne.rectified_focal_length(sample.calib, height, width)
  depth = metrics.prediction_to_kitti_depth(pred, height, width, focal)
  return metrics.depth_metrics(depth, gt)


def evaluate_sample(config: EvalConfig, sample: records.StereoSample,
                    predictor: Union[Predictor, PairPredictor]) -> Dict[str, Any]:
  """Loads, mixes, predicts and scores one pair; returns its row."""
  data = records.load_sample(sample)
  height, width = data['left'].shape[:2]
  mixture = synthesise_mixture(config.mixture, data['left'], data['right'])
  oracle = config.method == 'oracle'
  start = time.perf_counter()
  outputs = predictor(data['left'], data['right']) if oracle else predictor(mixture)
  seconds = time.perf_counter() - start
  _check_outputs(outputs, height, width, sample.name, views=not oracle)
  row = {'name': sample.name, 'height': height, 'width': width}
  if not oracle:
    row['psnr_left'] = metrics.psnr(outputs['left'], data['left'])
    row['psnr_right'] = metrics.psnr(outputs['right'], data['right'])
    row['psnr'] = (row['psnr_left'] + row['psnr_right']) / 2.0
  row['mixture_psnr_left'] = metrics.psnr(mixture, data['left'])
  row['mixture_psnr_right'] = metrics.psnr(mixture, data['right'])
  pred = np.asarray(outputs['disparity_left'], np.float32)
  if config.protocol == 'eigen':
    row.update(_eigen_metrics(sample, pred))
  else:
    row.update(_disparity_metrics(config.protocol, pred, data))
  row['seconds'] = seconds
  return row


def check_coverage(config: EvalConfig, count: int) -> None:
  """KITTI 2015 rule: an average over fewer than 200 images needs `allow_partial`."""
  if config.protocol == 'kitti2015' and count != KITTI2015_IMAGES and not config.allow_partial:
    raise ValueError(f'kitti2015 covers {count} of {KITTI2015_IMAGES} images: its average '
                     'would not be comparable with the paper\'s. Evaluate all 200 training '
                     'images, or pass --allow_partial to print a table marked '
                     f'"partial: {count} of {KITTI2015_IMAGES} images".')


def evaluate(config: EvalConfig, predictor: Union[Predictor, PairPredictor],
             progress: Optional[Callable[[int, int, Dict[str, Any]], None]] = None
             ) -> EvalResult:
  """Runs `predictor` over the protocol's pairs.

  Args:
    config: the run.
    predictor: uint8 mixture [H, W, 3] -> output dict; for method 'oracle', (left, right)
      uint8 -> disparities (module docstring).
    progress: optional callback(index, total, row) after each image.

  Raises:
    ValueError: unreadable data, malformed predictor outputs, or a partial kitti2015 run
      without `allow_partial` (raised before any image is evaluated).
  """
  samples = list_samples(config)
  expected = KITTI2015_IMAGES if config.protocol == 'kitti2015' else len(samples)
  if config.max_images is not None:
    samples = samples[:config.max_images]
  check_coverage(config, len(samples))
  rows, accumulator = [], metrics.Accumulator()
  for index, sample in enumerate(samples):
    row = evaluate_sample(config, sample, predictor)
    rows.append(row)
    accumulator.add({k: v for k, v in row.items() if isinstance(v, float)})
    if progress:
      progress(index, len(samples), row)
  counts = accumulator.counts()
  return EvalResult(config=config, rows=rows, averages=accumulator.means(), counts=counts,
                    expected=max(expected, len(rows)))



def stereo_pair_predictor(model, size_multiple: int) -> PairPredictor:
  """The stereo module of a joint model run on a clean uint8 pair (the 'oracle' method).

  Both views are padded to `size_multiple` by edge replication like `inference.Unmixer`
  pads mixtures, and the disparities ([H, W] float32 pixels) are cropped back.
  """
  from mixstereo_tf import inference  # pylint: disable=g-import-not-at-top (models)

  @tf.function(input_signature=[tf.TensorSpec([None, None, 3], tf.uint8)] * 2)
  def disparities(left, right):
    height, width = tf.shape(left)[0], tf.shape(left)[1]
    as_input = lambda u8: tf.cast(inference.pad_to_multiple(u8, size_multiple)[tf.newaxis],
                                  tf.float32) / 127.5 - 1.0
    out = model.compute_disparity(as_input(left), as_input(right), training=False)
    return {key: inference.crop_to(tf.cast(out[key][0], tf.float32), height, width)[..., 0]
            for key in ('disparity_left', 'disparity_right')}

  return lambda left, right: {key: value.numpy() for key, value in
                              disparities(tf.constant(left), tf.constant(right)).items()}
