"""TensorBoard summaries of training: every loss term and metric, and image panels."""

from typing import Dict, Optional

import tensorflow as tf

from mixstereo_tf.core import colormap
from mixstereo_tf.core import image_range


def write_scalars(scalars: Dict[str, float], step: int,
                  extra: Optional[Dict[str, float]] = None) -> None:
  """Writes every loss term and metric (and extras such as lr, steps/s) at `step`."""
  for name, value in {**scalars, **(extra or {})}.items():
    tf.summary.scalar(name, value, step=step)


def write_images(batch: Dict[str, tf.Tensor], outputs: Dict[str, tf.Tensor], step: int,
                 max_disparity: float, max_outputs: int = 2) -> None:
  """Mixture, true and separated views, and colour-mapped disparities (0..max_disparity)."""
  for key in ('mixture', 'left', 'right'):
    tf.summary.image(f'input/{key}', image_range.signed_to_u8(batch[key]), step=step,
                     max_outputs=max_outputs)
  for key in ('left', 'right'):
    if key in outputs:
      tf.summary.image(f'separated/{key}', image_range.signed_to_u8(outputs[key]), step=step,
                       max_outputs=max_outputs)
  for key in ('disparity_left', 'disparity_right'):
    if key in outputs:
      tf.summary.image(f'disparity/{key}', colormap.colorize_tf(outputs[key], max_disparity),
                       step=step, max_outputs=max_outputs)
