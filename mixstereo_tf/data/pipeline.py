"""The tf.data pipeline: stereo pairs in, mixtures synthesised on the fly out.

Training order (issue #2): list -> parallel decode -> random crop -> photometric
augmentation (identical for both views) -> random flip-and-swap -> normalise to [-1, 1] ->
mixture `f(left, right)` (one of the configured encodings) -> optional degradation of the
mixture (`degrade.py`) -> batch -> prefetch. Every random draw is a stateless op seeded by
(seed, element index), so a seeded pipeline yields identical batches run after run.

Elements are dicts with flat string keys (see docs/DESIGN.md): `mixture`, `left`, `right`
([H, W, 3] float32 in [-1, 1]), `disparity_left`, `disparity_right` ([H, W, 1] float32,
pixels, 0 = unknown), `valid_left`, `valid_right`, `nonocc_left` ([H, W, 1] float32 0/1),
`name` (string). The loaded `disc_left` mask is dropped: it has no right-view counterpart
to swap on a flip (evaluation reads it through `sources.load_sample`).
"""

import dataclasses
from typing import Dict, Sequence

from absl import logging
import numpy as np
import tensorflow as tf

from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import degrade
from mixstereo_tf.data import records
from mixstereo_tf.data import sources

_IMAGE_KEYS = ('left', 'right')
_MAP_KEYS = ('disparity_left', 'disparity_right', 'valid_left', 'valid_right', 'nonocc_left')
# Loaded but evaluation-only: there is no right-view counterpart to swap it with on a flip.
_EVAL_ONLY_KEYS = ('disc_left',)
# Stream numbers of `_seed`: one per random draw of an element, so no two draws of any two
# elements share a stateless seed.
_STREAM_CROP_TOP, _STREAM_AUGMENT, _STREAM_FLIP, _STREAM_CROP_LEFT = 1, 2, 3, 4
_STREAM_ENCODING, _STREAM_DEGRADE = 5, 6


@dataclasses.dataclass(frozen=True)
class PipelineConfig:
  """How pairs become training or evaluation elements.

  Attributes:
    mixture: name of the composition operator (`mixstereo_tf.core.mixtures.MIXTURE_NAMES`), or a
      comma-separated list of them ('anaglyphs' = every anaglyph encoding): then each
      element is mixed with one drawn uniformly (encoding mixing; not in the paper).
    crop_height: training crop height (paper: 256 KITTI, 384 Middlebury).
    crop_width: training crop width (paper: 512 KITTI, 384 Middlebury).
    batch_size: global batch size (paper: 1).
    augment: monodepth-style photometric augmentation with probability 0.5.
    flip: random horizontal flip-and-swap with probability 0.5.
    seed: seed of every random draw (shuffle, crop, augmentation, flip).
    shuffle_buffer: 0 shuffles the whole list each epoch.
    skip_bad_pairs: drop pairs that fail to decode while training instead of stopping;
      tf.data logs each dropped element's error but does not count them (list entries with
      missing files are counted earlier, by `sources.list_samples`).
    degrade: pass each mixture through `degrade.degrade` (noise, blur, JPEG, vignetting,
      channel imbalance, as real files have them; not in the paper).
  """
  mixture: str = 'anaglyph'
  crop_height: int = 256
  crop_width: int = 512
  batch_size: int = 1
  augment: bool = True
  flip: bool = True
  seed: int = 0
  shuffle_buffer: int = 0
  skip_bad_pairs: bool = False
  degrade: bool = False

  def __post_init__(self):
    try:
      mixtures.parse_names(self.mixture)
    except ValueError as e:
      raise ValueError(f'PipelineConfig.mixture: {e}') from None
    for field in ('crop_height', 'crop_width', 'batch_size'):
      if getattr(self, field) <= 0:
        raise ValueError(f'PipelineConfig.{field} must be positive, got '
                         f'{getattr(self, field)}.')
    if self.shuffle_buffer < 0:
      raise ValueError(f'PipelineConfig.shuffle_buffer must be >= 0, got {self.shuffle_buffer}.')


def _load_fn(samples: Sequence[records.StereoSample], skipping: bool = False):
  """Returns a graph function index -> dict of decoded arrays (via tf.numpy_function);
  `skipping`: a pair that fails to decode is logged as skipped before its error drops it
  (tf.data's own warning is hidden with TensorFlow's start-up noise)."""
  keys = tuple(records.LOADED_KEYS)
  dtypes = [tf.as_dtype(records.LOADED_KEYS[k]) for k in keys]

  def load(index):
    try:
      loaded = sources.load_sample(samples[int(index)])
    except ValueError as e:
      if skipping:
        logging.warning('Skipped a pair that does not decode (skip_bad_pairs): %s', e)
      raise
    return [np.asarray(loaded[k], dtype=records.LOADED_KEYS[k]) for k in keys]

  def graph_load(index):
    tensors = tf.numpy_function(load, [index], dtypes, stateful=False)
    out = {}
    for key, tensor in zip(keys, tensors):
      if key in _IMAGE_KEYS:
        tensor.set_shape([None, None, 3])
        out[key] = image_range.u8_to_unit(tensor)
      else:
        tensor.set_shape([None, None])
        out[key] = tf.cast(tensor, tf.float32)[..., None]
    out['name'] = tf.gather(tf.constant([s.name for s in samples]), index)
    return out

  return graph_load


def _seed(seed: tf.Tensor, index: tf.Tensor, stream: int) -> tf.Tensor:
  """A stateless seed unique to (run seed, element index, draw)."""
  return tf.stack([tf.cast(seed, tf.int64) * 7919 + stream, tf.cast(index, tf.int64)])


def _pad_edge(image, height, width):
  """Pads [h, w, C] at the bottom/right to at least [height, width] by edge replication."""
  shape = tf.shape(image)
  rows = tf.minimum(tf.range(tf.maximum(shape[0], height)), shape[0] - 1)
  cols = tf.minimum(tf.range(tf.maximum(shape[1], width)), shape[1] - 1)
  return tf.gather(tf.gather(image, rows, axis=0), cols, axis=1)


def _random_crop(element, height, width, top_seed, left_seed):
  """Crops all image-aligned keys at one random window (offsets drawn from the two seeds).

  Images smaller than the crop are first padded by edge replication at the bottom/right;
  padded ground truth is marked unknown (0), not replicated.
  """
  shape = tf.shape(element['left'])
  out = dict(element)
  for key in _IMAGE_KEYS:
    out[key] = _pad_edge(element[key], height, width)
  pad = [[0, tf.maximum(height - shape[0], 0)], [0, tf.maximum(width - shape[1], 0)], [0, 0]]
  for key in _MAP_KEYS:
    out[key] = tf.pad(element[key], pad)
  shape = tf.shape(out['left'])
  top = tf.random.stateless_uniform([], top_seed, 0, shape[0] - height + 1, dtype=tf.int32)
  left = tf.random.stateless_uniform([], left_seed, 0, shape[1] - width + 1, dtype=tf.int32)
  for key in _IMAGE_KEYS + _MAP_KEYS:
    channels = 3 if key in _IMAGE_KEYS else 1
    out[key] = tf.ensure_shape(out[key][top:top + height, left:left + width],
                               [height, width, channels])
  return out


def photometric_parameters(seed) -> Dict[str, tf.Tensor]:
  """The random draws of `augment_photometric` for a stateless seed [2].

  Returns:
    'apply': bool scalar, True with probability 0.5; 'gamma' ~ U[0.8, 1.2]; 'brightness'
    ~ U[0.5, 2.0]; 'colour': [3] ~ U[0.8, 1.2] per channel (monodepth's ranges).
  """
  draws = tf.random.stateless_uniform([6], seed)
  return {'apply': draws[0] < 0.5, 'gamma': 0.8 + 0.4 * draws[1],
          'brightness': 0.5 + 1.5 * draws[2], 'colour': 0.8 + 0.4 * draws[3:6]}


def augment_photometric(left, right, seed):
  """monodepth augmentation, identical for both views, applied with probability 0.5.

  Args:
    left, right: [H, W, 3] float32 in [0, 1].
    seed: a stateless seed [2].

  Returns:
    The pair unchanged, or (when `photometric_parameters(seed)['apply']`) each view as
    clip(x ** gamma * brightness * colour, 0, 1).
  """
  params = photometric_parameters(seed)

  def change(image):
    image = tf.pow(image, params['gamma']) * params['brightness'] * params['colour']
    return tf.clip_by_value(image, 0.0, 1.0)

  return (tf.where(params['apply'], change(left), left),
          tf.where(params['apply'], change(right), right))


def flip_and_swap(element: Dict[str, tf.Tensor]) -> Dict[str, tf.Tensor]:
  """Mirrors the pair so the left view stays on the left.

  new left = flip(right), new right = flip(left), and likewise for the disparities: with the
  left pixel x matching the right pixel x - d_L, the mirrored left view's disparity is the
  mirrored right disparity. There is no right non-occlusion mask, so `nonocc_left` becomes the
  mirrored right validity.
  """
  flip = lambda x: tf.reverse(x, axis=[1])
  out = dict(element)
  out['left'], out['right'] = flip(element['right']), flip(element['left'])
  out['disparity_left'] = flip(element['disparity_right'])
  out['disparity_right'] = flip(element['disparity_left'])
  out['valid_left'] = flip(element['valid_right'])
  out['valid_right'] = flip(element['valid_left'])
  out['nonocc_left'] = flip(element['valid_right'])
  return out


def _finish(element, config: PipelineConfig, count):
  """Normalises to the network range and synthesises the mixture (paper: inputs in [-1, 1]),
  of one encoding drawn from the configured ones, degraded like a real file if asked."""
  out = dict(element)
  for key in _IMAGE_KEYS:
    out[key] = image_range.unit_to_signed(element[key])
  names = mixtures.parse_names(config.mixture)
  if len(names) == 1:
    out['mixture'] = mixtures.mix(names[0], out['left'], out['right'])
  else:
    index = tf.random.stateless_uniform([], _seed(config.seed, count, _STREAM_ENCODING), 0,
                                        len(names), dtype=tf.int32)
    out['mixture'] = mixtures.mix_one_of(names, index, out['left'], out['right'])
  if config.degrade:
    out['mixture'] = image_range.unit_to_signed(degrade.degrade(
        image_range.signed_to_unit(out['mixture']),
        _seed(config.seed, count, _STREAM_DEGRADE)))
  return out


def _check_samples(samples):
  if not samples:
    raise ValueError('The dataset is empty: expected at least one stereo pair from the '
                     'reader (check DataConfig.data_dir and DataConfig.split_list).')


def train_dataset(samples: Sequence[records.StereoSample], config: PipelineConfig,
                  start_batch: int = 0) -> tf.data.Dataset:
  """An infinite, shuffled, augmented, batched dataset of training elements, from batch
  `start_batch` of the seeded stream on (a resumed run continues the stream: the skipped
  elements are list indices, nothing is decoded for them).

  A pair that fails to decode stops iteration with an error naming it, unless
  `config.skip_bad_pairs`: then it is dropped with a logged warning naming it, each time
  the stream reaches it (a resumed stream then starts as many elements
  late as were dropped before).
  """
  _check_samples(samples)
  samples = list(samples)
  load = _load_fn(samples, config.skip_bad_pairs)
  buffer = config.shuffle_buffer or len(samples)
  ds = tf.data.Dataset.range(len(samples))
  ds = ds.shuffle(buffer, seed=config.seed, reshuffle_each_iteration=True).repeat()
  ds = ds.enumerate()  # Element counter: the stateless seeds differ for every draw.
  ds = ds.skip(start_batch * config.batch_size)

  def prepare(count, index):
    element = load(index)
    for key in _EVAL_ONLY_KEYS:
      del element[key]
    element = _random_crop(element, config.crop_height, config.crop_width,
                           _seed(config.seed, count, _STREAM_CROP_TOP),
                           _seed(config.seed, count, _STREAM_CROP_LEFT))
    if config.augment:
      element['left'], element['right'] = augment_photometric(
          element['left'], element['right'], _seed(config.seed, count, _STREAM_AUGMENT))
    if config.flip:
      coin = tf.random.stateless_uniform([], _seed(config.seed, count, _STREAM_FLIP))
      element = tf.cond(coin < 0.5, lambda e=element: flip_and_swap(e),
                        lambda e=element: dict(e))
    return _finish(element, config, count)

  ds = ds.map(prepare, num_parallel_calls=tf.data.AUTOTUNE, deterministic=True)
  if config.skip_bad_pairs:
    ds = ds.ignore_errors(log_warning=True)
  ds = ds.batch(config.batch_size, drop_remainder=True)
  return ds.prefetch(tf.data.AUTOTUNE)

