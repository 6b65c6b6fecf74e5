"""The one entry point from a dataset to its stereo pairs: listing by split, and loading.

`list_samples(DataConfig, split)` dispatches through a registry of datasets (`DATASETS`);
`load_sample(StereoSample)` turns one record into arrays, whether it names files or a
virtual URI of the embedded `sample` source. Training, evaluation and the benchmarks all
reach datasets through these two functions.

Splits: 'train' (what training reads) and 'heldout' (what evaluation reads). Only the
embedded `sample` source has two different sets; the other datasets list the folder or
the split list they are given for either split.
"""

import dataclasses
import math
from typing import Callable, Dict, List, Optional, Tuple

from absl import logging
import numpy as np

from mixstereo_tf.data import kitti
from mixstereo_tf.data import middlebury
from mixstereo_tf.data import records
from mixstereo_tf.data import sample
from mixstereo_tf.data import sample_files
from mixstereo_tf.data import split_lists

SPLITS = ('train', 'heldout')


@dataclasses.dataclass(frozen=True)
class DataConfig:
  """Where the stereo pairs come from.

  Attributes:
    dataset: one of DATASETS.
    data_dir: the dataset root (not used by `sample`).
    split_list: a list of `left right` lines relative to data_dir (`kitti_raw`), or of
      scene names (`middlebury`: only those scenes are read; `middlebury.read_scene_list`).
    skip_bad_pairs: log and count pairs with missing files instead of failing.
    sample_scenes: number of procedural training scenes of the `sample` source.
    heldout_scenes: number of procedural held-out scenes of `sample` (None: the source's
      default); the Motorcycle pair is always added.
    sample_height: height of `sample` scenes (None: the source's default).
    sample_width: width of `sample` scenes (None: the source's default).
    max_disparity: the network's disparity range; `sample` scenes stay inside it
      (required for `sample`).
    middlebury_scales: (scene, GT scale) pairs replacing the Middlebury layout's disparity
      scale of those scenes (`middlebury`), scene names case-insensitive.
    texture_dir: a folder of photographs texturing the `sample` training scenes (None: the
      scikit-image pictures of the split).
    realistic_scenes: `sample` training scenes with ground planes, thin poles and more
      layers (`synthetic.SceneConfig.realistic`).
    allow_evaluation_scenes: let the 'train' split read evaluation data: the Middlebury
      scenes of the paper's tables (`middlebury.EVALUATION_SCENES`) and the KITTI 2015
      training frames. Off: such a training set is refused.
    fit_disparity: 'train' split of `middlebury`: a scene whose ground truth exceeds
      max_disparity - 1 (2014 scenes at full size: hundreds of px) is shrunk by the smallest
      integer factor that fits (`StereoSample.fit_disparity`), then cropped as any pair.
  """
  dataset: str = 'sample'
  data_dir: Optional[str] = None
  split_list: Optional[str] = None
  skip_bad_pairs: bool = False
  sample_scenes: int = sample.DEFAULT_TRAIN_SCENES
  heldout_scenes: Optional[int] = None
  sample_height: Optional[int] = None
  sample_width: Optional[int] = None
  max_disparity: Optional[int] = None
  middlebury_scales: Tuple[Tuple[str, float], ...] = ()
  texture_dir: Optional[str] = None
  realistic_scenes: bool = False
  allow_evaluation_scenes: bool = False
  fit_disparity: bool = True

  def __post_init__(self):
    if self.dataset not in _LISTERS:
      raise ValueError(f'Unknown DataConfig.dataset={self.dataset!r}; valid: '
                       f'{", ".join(DATASETS)}.')
    if self.dataset != 'sample' and not self.data_dir:
      raise ValueError(f'DataConfig.data_dir is required for dataset {self.dataset!r}.')
    if self.dataset == 'sample' and (self.data_dir or self.split_list):
      given = 'data_dir' if self.data_dir else 'split_list'
      raise ValueError(f"DataConfig.{given} is given but dataset 'sample' is generated and "
                       'reads no files; name the dataset it holds (DataConfig.dataset: '
                       f'{", ".join(d for d in DATASETS if d != "sample")}).')
    if self.dataset == 'sample' and self.max_disparity is None:
      raise ValueError("DataConfig.max_disparity is required for dataset 'sample'.")
    if self.dataset == 'kitti_raw' and not self.split_list:
      raise ValueError("DataConfig.split_list is required for dataset 'kitti_raw' (e.g. "
                       'data_lists/kitti/kitti_train_files.txt).')
    if self.middlebury_scales and self.dataset != 'middlebury':
      raise ValueError(f"DataConfig.middlebury_scales apply to dataset 'middlebury' only, "
                       f'got {self.dataset!r}.')
    seen = set()
    for scene, scale in self.middlebury_scales:
      if not scene or not (math.isfinite(scale) and scale > 0):
        raise ValueError('DataConfig.middlebury_scales: expected a non-empty scene and a '
                         f'positive scale, got {scene}:{scale:g}.')
      if scene.lower() in seen:
        raise ValueError(f'DataConfig.middlebury_scales: scene {scene!r} is given twice.')
      seen.add(scene.lower())


def _sample(config: DataConfig, split: str) -> List[records.StereoSample]:
  sizes = {k: v for k, v in (('height', config.sample_height),
                             ('width', config.sample_width)) if v is not None}
  if split == 'train':
    return sample.sample_records('train', num_scenes=config.sample_scenes,
                                 max_disparity=config.max_disparity,
                                 texture_dir=config.texture_dir,
                                 realistic=config.realistic_scenes, **sizes)
  return sample.sample_records('heldout', num_scenes=config.heldout_scenes,
                               max_disparity=config.max_disparity, **sizes)


def _kitti_raw(config: DataConfig, split: str) -> List[records.StereoSample]:
  del split  # The split list is the split.
  split_list = kitti.read_split_list(split_lists.resolve(config.split_list), config.data_dir,
                                     skip_bad_pairs=config.skip_bad_pairs)
  if split_list.skipped:
    total = len(split_list.samples) + len(split_list.skipped)
    logging.warning('skip_bad_pairs: skipped %d of %d pairs of %s (missing files), at '
                    'lines %s.', len(split_list.skipped), total, config.split_list,
                    kitti.line_ranges(split_list.skipped_lines))
  return split_list.samples


def _refuse_evaluation_data(config: DataConfig, what: str) -> None:
  if not config.allow_evaluation_scenes:
    raise ValueError(f'{what} in {config.data_dir} are the paper\'s evaluation data and '
                     'would make its tables meaningless as training data; remove them, or '
                     'set DataConfig.allow_evaluation_scenes to train on them anyway.')


def _kitti_stereo(version: str) -> Callable[[DataConfig, str], List[records.StereoSample]]:

  def lister(config: DataConfig, split: str) -> List[records.StereoSample]:
    samples = kitti.kitti_stereo_samples(config.data_dir, version=version)
    if split == 'train' and version == '2015':
      _refuse_evaluation_data(config, f'The {len(samples)} KITTI 2015 training frames')
    return samples

  return lister


def _middlebury(config: DataConfig, split: str) -> List[records.StereoSample]:
  samples = middlebury.middlebury_samples(config.data_dir,
                                          scale_overrides=dict(config.middlebury_scales))
  if config.split_list:
    path = split_lists.resolve(config.split_list)
    samples, missing = middlebury.select_scenes(samples, middlebury.read_scene_list(path),
                                                path)
    if missing:
      logging.warning('%d scene(s) of %s not in %s: %s.', len(missing), path,
                      config.data_dir, ', '.join(missing))
  evaluation = [s.name for s in samples if middlebury.is_evaluation_scene(s.name)]
  if split == 'train' and evaluation:
    _refuse_evaluation_data(config, f'The Middlebury scenes {", ".join(evaluation)}')
  if split == 'train' and config.fit_disparity and config.max_disparity:
    samples = [dataclasses.replace(s, fit_disparity=config.max_disparity) for s in samples]
  return samples


_LISTERS: Dict[str, Callable[[DataConfig, str], List[records.StereoSample]]] = {
    'sample': _sample,
    'kitti_raw': _kitti_raw,
    'kitti2015': _kitti_stereo('2015'),
    'kitti2012': _kitti_stereo('2012'),
    'middlebury': _middlebury,
}
DATASETS = tuple(_LISTERS)


def list_samples(config: DataConfig, split: str = 'train') -> List[records.StereoSample]:
  """Lists the pairs of a dataset's split (see the module docstring).

  With `config.skip_bad_pairs`, list entries whose files are missing are dropped and one
  warning reports how many, with their line numbers.

  Raises:
    ValueError: unknown split, nothing found, or a bad list entry (named by file and line).
  """
  if split not in SPLITS:
    raise ValueError(f'Unknown split {split!r}; valid: {", ".join(SPLITS)}.')
  return _LISTERS[config.dataset](config, split)


def load_sample(record: records.StereoSample) -> Dict[str, np.ndarray]:
  """Loads a record into NumPy arrays with exactly the keys of `records.LOADED_KEYS`.

  Images are converted to 8-bit RGB whatever their file format.

  Raises:
    ValueError: a file is missing or unreadable, or the views differ in size; the message
      names the file and `record.source`.
  """
  if record.is_virtual:
    return sample.load_virtual(record)
  return sample_files.load_file_sample(record)
