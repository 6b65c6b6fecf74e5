"""Per-module parameter counts of a model configuration (the paper reports 17.1M)."""

from typing import List, Tuple

import numpy as np

from mixstereo_tf.models import config as config_lib
from mixstereo_tf.models import joint

PAPER_PARAMETERS = 17.1e6


def count(variables) -> int:
  return int(sum(np.prod(v.shape) for v in variables))


def parameter_rows(model: joint.MixStereoNet) -> List[Tuple[str, int]]:
  """(module, trainable parameters) for each layer of both modules."""
  rows = []
  for module in (model.separation, model.stereo):
    for layer in module.layers:
      rows.append((f'{module.name}/{layer.name}', count(layer.trainable_variables)))
    rows.append((f'{module.name} (total)', count(module.trainable_variables)))
  return rows


def parameter_table(model_config: config_lib.ModelConfig = config_lib.ModelConfig()) -> str:
  """A text table of trainable parameters ending with 'total trainable parameters: N'."""
  model = joint.build_model(model_config)
  lines = [f'{"module":<40}{"parameters":>14}']
  for name, n in parameter_rows(model):
    lines.append(f'{name:<40}{n:>14,}')
  total = count(model.trainable_variables)
  lines.append(f'paper: {PAPER_PARAMETERS / 1e6:.1f}M; ours / paper = '
               f'{total / PAPER_PARAMETERS:.4f}')
  lines.append(f'total trainable parameters: {total}')
  return '\n'.join(lines)
