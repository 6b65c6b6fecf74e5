"""The joint model: separation U-Net followed by the stereo network (paper Fig. 2)."""

from typing import Dict

import tensorflow as tf

from mixstereo_tf.models import config as config_lib
from mixstereo_tf.models import separation
from mixstereo_tf.models import stereo


class MixStereoNet(tf.keras.Model):
  """Mixture [B, H, W, 3] in [-1, 1] -> separated views and both disparities.

  `call` returns {'left', 'right'} ([B, H, W, 3], [-1, 1]) and {'disparity_left',
  'disparity_right'} ([B, H, W, 1], pixels, positive; see StereoNet.call). The stereo
  module sees the SEPARATED views, so its loss trains the U-Net too (end to end); with
  `ModelConfig.input_is_left` (monocular) the left view is the input itself.
  """

  def __init__(self, model_config: config_lib.ModelConfig = config_lib.ModelConfig(),
               **kwargs):
    super().__init__(**kwargs)
    if isinstance(model_config, dict):
      model_config = config_lib.ModelConfig.from_dict(model_config)
    self.model_config = model_config
    self.separation = separation.SeparationNet(model_config.separation_widths,
                                               name='separation')
    self.stereo = stereo.StereoNet(model_config.stereo_features,
                                   model_config.stereo_residual_blocks,
                                   model_config.stereo_3d_widths,
                                   model_config.max_disparity,
                                   model_config.conv3d_implementation,
                                   census_cost=model_config.census_cost, name='stereo')

  @property
  def size_multiple(self) -> int:
    return self.model_config.size_multiple

  def separate(self, mixture: tf.Tensor, training: bool = False) -> Dict[str, tf.Tensor]:
    """The separation module alone: {'left', 'right'}."""
    return self.separation(mixture, training=training)

  def compute_disparity(self, left: tf.Tensor, right: tf.Tensor,
                        training: bool = False) -> Dict[str, tf.Tensor]:
    """The stereo module alone on a given pair: {'disparity_left', 'disparity_right'}."""
    return self.stereo(left, right, training=training)

  def call(self, mixture: tf.Tensor, training: bool = False) -> Dict[str, tf.Tensor]:
    views = self.separate(mixture, training=training)
    if self.model_config.input_is_left:  # Monocular: the input is the left view.
      views = {'left': tf.cast(mixture, views['right'].dtype), 'right': views['right']}
    outputs = dict(views)
    outputs.update(self.compute_disparity(views['left'], views['right'], training=training))
    return outputs

  def get_config(self):
    config = super().get_config()
    config.update(model_config=self.model_config.to_dict())
    return config

  @classmethod
  def from_config(cls, config):
    return cls(**config)


def build_model(model_config: config_lib.ModelConfig = config_lib.ModelConfig(),
                name: str = 'mixstereo') -> MixStereoNet:
  """Creates the joint model and its variables (one pass on a smallest valid input)."""
  model = MixStereoNet(model_config, name=name)
  size = model_config.smallest_input
  model(tf.zeros([1, size, size, 3]))
  return model
