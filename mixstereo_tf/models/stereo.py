"""The stereo module: GC-Net-style disparity from the separated views (paper section 3.2).

The paper builds on SsSMnet (Zhong et al. 2017) without its consistency check, i.e. GC-Net
(Kendall et al. 2017), trained without ground-truth disparity:
  1      5x5 stride-2 conv, F features              (shared 2D tower, 1/2 resolution)
  2-17   8 residual blocks of two 3x3 convs, F
  18     3x3 conv, F (no BN, no ReLU)
  cost   concatenation volume over D/2 levels at 1/2 resolution -> [D/2, H/2, W/2, 2F]
         (+1 channel: the census cost of the half-resolution views, with census_cost)
  19-20  two 3x3x3 convs, F
  21-32  per level: 3x3x3 stride-2 conv (from the previous level's strided conv, as in
         GC-Net), two 3x3x3 convs; widths 64, 64, 64, 128
  33-36  3x3x3 stride-2 transposed convs, each ADDed to the matching encoder output
  37     3x3x3 stride-2 transposed conv to 1 channel (no BN, no ReLU) -> [D, H, W]
  soft-argmin over D levels -> disparity in full-resolution pixels.
BN + ReLU follow every layer but 18 and 37 (convs before BN carry no bias).

Right disparity: a mirrored pass. Flipping both views horizontally and swapping them turns
the right view into the left view of a mirrored pair, whose left-referenced disparity is the
right disparity mirrored. In training both passes run as one batch of 2B through shared
weights (batch norm sees both); in inference they run one after the other.
"""

import functools
from typing import Dict, Sequence

import tensorflow as tf

from mixstereo_tf.models import config as config_lib
from mixstereo_tf.models import layers_util
from mixstereo_tf.ops import census
from mixstereo_tf.ops import conv3d
from mixstereo_tf.ops import cost_volume


_PAPER = config_lib.ModelConfig()  # The defaults of the layers below are the paper's.


class Strided3D(tf.keras.layers.Layer):
  """A stride-2 3x3x3 conv or transposed conv (`ops/conv3d.py` picks the implementation).

  The kernel has Keras' layout ([k, k, k, in, out], transposed: [k, k, k, out, in]) and
  initialiser, so the layer is a drop-in for Conv3D / Conv3DTranspose with strides=2.
  """

  def __init__(self, filters: int, kernel: int = 3, transposed: bool = False,
               use_bias: bool = False, implementation: str = 'auto', **kwargs):
    super().__init__(**kwargs)
    self.filters, self.kernel_size, self.transposed = filters, kernel, transposed
    self.use_bias, self.implementation = use_bias, implementation
    conv3d.resolve_implementation(implementation)  # Validates the name.

  def build(self, input_shape):
    channels = int(input_shape[-1])
    k = self.kernel_size
    shape = (k, k, k, self.filters, channels) if self.transposed else (
        k, k, k, channels, self.filters)
    self.kernel = self.add_weight(name='kernel', shape=shape,
                                  initializer='glorot_uniform')
    self.bias = (self.add_weight(name='bias', shape=(self.filters,), initializer='zeros')
                 if self.use_bias else None)

  def call(self, x):
    if self.transposed:
      y = conv3d.conv3d_transpose_stride2(x, self.kernel, self.implementation)
    else:
      y = conv3d.conv3d_stride2(x, self.kernel, self.implementation)
    return y + self.bias if self.use_bias else y

  def get_config(self):
    config = super().get_config()
    config.update(filters=self.filters, kernel=self.kernel_size, transposed=self.transposed,
                  use_bias=self.use_bias, implementation=self.implementation)
    return config


class ConvBnRelu(tf.keras.layers.Layer):
  """conv (no bias) -> batch norm -> ReLU, 2D or 3D, optionally transposed."""

  def __init__(self, filters: int, kernel: int, strides: int = 1, rank: int = 2,
               transposed: bool = False, implementation: str = 'auto', **kwargs):
    super().__init__(**kwargs)
    self.filters, self.kernel, self.strides = filters, kernel, strides
    self.rank, self.transposed, self.implementation = rank, transposed, implementation
    if rank == 3 and strides == 2:
      self.conv = Strided3D(filters, kernel, transposed, implementation=implementation)
    else:
      layer = {(2, False): tf.keras.layers.Conv2D, (3, False): tf.keras.layers.Conv3D,
               (2, True): tf.keras.layers.Conv2DTranspose}[(rank, transposed)]
      self.conv = layer(filters, kernel, strides=strides, padding='same', use_bias=False)
    self.bn = layers_util.FusedBatchNorm()

  def call(self, x, training=False):
    return tf.nn.relu(self.bn(self.conv(x), training=training))

  def get_config(self):
    config = super().get_config()
    config.update(filters=self.filters, kernel=self.kernel, strides=self.strides,
                  rank=self.rank, transposed=self.transposed,
                  implementation=self.implementation)
    return config


class StereoNet(tf.keras.Model):
  """GC-Net-like stereo network: (left, right) -> {'disparity_left', 'disparity_right'}."""

  def __init__(self, features: int = _PAPER.stereo_features,
               residual_blocks: int = _PAPER.stereo_residual_blocks,
               widths_3d: Sequence[int] = _PAPER.stereo_3d_widths,
               max_disparity: int = _PAPER.max_disparity,
               conv3d_implementation: str = _PAPER.conv3d_implementation,
               census_cost: bool = _PAPER.census_cost, **kwargs):
    super().__init__(**kwargs)
    self.conv3d_implementation = conv3d_implementation
    self.census_cost = bool(census_cost)
    impl = {'implementation': conv3d_implementation}
    self.features, self.residual_blocks = int(features), int(residual_blocks)
    self.widths_3d, self.max_disparity = tuple(int(w) for w in widths_3d), int(max_disparity)
    f = self.features
    self.tower_in = ConvBnRelu(f, 5, strides=2, name='conv1')
    track = functools.partial(layers_util.tracked, self)
    self.tower_first = track('tower_first', [ConvBnRelu(f, 3, name=f'conv{2 + 2 * i}')
                                             for i in range(self.residual_blocks)])
    self.tower_second = track('tower_second', [ConvBnRelu(f, 3, name=f'conv{3 + 2 * i}')
                                               for i in range(self.residual_blocks)])
    self.tower_out = layers_util.conv2d(f, 3, activation=None, name='conv_tower_out')
    self.volume_in = track('volume_in', [ConvBnRelu(f, 3, rank=3, name='conv3d_a'),
                                         ConvBnRelu(f, 3, rank=3, name='conv3d_b')])
    self.encoder_strided = track('encoder_strided', [
        ConvBnRelu(w, 3, strides=2, rank=3, name=f'conv3d_down{i}', **impl)
        for i, w in enumerate(self.widths_3d)])
    self.encoder_first = track('encoder_first', [
        ConvBnRelu(w, 3, rank=3, name=f'conv3d_down{i}_a')
        for i, w in enumerate(self.widths_3d)])
    self.encoder_second = track('encoder_second', [
        ConvBnRelu(w, 3, rank=3, name=f'conv3d_down{i}_b')
        for i, w in enumerate(self.widths_3d)])
    skip_widths = (f,) + self.widths_3d[:-1]
    self.decoder = track('decoder', [
        ConvBnRelu(w, 3, strides=2, rank=3, transposed=True, name=f'deconv3d_{i}', **impl)
        for i, w in reversed(list(enumerate(skip_widths)))])
    self.volume_out = Strided3D(1, 3, transposed=True, use_bias=True, name='deconv3d_out',
                                **impl)

  @property
  def size_multiple(self) -> int:
    return 2 ** (len(self.widths_3d) + 1)

  def feature_tower(self, image: tf.Tensor, training: bool = False) -> tf.Tensor:
    """The shared 2D tower: [N, H, W, 3] -> [N, H/2, W/2, F] (layers 1-18)."""
    x = self.tower_in(image, training=training)
    for first, second in zip(self.tower_first, self.tower_second):
      x = x + second(first(x, training=training), training=training)  # Residual block.
    return self.tower_out(x)

  def filter_volume(self, volume: tf.Tensor, training: bool = False) -> tf.Tensor:
    """The 3D encoder-decoder (layers 19-37): [B, D/2, H/2, W/2, 2F] -> costs [B, D, H, W]."""
    x = volume
    for layer in self.volume_in:
      x = layer(x, training=training)
    skips = [x]
    down = volume
    for strided, first, second in zip(self.encoder_strided, self.encoder_first,
                                      self.encoder_second):
      down = strided(down, training=training)
      skips.append(second(first(down, training=training), training=training))
    x = skips.pop()
    for deconv, skip in zip(self.decoder, reversed(skips)):
      x = deconv(x, training=training) + skip  # GC-Net's skip additions.
    return self.volume_out(x)[..., 0]

  def _disparity(self, left, right, training):
    """Left-referenced disparity [B, H, W, 1] in pixels from a rectified pair."""
    features = self.feature_tower(tf.concat([left, right], axis=0), training)
    left_features, right_features = tf.split(features, 2, axis=0)
    volume = cost_volume.concat_cost_volume(left_features, right_features,
                                            self.max_disparity // 2)
    if self.census_cost:  # The hybrid: the classical census cost as one more channel.
      half = lambda image: tf.nn.avg_pool2d(image, 2, 2, 'VALID')
      census_volume = census.cost_volume(half(left), half(right), self.max_disparity // 2)
      volume = tf.concat([volume, tf.cast(census_volume, volume.dtype)], axis=-1)
    return cost_volume.soft_argmin(self.filter_volume(volume, training))

  def call(self, left: tf.Tensor, right: tf.Tensor, training: bool = False
           ) -> Dict[str, tf.Tensor]:
    """Both disparities of a rectified pair.

    Args:
      left: [B, H, W, 3] left view in [-1, 1]; H, W multiples of `size_multiple`.
      right: [B, H, W, 3] right view.
      training: batch-norm mode.

    Returns:
      'disparity_left' and 'disparity_right': [B, H, W, 1] float32, pixels, positive;
      the left pixel x matches the right pixel x - d_L, the right pixel x matches the left
      pixel x + d_R.
    """
    layers_util.check_size(left, self.size_multiple, 'StereoNet input')
    mirrored_left = tf.reverse(right, axis=[2])
    mirrored_right = tf.reverse(left, axis=[2])
    if training:
      # One batch: batch-norm statistics are taken over both passes together.
      disparity = self._disparity(tf.concat([left, mirrored_left], axis=0),
                                  tf.concat([right, mirrored_right], axis=0), training)
      disparity_left, mirrored = tf.split(disparity, 2, axis=0)
    else:
      # Batch norm uses its moving statistics, so the passes are independent: running them
      # one after the other halves the peak memory of the 3D volumes (same results).
      disparity_left = self._disparity(left, right, training)
      with tf.control_dependencies([disparity_left]):
        mirrored_left = tf.identity(mirrored_left)
      mirrored = self._disparity(mirrored_left, mirrored_right, training)
    return {'disparity_left': disparity_left,
            'disparity_right': tf.reverse(mirrored, axis=[2])}

  def get_config(self):
    config = super().get_config()
    config.update(features=self.features, residual_blocks=self.residual_blocks,
                  widths_3d=list(self.widths_3d), max_disparity=self.max_disparity,
                  conv3d_implementation=self.conv3d_implementation,
                  census_cost=self.census_cost)
    return config

  @classmethod
  def from_config(cls, config):
    return cls(**config)
