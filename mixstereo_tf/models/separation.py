"""The separation module: a U-Net from the mixture to the two views (paper section 3.1).

Paper: "a U-Net ... 22 convolutional layers", ReLU after each but the last, element-wise
ADD skip connections, `tanh` output with 6 channels (left RGB, right RGB). With the default
widths 32-64-128-256-512-512 the layers are:
  1  3x3 conv (full resolution)
  2-11  five levels of [3x3 stride-2 conv, 3x3 conv]
  12-21 five levels of [2x2 stride-2 transposed conv, ADD the encoder output, 3x3 conv]
  22 3x3 conv to 6 channels, tanh
which is 14,313,862 parameters.
"""

from typing import Dict, Sequence

import tensorflow as tf

from mixstereo_tf.models import config as config_lib
from mixstereo_tf.models import layers_util


class SeparationNet(tf.keras.Model):
  """U-Net F: mixture [B, H, W, 3] in [-1, 1] -> {'left', 'right'} in [-1, 1]."""

  def __init__(self, widths: Sequence[int] = config_lib.ModelConfig().separation_widths,
               **kwargs):
    super().__init__(**kwargs)
    self.widths = tuple(int(w) for w in widths)
    conv = layers_util.conv2d
    self.stem = conv(self.widths[0], 3, name='conv1')
    down_strided, down_plain, up_transposed, up_plain = [], [], [], []
    index = 2
    for width in self.widths[1:]:
      down_strided.append(conv(width, 3, strides=2, name=f'conv{index}'))
      down_plain.append(conv(width, 3, name=f'conv{index + 1}'))
      index += 2
    for width in reversed(self.widths[:-1]):
      up_transposed.append(layers_util.conv2d_transpose(width, 2, name=f'conv{index}'))
      up_plain.append(conv(width, 3, name=f'conv{index + 1}'))
      index += 2
    self.down_strided = layers_util.tracked(self, 'down_strided', down_strided)
    self.down_plain = layers_util.tracked(self, 'down_plain', down_plain)
    self.up_transposed = layers_util.tracked(self, 'up_transposed', up_transposed)
    self.up_plain = layers_util.tracked(self, 'up_plain', up_plain)
    # Last layer: no ReLU, tanh to [-1, 1]; 6 channels = left RGB, right RGB.
    self.head = conv(6, 3, activation='tanh', name=f'conv{index}')
    self.num_conv_layers = index

  @property
  def size_multiple(self) -> int:
    return 2 ** (len(self.widths) - 1)

  def call(self, mixture: tf.Tensor, training: bool = False) -> Dict[str, tf.Tensor]:
    layers_util.check_size(mixture, self.size_multiple, 'SeparationNet input')
    x = self.stem(mixture)
    skips = [x]
    for strided, plain in zip(self.down_strided, self.down_plain):
      x = plain(strided(x))
      skips.append(x)
    skips.pop()
    for transposed, plain, skip in zip(self.up_transposed, self.up_plain, reversed(skips)):
      x = plain(transposed(x) + skip)  # Element-wise ADD skip connection (paper).
    views = self.head(x)
    return {'left': views[..., :3], 'right': views[..., 3:]}

  def get_config(self):
    config = super().get_config()
    config.update({'widths': list(self.widths)})
    return config

  @classmethod
  def from_config(cls, config):
    return cls(**config)
