"""mixstereo_tf: stereo computation for a single mixture image (Zhong, Dai, Li, ECCV 2018)."""

__version__ = '0.1.0'
