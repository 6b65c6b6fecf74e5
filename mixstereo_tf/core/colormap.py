"""The disparity colour map shared by training summaries and the unmix tool's outputs.

A perceptually ordered dark-to-bright ramp: `low` (far) is black-purple, `high` (near) pale
yellow, linear in between and clipped outside. Keep (low, high) fixed over a run or a
video, so that colours are comparable between images.
"""

import numba
import numpy as np
import tensorflow as tf

# Anchors of the ramp, evenly spaced on [0, 1]; colours in between are interpolated.
_RAMP = np.array([[0, 0, 4], [40, 11, 84], [101, 21, 110], [159, 42, 99], [212, 72, 66],
                  [245, 125, 21], [250, 193, 39], [252, 255, 164]], np.float32) / 255.0


def _check_range(low: float, high: float) -> None:
  if not (np.isfinite(low) and np.isfinite(high) and high > low):
    raise ValueError(f'The colour map needs finite low < high, got low={low!r}, '
                     f'high={high!r}.')


def colorize_tf(disparity: tf.Tensor, high: float, low: float = 0.0) -> tf.Tensor:
  """Colours of a batch of disparities (TensorFlow).

  Args:
    disparity: [B, H, W, 1] pixels.
    high: disparity shown with the brightest colour (and above).
    low: disparity shown with the darkest colour (and below).

  Returns:
    [B, H, W, 3] uint8.
  """
  _check_range(low, high)
  ramp = tf.constant(_RAMP)
  shifted = tf.cast(disparity[..., 0], tf.float32) - low
  t = tf.clip_by_value(shifted / (high - low), 0.0, 1.0)
  position = t * (len(_RAMP) - 1)
  lower = tf.minimum(tf.cast(tf.floor(position), tf.int32), len(_RAMP) - 2)
  frac = (position - tf.cast(lower, tf.float32))[..., None]
  colour = tf.gather(ramp, lower) * (1.0 - frac) + tf.gather(ramp, lower + 1) * frac
  return tf.cast(tf.round(colour * 255.0), tf.uint8)


@numba.njit(nogil=True, cache=True, error_model='numpy')
def _colorize(disparity, ramp, high, low, out):
  """`colorize_tf`'s arithmetic in float32, one pixel at a time (a video frame's map
  in ~6 ms instead of 20-30 through TensorFlow's eager ops; equal to the last bit)."""
  last = ramp.shape[0] - 1
  scale = np.float32(high - low)
  for y in range(disparity.shape[0]):
    for x in range(disparity.shape[1]):
      value = disparity[y, x]
      if np.isnan(value):
        value = low
      t = min(max((value - low) / scale, np.float32(0.0)), np.float32(1.0))
      position = t * np.float32(last)
      lower = min(int(np.floor(position)), last - 1)
      frac = position - np.float32(lower)
      for c in range(3):
        colour = ramp[lower, c] * (np.float32(1.0) - frac) + ramp[lower + 1, c] * frac
        out[y, x, c] = np.uint8(np.rint(colour * np.float32(255.0)))


def colorize(disparity: np.ndarray, high: float, low: float = 0.0) -> np.ndarray:
  """Colours of one disparity map (NumPy); NaN shows as `low`.

  Args:
    disparity: [H, W] (or [H, W, 1]) pixels.
    high, low: the fixed range, as in `colorize_tf` (and equal to it).

  Returns:
    uint8 RGB [H, W, 3].
  """
  _check_range(low, high)
  disparity = np.asarray(disparity, np.float32)
  disparity = np.ascontiguousarray(disparity.reshape(disparity.shape[:2]))
  out = np.empty(disparity.shape + (3,), np.uint8)
  _colorize(disparity, _RAMP, np.float32(high), np.float32(low), out)
  return out
