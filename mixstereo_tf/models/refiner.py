"""The hybrid model: networks that refine the classical method's views and disparities.

Not in the paper. The issue "A pretrained model that ... beats the classical baseline"
allows a hybrid in which the network refines the classical matcher's disparity while the
separation and colour restoration stay learned. `RefinerNet` takes, per pixel, the
mixture and the classical result (`classical`) and returns:
  * the views: a small U-Net of [mixture, classical left, classical right] adds a residual
    to the classical views (learned separation; its last layer starts at zero, so an
    untrained refiner returns the classical views);
  * the disparities: a dilated residual network (StereoNet-style refinement) sees the
    refined left view, the right view warped into it by the classical disparity, their
    difference, and that disparity relative to its image mean, and adds a correction
    (last layer zero at start). The right disparity is the same network on the mirrored,
    swapped pair: mirroring x -> W - 1 - x and swapping the views turns d_R into a left
    disparity of the same sign convention.
Everything is fully convolutional and in pixels, so any signed range and any resolution
pass unchanged (no disparity levels, no rescaling).

Input: [B, H, W, 11] = mixture, classical left, classical right (RGB in [-1, 1]), classical
d_L, classical d_R (signed pixels: left x matches right x - d_L, right x matches left
x + d_R). Output: {'left', 'right'} [B, H, W, 3] in [-1, 1], {'disparity_left',
'disparity_right'} [B, H, W, 1] signed pixels.
"""

import dataclasses
from typing import Any, Dict, Mapping, Tuple

import numpy as np
import tensorflow as tf

from mixstereo_tf.core import image_range
from mixstereo_tf.models import layers_util
from mixstereo_tf.ops import warp

INPUT_CHANNELS = 11


def network_input(mixture, left, right, d_left, d_right) -> np.ndarray:
  """The refiner's [..., H, W, 11] float32 input from uint8 images and float disparities."""
  mixture = np.asarray(mixture)
  out = np.empty(mixture.shape[:-1] + (INPUT_CHANNELS,), np.float32)
  for start, image in zip((0, 3, 6), (mixture, left, right)):
    out[..., start:start + 3] = image_range.u8_to_signed(image)
  out[..., 9], out[..., 10] = d_left, d_right
  return out



@dataclasses.dataclass(frozen=True)
class RefinerConfig:
  """Widths of the hybrid refiner.

  Attributes:
    view_widths: residual U-Net widths from full resolution down (one stride-2 level per
      entry after the first).
    disparity_features: width of the disparity refinement network.
    dilations: dilation of each 3x3 residual block of the disparity network.
    disparity_unit: pixels per unit of the disparities the network sees and outputs.
  """
  view_widths: Tuple[int, ...] = (16, 32, 64)
  disparity_features: int = 16
  dilations: Tuple[int, ...] = (1, 2, 4, 8, 1, 1)
  disparity_unit: float = 8.0

  def __post_init__(self):
    object.__setattr__(self, 'view_widths', tuple(int(w) for w in self.view_widths))
    object.__setattr__(self, 'dilations', tuple(int(d) for d in self.dilations))
    if len(self.view_widths) < 2 or min(self.view_widths) <= 0:
      raise ValueError(f'RefinerConfig.view_widths needs >= 2 positive entries, got '
                       f'{self.view_widths}.')
    if self.disparity_features <= 0:
      raise ValueError(f'RefinerConfig.disparity_features must be positive, got '
                       f'{self.disparity_features}.')
    if not self.dilations or min(self.dilations) <= 0:
      raise ValueError(f'RefinerConfig.dilations must be positive, got {self.dilations}.')
    if not self.disparity_unit > 0:
      raise ValueError(f'RefinerConfig.disparity_unit must be positive, got '
                       f'{self.disparity_unit}.')

  @property
  def size_multiple(self) -> int:
    """Input height and width must be multiples of this."""
    return 2 ** (len(self.view_widths) - 1)

  def to_dict(self) -> Dict[str, Any]:
    return {k: list(v) if isinstance(v, tuple) else v
            for k, v in dataclasses.asdict(self).items()}

  @classmethod
  def from_dict(cls, values: Mapping[str, Any]) -> 'RefinerConfig':
    fields = {f.name for f in dataclasses.fields(cls)}
    unknown = set(values) - fields
    if unknown:
      raise ValueError(f'Unknown RefinerConfig fields {sorted(unknown)}; valid: '
                       f'{sorted(fields)}.')
    return cls(**values)


def _zero_conv(filters: int, name: str) -> tf.keras.layers.Layer:
  return tf.keras.layers.Conv2D(filters, 3, padding='same', kernel_initializer='zeros',
                                name=name)


class _ResidualViews(tf.keras.layers.Layer):
  """U-Net: [mixture, left, right] -> residuals of both views (6 channels)."""

  def __init__(self, widths, **kwargs):
    super().__init__(**kwargs)
    conv = layers_util.conv2d
    self.stem = conv(widths[0], 3, name='stem')
    self.down = layers_util.tracked(self, 'down', [conv(w, 3, strides=2, name=f'down{i}')
                                                   for i, w in enumerate(widths[1:])])
    self.up = layers_util.tracked(self, 'up', [layers_util.conv2d_transpose(w, 2, name=f'up{i}')
                                               for i, w in enumerate(reversed(widths[:-1]))])
    self.merge = layers_util.tracked(self, 'merge', [conv(w, 3, name=f'merge{i}')
                                                     for i, w in enumerate(reversed(widths[:-1]))])
    self.head = _zero_conv(6, 'head')

  def call(self, x):
    skips = [self.stem(x)]
    for layer in self.down:
      skips.append(layer(skips[-1]))
    x = skips.pop()
    for up, merge, skip in zip(self.up, self.merge, reversed(skips)):
      x = merge(up(x) + skip)
    return self.head(x)


class _DisparityCorrection(tf.keras.layers.Layer):
  """(left, right, d_L) -> a correction of d_L, in units of `unit` pixels."""

  def __init__(self, features, dilations, unit, **kwargs):
    super().__init__(**kwargs)
    self.unit = unit
    self.stem = layers_util.conv2d(features, 3, name='stem')
    self.blocks = layers_util.tracked(self, 'block', [
        tf.keras.layers.Conv2D(features, 3, padding='same', dilation_rate=d,
                               activation='relu', name=f'block{i}')
        for i, d in enumerate(dilations)])
    self.head = _zero_conv(1, 'head')

  def call(self, left, right, disparity):
    warped = warp.reconstruct_left(right, disparity)
    relative = (disparity - tf.reduce_mean(disparity, axis=[1, 2, 3], keepdims=True))
    x = self.stem(tf.concat([left, warped, left - warped, relative / self.unit], -1))
    for block in self.blocks:
      x = x + block(x)
    return disparity + self.unit * self.head(x)


class RefinerNet(tf.keras.Model):
  """The hybrid refiner (module docstring): [B, H, W, 11] -> views and disparities."""

  def __init__(self, refiner_config: RefinerConfig = RefinerConfig(), **kwargs):
    super().__init__(**kwargs)
    if isinstance(refiner_config, dict):
      refiner_config = RefinerConfig.from_dict(refiner_config)
    self.refiner_config = refiner_config
    self.views = _ResidualViews(refiner_config.view_widths, name='views')
    self.correction = _DisparityCorrection(refiner_config.disparity_features,
                                           refiner_config.dilations,
                                           refiner_config.disparity_unit, name='correction')

  @property
  def size_multiple(self) -> int:
    return self.refiner_config.size_multiple

  def call(self, inputs: tf.Tensor, training: bool = False) -> Dict[str, tf.Tensor]:
    layers_util.check_size(inputs, self.size_multiple, 'RefinerNet input')
    classical_views = inputs[..., 3:9]
    views = tf.clip_by_value(classical_views + self.views(inputs[..., :9]), -1.0, 1.0)
    left, right = views[..., :3], views[..., 3:]
    d_left, d_right = inputs[..., 9:10], inputs[..., 10:11]
    mirror = lambda t: tf.reverse(t, axis=[2])
    return {'left': left, 'right': right,
            'disparity_left': self.correction(left, right, d_left),
            'disparity_right': mirror(self.correction(mirror(right), mirror(left),
                                                      mirror(d_right)))}

  def get_config(self):
    config = super().get_config()
    config.update(refiner_config=self.refiner_config.to_dict())
    return config

  @classmethod
  def from_config(cls, config):
    return cls(**config)


def build_refiner(refiner_config: RefinerConfig = RefinerConfig(),
                  name: str = 'refiner') -> RefinerNet:
  """Creates the refiner and its variables (one pass on a smallest valid input)."""
  model = RefinerNet(refiner_config, name=name)
  size = refiner_config.size_multiple
  model(tf.zeros([1, size, size, INPUT_CHANNELS]))
  return model
