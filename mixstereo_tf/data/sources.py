"""One entry point from a dataset name (the `--dataset` flag) to a list of StereoSamples."""

import dataclasses
from typing import List, Optional

from mixstereo_tf.data import kitti
from mixstereo_tf.data import middlebury
from mixstereo_tf.data import records
from mixstereo_tf.data import sample

DATASETS = ('sample', 'kitti_raw', 'kitti2015', 'kitti2012', 'middlebury')
SPLITS = ('train', 'eval')


@dataclasses.dataclass(frozen=True)
class DataConfig:
  """Where the stereo pairs come from.

  Attributes:
    dataset: one of DATASETS.
    data_dir: the dataset root (not used by `sample`).
    train_list: a split list of `left right` lines relative to data_dir (`kitti_raw`).
    skip_bad_pairs: log and count pairs with missing files instead of failing.
    sample_scenes: number of procedural training scenes of the `sample` source.
    sample_height: height of `sample` scenes (None: the source's default).
    sample_width: width of `sample` scenes (None: the source's default).
    max_disparity: the network's disparity range; `sample` scenes stay inside it.
  """
  dataset: str = 'sample'
  data_dir: Optional[str] = None
  train_list: Optional[str] = None
  skip_bad_pairs: bool = False
  sample_scenes: int = 2000
  sample_height: Optional[int] = None
  sample_width: Optional[int] = None
  max_disparity: int = 96

  def __post_init__(self):
    if self.dataset not in DATASETS:
      raise ValueError(f'Unknown dataset {self.dataset!r}; valid: {", ".join(DATASETS)}.')
    if self.dataset != 'sample' and not self.data_dir:
      raise ValueError(f'--data_dir is required for --dataset={self.dataset}.')
    if self.dataset == 'kitti_raw' and not self.train_list:
      raise ValueError('--train_list is required for --dataset=kitti_raw (e.g. '
                       'data_lists/kitti/kitti_train_files.txt).')


def load_samples(config: DataConfig, split: str = 'train') -> List[records.StereoSample]:
  """Lists the pairs of a dataset; `split='eval'` selects held-out data where it differs.

  Raises:
    ValueError: nothing found, or a bad list entry (named by file and line).
  """
  if split not in SPLITS:
    raise ValueError(f'Unknown split {split!r}; valid: {SPLITS}.')
  if config.dataset == 'sample':
    sizes = {k: v for k, v in (('height', config.sample_height),
                               ('width', config.sample_width)) if v is not None}
    if split == 'train':
      return sample.sample_records('train', num_scenes=config.sample_scenes,
                                   max_disparity=config.max_disparity, **sizes)
    return sample.sample_records('heldout', max_disparity=config.max_disparity, **sizes)
  if config.dataset == 'kitti_raw':
    return kitti.read_split_list(config.train_list, config.data_dir,
                                 skip_bad_pairs=config.skip_bad_pairs).samples
  if config.dataset in ('kitti2015', 'kitti2012'):
    return kitti.kitti_stereo_samples(config.data_dir, version=config.dataset[-4:])
  return middlebury.middlebury_samples(config.data_dir)
