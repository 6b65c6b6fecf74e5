"""What an evaluation run is asked to do (`EvalConfig`) and what it found (`EvalResult`)."""

import dataclasses
from typing import Any, Dict, List, Optional, Tuple


@dataclasses.dataclass(frozen=True)
class EvalConfig:
  """What to evaluate.

  Attributes:
    protocol: a registered protocol name (`evaluation.protocols.names()`).
    mixture: the mixture operator the pairs are mixed with (`mixtures.MIXTURE_NAMES`).
    data_dir: dataset root: KITTI stereo (holding `training/`), Middlebury scenes, or the
      KITTI raw root for 'eigen'; unused by protocols without data ('sample').
    allow_partial: accept a run over fewer images than the protocol's full count.
    max_images: evaluate only the first N pairs (None = all).
    split_list: the split list of list-based protocols ('eigen'); None = the protocol's
      default list shipped with the package.
    max_disparity: the predictor's disparity range ('sample' renders its GT below it).
    heldout_scenes: procedural held-out scenes for 'sample' (None = the source's default).
    middlebury_scales: (scene, GT scale) pairs replacing the layout's disparity scale of
      those Middlebury scenes ('middlebury').
    depth_caps: maximum depths in metres the depth metrics are computed at ('eigen'),
      each giving its own table: 50 m (the cap of the paper's Garg and Godard rows, and
      the one its own RMSE fits) and 80 m (the cap of its Zhou row).
  """
  protocol: str
  mixture: str
  data_dir: Optional[str] = None
  allow_partial: bool = False
  max_images: Optional[int] = None
  split_list: Optional[str] = None
  max_disparity: Optional[int] = None
  heldout_scenes: Optional[int] = None
  middlebury_scales: Tuple[Tuple[str, float], ...] = ()
  depth_caps: Tuple[float, ...] = (50.0, 80.0)

  def __post_init__(self):
    if self.max_images is not None and self.max_images <= 0:
      raise ValueError(f'EvalConfig.max_images must be positive, got {self.max_images}.')
    object.__setattr__(self, 'depth_caps', tuple(float(c) for c in self.depth_caps))
    if not self.depth_caps or min(self.depth_caps) <= 1e-3:
      raise ValueError(f'EvalConfig.depth_caps must be depths above 1e-3 m, got '
                       f'{self.depth_caps}.')


@dataclasses.dataclass
class EvalResult:
  """Per-image rows, their means, and how much of the benchmark they cover.

  Attributes:
    config: the run's EvalConfig.
    method: the predictor's method ('model', 'classical', 'oracle').
    restore_colour: whether the predictor rebuilt the views' kept channels (paper 4.2).
    rows: one dict per image, in dataset order (`runner` documents the keys).
    averages: {metric: mean over images with a value}.
    counts: {metric: images with a value}.
    expected: images in the full benchmark (the protocol's full count, else the listed).
  """
  config: EvalConfig
  method: str
  restore_colour: bool
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
