"""One entry point from a dataset name (the `--dataset` flag) to a list of StereoSamples."""

import dataclasses
import math
from typing import List, Optional, Sequence, Tuple

from absl import logging

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
    middlebury_scales: (scene, GT scale) pairs replacing the Middlebury layout's disparity
      scale of those scenes (`middlebury`; see `parse_scene_scales`).
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
  middlebury_scales: Tuple[Tuple[str, float], ...] = ()

  def __post_init__(self):
    if self.dataset not in DATASETS:
      raise ValueError(f'Unknown dataset {self.dataset!r}; valid: {", ".join(DATASETS)}.')
    if self.dataset != 'sample' and not self.data_dir:
      raise ValueError(f'--data_dir is required for --dataset={self.dataset}.')
    if self.dataset == 'kitti_raw' and not self.train_list:
      raise ValueError('--train_list is required for --dataset=kitti_raw (e.g. '
                       'data_lists/kitti/kitti_train_files.txt).')
    if self.middlebury_scales and self.dataset != 'middlebury':
      raise ValueError(f'--middlebury_scale applies to --dataset=middlebury only, got '
                       f'--dataset={self.dataset}.')
    _check_scene_scales(self.middlebury_scales, 'middlebury_scale',
                        [f'{scene}:{scale:g}' for scene, scale in self.middlebury_scales])


def _check_scene_scales(pairs: Sequence[Tuple[str, float]], flag: str,
                        items: Sequence[str]) -> None:
  """ValueError naming `--flag` and the item (text of the pair) unless every scale is
  positive and finite and every scene (case-insensitive) appears once."""
  seen = set()
  for (scene, scale), item in zip(pairs, items):
    if not scene or not (math.isfinite(scale) and scale > 0):
      raise ValueError(f'--{flag}: expected scene:scale with a non-empty scene and a positive '
                       f'scale (e.g. tsukuba:16), got {item!r}.')
    if scene.lower() in seen:
      raise ValueError(f'--{flag}: scene {scene!r} is given twice ({item!r}).')
    seen.add(scene.lower())


def parse_scene_scales(items: Sequence[str],
                       flag: str = 'middlebury_scale') -> Tuple[Tuple[str, float], ...]:
  """Parses `scene:scale` items (e.g. ['tsukuba:16', 'venus:8']) into (scene, scale) pairs.

  Scene names are matched case-insensitively by the Middlebury reader.

  Raises:
    ValueError: an item is not `scene:scale` with a positive finite scale, or a scene is
      given twice; the message names `--flag` and the item.
  """
  pairs = []
  for item in items:
    scene, _, value = item.rpartition(':')
    try:
      scale = float(value)
    except ValueError:
      raise ValueError(f'--{flag}: expected scene:scale with a number as scale (e.g. '
                       f'tsukuba:16), got {item!r}.') from None
    pairs.append((scene.strip(), scale))
  _check_scene_scales(pairs, flag, items)
  return tuple(pairs)


def load_samples(config: DataConfig, split: str = 'train') -> List[records.StereoSample]:
  """Lists the pairs of a dataset; `split='eval'` selects held-out data where it differs.

  With `config.skip_bad_pairs`, list entries whose files are missing are dropped and one
  warning reports how many, with their line numbers.

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
    split_list = kitti.read_split_list(config.train_list, config.data_dir,
                                       skip_bad_pairs=config.skip_bad_pairs)
    if split_list.skipped:
      total = len(split_list.samples) + len(split_list.skipped)
      logging.warning('--skip_bad_pairs: skipped %d of %d pairs of %s (missing files), at '
                      'lines %s.', len(split_list.skipped), total, config.train_list,
                      ', '.join(str(n) for n in split_list.skipped_lines))
    return split_list.samples
  if config.dataset in ('kitti2015', 'kitti2012'):
    return kitti.kitti_stereo_samples(config.data_dir, version=config.dataset[-4:])
  return middlebury.middlebury_samples(config.data_dir,
                                       scale_overrides=dict(config.middlebury_scales))
