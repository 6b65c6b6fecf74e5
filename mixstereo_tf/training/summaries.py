"""TensorBoard summaries and the disparity colour map shared with the unmix CLI."""

from typing import Dict, Optional

import numpy as np
import tensorflow as tf

# Anchors of a perceptually ordered dark-to-bright ramp (near = bright), evenly spaced on
# [0, 1]; colours in between are interpolated linearly.
_RAMP = np.array([[0, 0, 4], [40, 11, 84], [101, 21, 110], [159, 42, 99], [212, 72, 66],
                  [245, 125, 21], [250, 193, 39], [252, 255, 164]], np.float32) / 255.0


def colorize_disparity(disparity: tf.Tensor, max_disparity: float) -> tf.Tensor:
  """Maps disparity to colours with one fixed range.

  Args:
    disparity: [B, H, W, 1] pixels.
    max_disparity: the value mapped to the brightest colour (use one value per run so that
      colours are comparable between images).

  Returns:
    [B, H, W, 3] uint8.
  """
  ramp = tf.constant(_RAMP)
  t = tf.clip_by_value(tf.cast(disparity[..., 0], tf.float32) / max_disparity, 0.0, 1.0)
  position = t * (len(_RAMP) - 1)
  low = tf.minimum(tf.cast(tf.floor(position), tf.int32), len(_RAMP) - 2)
  frac = (position - tf.cast(low, tf.float32))[..., None]
  colour = tf.gather(ramp, low) * (1.0 - frac) + tf.gather(ramp, low + 1) * frac
  return tf.cast(tf.round(colour * 255.0), tf.uint8)


def to_uint8(image: tf.Tensor) -> tf.Tensor:
  """[-1, 1] float images to uint8."""
  return tf.cast(tf.round(tf.clip_by_value((image + 1.0) * 127.5, 0.0, 255.0)), tf.uint8)


def write_scalars(scalars: Dict[str, float], step: int,
                  extra: Optional[Dict[str, float]] = None) -> None:
  """Writes every loss term and metric (and extras such as lr, steps/s) at `step`."""
  for name, value in {**scalars, **(extra or {})}.items():
    tf.summary.scalar(name, value, step=step)


def write_images(batch: Dict[str, tf.Tensor], outputs: Dict[str, tf.Tensor], step: int,
                 max_disparity: float, max_outputs: int = 2) -> None:
  """Mixture, true and separated views, and colour-mapped disparities."""
  for key in ('mixture', 'left', 'right'):
    tf.summary.image(f'input/{key}', to_uint8(batch[key]), step=step, max_outputs=max_outputs)
  for key in ('left', 'right'):
    if key in outputs:
      tf.summary.image(f'separated/{key}', to_uint8(outputs[key]), step=step,
                       max_outputs=max_outputs)
  for key in ('disparity_left', 'disparity_right'):
    if key in outputs:
      tf.summary.image(f'disparity/{key}', colorize_disparity(outputs[key], max_disparity),
                       step=step, max_outputs=max_outputs)
