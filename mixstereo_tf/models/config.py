"""The architecture configuration; its defaults are the paper's 17.1M-parameter model."""

import dataclasses
from typing import Any, Dict, Mapping, Tuple

from mixstereo_tf.ops import census
from mixstereo_tf.ops import conv3d


@dataclasses.dataclass(frozen=True)
class ModelConfig:
  """Widths and ranges of the joint model (defaults: the paper's configuration).

  Attributes:
    separation_widths: U-Net widths from full resolution down; one stride-2 level per entry
      after the first (paper: 22 conv layers; 32-64-128-256-512-512 gives 14.31M).
    stereo_features: GC-Net 2D feature width (32 in GC-Net; 2.85M parameters).
    stereo_residual_blocks: residual blocks of the 2D feature tower (GC-Net: 8).
    stereo_3d_widths: widths of the 3D encoder levels (GC-Net: 64, 64, 64, 128); the number
      of entries is the depth of the 3D encoder-decoder.
    max_disparity: disparity levels at full resolution (paper: 96; 48 at 1/2 resolution).
    conv3d_implementation: how stride-2 3D (transposed) convs run, 'auto' | 'native' |
      'dense' (`ops/conv3d.py`); the same function and weights either way.
    census_cost: give the 3D network a census matching cost of its two input views beside
      the learned features (`ops/census.py`; one more volume channel): the hybrid in which
      the network aggregates the classical matcher's cost. Not in the paper (False).
    input_is_left: the mixture IS the left view (monocular, `I = I_L`): the input itself
      is the model's left view and the stereo module's left input (paper section 3.1:
      "only the right image will be needed as the left image has been provided as
      input"); the separation network's left output is unused.
  """
  separation_widths: Tuple[int, ...] = (32, 64, 128, 256, 512, 512)
  stereo_features: int = 32
  stereo_residual_blocks: int = 8
  stereo_3d_widths: Tuple[int, ...] = (64, 64, 64, 128)
  max_disparity: int = 96
  conv3d_implementation: str = 'auto'
  census_cost: bool = False
  input_is_left: bool = False

  def __post_init__(self):
    object.__setattr__(self, 'separation_widths', tuple(int(w) for w in self.separation_widths))
    object.__setattr__(self, 'stereo_3d_widths', tuple(int(w) for w in self.stereo_3d_widths))
    if len(self.separation_widths) < 2:
      raise ValueError('ModelConfig.separation_widths needs at least 2 entries, got '
                       f'{self.separation_widths}.')
    if not self.stereo_3d_widths:
      raise ValueError('ModelConfig.stereo_3d_widths needs at least one level.')
    for name in ('separation_widths', 'stereo_3d_widths'):
      if min(getattr(self, name)) <= 0:
        raise ValueError(f'ModelConfig.{name} must be positive, got {getattr(self, name)}.')
    if self.stereo_features <= 0 or self.stereo_residual_blocks < 0:
      raise ValueError('ModelConfig.stereo_features must be positive and '
                       'stereo_residual_blocks non-negative.')
    if self.conv3d_implementation not in conv3d.IMPLEMENTATIONS:
      raise ValueError(f'ModelConfig.conv3d_implementation must be one of '
                       f'{conv3d.IMPLEMENTATIONS}, got {self.conv3d_implementation!r}.')
    volume_multiple = 2 ** (len(self.stereo_3d_widths) + 1)
    if self.max_disparity <= 0 or self.max_disparity % volume_multiple:
      raise ValueError(
          f'ModelConfig.max_disparity={self.max_disparity} must be a positive multiple of '
          f'{volume_multiple}: the volume is built at 1/2 resolution and halved by each of '
          f'the {len(self.stereo_3d_widths)} 3D encoder levels.')

  @property
  def size_multiple(self) -> int:
    """Input height and width must be multiples of this (32 for the paper's model)."""
    return max(2 ** (len(self.separation_widths) - 1),
               2 ** (len(self.stereo_3d_widths) + 1))

  @property
  def smallest_input(self) -> int:
    """The smallest valid input height and width: `size_multiple`, or with `census_cost`
    the smallest multiple of it whose half-resolution views hold the census window."""
    if not self.census_cost:
      return self.size_multiple
    needed = 2 * (max(census.WINDOW) // 2 + 1)
    return self.size_multiple * -(-needed // self.size_multiple)

  def to_dict(self) -> Dict[str, Any]:
    return {k: list(v) if isinstance(v, tuple) else v
            for k, v in dataclasses.asdict(self).items()}

  @classmethod
  def from_dict(cls, values: Mapping[str, Any]) -> 'ModelConfig':
    """Builds a config from `to_dict()` output (or a run's config.json 'model' entry)."""
    fields = {f.name for f in dataclasses.fields(cls)}
    unknown = set(values) - fields
    if unknown:
      raise ValueError(f'Unknown ModelConfig fields {sorted(unknown)}; valid: {sorted(fields)}.')
    return cls(**values)
