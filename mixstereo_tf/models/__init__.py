"""The paper's networks: separation U-Net, GC-Net-style stereo network, joint model."""

from mixstereo_tf.models.config import ModelConfig
from mixstereo_tf.models.joint import MixStereoNet
from mixstereo_tf.models.joint import build_model
from mixstereo_tf.models.separation import SeparationNet
from mixstereo_tf.models.stereo import StereoNet

__all__ = ['ModelConfig', 'build_model', 'MixStereoNet', 'SeparationNet', 'StereoNet']
