"""Learned matching features for the two eyes of an anaglyph (MC-CNN style; not in the paper).

The paper's idea is that a learned stage makes the two eyes of a mixture matchable. At CPU
scale the stage learns per-pixel descriptors whose cosine similarity is the matching cost
(Zbontar & LeCun, "Stereo Matching by Training a Convolutional Neural Network to Compare
Image Patches", JMLR 2016, the 'fast' architecture): one branch per eye, because the eyes
of an anaglyph live in different channels:
  * the 'single' branch sees the eye carried by one mixture channel (red of red-cyan,
    green of green-magenta, blue of amber-blue);
  * the 'pair' branch sees the eye carried by two channels (green and blue of red-cyan ...).
Each branch: per-channel standardisation over the image (zero mean, unit deviation: the
channels' different gains and offsets go), `layers` 3x3 convolutions of `width` channels
with ReLU between them (optionally dilated: receptive field 1 + 2 * sum(dilations)
pixels, 2 * layers + 1 undilated), and L2 normalisation, so a
descriptor is a unit vector and cost = 1 - cosine lies in [0, 2].

Input: single [B, H, W, 1], pair [B, H, W, 2], intensities in any linear unit. Output: two
[B, H, W, width] unit descriptors (single's, pair's).

`EchoFeatures` is the variant for double images I = a L + (1 - a) R, whose eyes both live
in all channels of one image: two branches over the mixture, 'here' and 'there', and the
cosine of here(x) with there(x - d) scores the echo lag d (`unmixing/learned_diplopia.py`).
Two branches, not one: one branch's cosine of x with x - d is 1 at d = 0 and near 1 at
small lags for any smooth descriptor, so the smallest lags would always win (measured: a
one-branch model, 1000 steps, chose wrong lags at 99-100 % of pixels).
"""

import dataclasses
from typing import Any, Dict, Mapping, Tuple

import tensorflow as tf

from mixstereo_tf.core import mixtures
from mixstereo_tf.models import layers_util


@dataclasses.dataclass(frozen=True)
class FeatureConfig:
  """Size of the matching-feature branches.

  Attributes:
    width: channels of every convolution (descriptor length).
    layers: 3x3 convolutions per branch.
    dilations: each convolution's dilation, `layers` entries (a wider context at the same
      cost; not MC-CNN's); empty: all 1 (the shipped features).
  """
  width: int = 32
  layers: int = 4
  dilations: Tuple[int, ...] = ()

  def __post_init__(self):
    object.__setattr__(self, 'dilations', tuple(int(d) for d in self.dilations))
    if self.width <= 0 or self.layers <= 0:
      raise ValueError(f'FeatureConfig.width and layers must be positive, got {self.width} '
                       f'and {self.layers}.')
    if self.dilations and (len(self.dilations) != self.layers or min(self.dilations) < 1):
      raise ValueError(f'FeatureConfig.dilations needs {self.layers} entries >= 1 (one per '
                       f'layer) or none, got {self.dilations}.')

  @property
  def layer_dilations(self) -> Tuple[int, ...]:
    """The dilation of each convolution (`dilations`, or all 1)."""
    return self.dilations or (1,) * self.layers

  @property
  def receptive_field(self) -> int:
    """Pixels across the window one descriptor sees."""
    return 1 + 2 * sum(self.layer_dilations)

  def to_dict(self) -> Dict[str, Any]:
    """JSON-ready fields."""
    return dataclasses.asdict(self)

  @classmethod
  def from_dict(cls, values: Mapping[str, Any]) -> 'FeatureConfig':
    """The config of `to_dict`'s output."""
    return cls(**values)


def eye_inputs(mixture01, name: str):
  """(single [..., 1], pair [..., 2], single_is_left) of an anaglyph [..., 3]: the mixture
  channels of the eye carried by one channel, those of the eye carried by two
  (`mixtures.MixtureSpec.eye_channels`), and whether the first is the left eye's."""
  left, right = mixtures.get_mixture(name).eye_channels
  if sorted((len(left), len(right))) != [1, 2]:
    raise ValueError(f'The matching features need an anaglyph whose eyes take one and two '
                     f'channels; {name!r} has eye channels {left} and {right}.')
  single_is_left = len(left) == 1
  single, pair = (left, right) if single_is_left else (right, left)
  return mixture01[..., list(single)], mixture01[..., list(pair)], single_is_left


def standardise(image: tf.Tensor) -> tf.Tensor:
  """Per-image, per-channel zero mean and unit deviation of [B, H, W, C] (a flat channel
  stays finite: the variance gets 1e-6)."""
  mean, variance = tf.nn.moments(image, axes=[1, 2], keepdims=True)
  return (image - mean) * tf.math.rsqrt(variance + 1e-6)


class _Branch(tf.keras.layers.Layer):
  """standardise -> (conv 3x3, ReLU) x (layers - 1) -> conv 3x3 -> L2 normalise."""

  def __init__(self, config: FeatureConfig, **kwargs):
    super().__init__(**kwargs)
    last = config.layers - 1
    self.convs = layers_util.tracked(self, 'conv', [
        layers_util.conv2d(config.width, 3, activation='relu' if i < last else None,
                           dilation=dilation, name=f'conv{i}')
        for i, dilation in enumerate(config.layer_dilations)])

  def call(self, image):
    x = standardise(image)
    for conv in self.convs:
      x = conv(x)
    return tf.math.l2_normalize(tf.cast(x, tf.float32), axis=-1)


class _Features(tf.keras.Model):
  """A model of `FeatureConfig`-sized branches: the config and its (de)serialisation."""

  def __init__(self, feature_config: FeatureConfig = FeatureConfig(), **kwargs):
    super().__init__(**kwargs)
    self.feature_config = feature_config

  def get_config(self):
    return {'feature_config': self.feature_config.to_dict()}

  @classmethod
  def from_config(cls, config):
    return cls(FeatureConfig.from_dict(config['feature_config']))


class MatchingFeatures(_Features):
  """The two descriptor branches (module docstring)."""

  def __init__(self, feature_config: FeatureConfig = FeatureConfig(), **kwargs):
    super().__init__(feature_config, **kwargs)
    self.single = _Branch(feature_config, name='single')
    self.pair = _Branch(feature_config, name='pair')

  def call(self, inputs: Tuple[tf.Tensor, tf.Tensor],
           training: bool = False) -> Tuple[tf.Tensor, tf.Tensor]:
    """(single [B, H, W, 1], pair [B, H, W, 2]) -> their unit descriptors."""
    del training  # No dropout or batch statistics.
    single, pair = inputs
    return self.single(single), self.pair(pair)


class EchoFeatures(_Features):
  """Two branches over a double image's three channels (module docstring)."""

  def __init__(self, feature_config: FeatureConfig = FeatureConfig(), **kwargs):
    super().__init__(feature_config, **kwargs)
    self.here = _Branch(feature_config, name='here')
    self.there = _Branch(feature_config, name='there')

  def call(self, mixture: tf.Tensor, training: bool = False) -> Tuple[tf.Tensor, tf.Tensor]:
    """mixture [B, H, W, 3] -> unit descriptors (here, there), each [B, H, W, width]."""
    del training  # No dropout or batch statistics.
    return self.here(mixture), self.there(mixture)


def build_features(feature_config: FeatureConfig = FeatureConfig()) -> MatchingFeatures:
  """A MatchingFeatures with its variables created (on a 1 x 8 x 8 input)."""
  model = MatchingFeatures(feature_config)
  model((tf.zeros([1, 8, 8, 1]), tf.zeros([1, 8, 8, 2])))
  return model


def build_echo_features(feature_config: FeatureConfig = FeatureConfig()) -> EchoFeatures:
  """An EchoFeatures with its variables created (on a 1 x 8 x 8 x 3 input)."""
  model = EchoFeatures(feature_config)
  model(tf.zeros([1, 8, 8, 3]))
  return model
