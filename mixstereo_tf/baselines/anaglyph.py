"""Training-free de-anaglyph: census-SGM across colour channels, then colour restoration.

A stand-in for the paper's classical comparisons (Joulin & Kang 2013, Williem et al. 2015,
no public code). For a channel-selection anaglyph (`MixtureSpec.is_channel_anaglyph`) the
left view is seen only through its surviving channels and the right view through its own:
  1. `sgm.match` on the mixture channels of the left view against those of the right view
     (red against green and blue for red-cyan; the cost averages the census Hamming
     distances of all channel pairs). Census compares each pixel only with its own
     neighbourhood, so the different responses of different channels matter little.
     Then 4-path SGM, left and right disparities, left-right check, background-favouring
     hole filling.
  3. Colour: `ops.colour_restore.restore_views` copies each view's observed channels and
     warps the other view's where the left-right check passes; elsewhere (occlusions,
     matches outside the image) the missing channels come from a colour transfer:
     `colour_transfer.local_linear_transfer` fitted on the consistent pixels, where the
     warped channels give (observed, missing) training pairs.
"""

from typing import Dict, Optional

import numpy as np
import tensorflow as tf

from mixstereo_tf import mixtures
from mixstereo_tf.baselines import colour_transfer
from mixstereo_tf.baselines import sgm
from mixstereo_tf.ops import colour_restore
from mixstereo_tf.ops import warp

SUPPORTED_MIXTURES = tuple(name for name in mixtures.MIXTURE_NAMES
                           if mixtures.get_mixture(name).is_channel_anaglyph)


def _transfer_fallback(mixture01: np.ndarray, own: Dict[int, int], other: Dict[int, int],
                       warped01: np.ndarray, consistent: np.ndarray,
                       radius: int) -> np.ndarray:
  """One view with its own channels from the mixture and the rest colour-transferred."""
  own_view = sorted(own)
  missing = [c for c in range(3) if c not in own]
  guide = mixture01[..., [own[c] for c in own_view]]
  # The other view's channels warped into this view: training targets where consistent.
  target = np.stack([warped01[..., other[c]] if c in other else guide.mean(-1)
                     for c in missing], axis=-1)
  predicted = colour_transfer.local_linear_transfer(guide, target, consistent, radius)
  view = np.empty_like(mixture01)
  for i, c in enumerate(own_view):
    view[..., c] = guide[..., i]
  for i, c in enumerate(missing):
    view[..., c] = predicted[..., i]
  return view


def unmix_anaglyph(mixture, mixture_name: str, config: Optional[sgm.SgmConfig] = None,
                   transfer_radius: int = 7) -> Dict[str, np.ndarray]:
  """Separates a channel-selection anaglyph into two views and disparities.

  Args:
    mixture: uint8 [H, W, 3] RGB, or float in [0, 1].
    mixture_name: one of SUPPORTED_MIXTURES.
    config: matching parameters (default `sgm.SgmConfig()`).
    transfer_radius: window radius of the occlusion colour transfer, pixels.

  Returns:
    'left', 'right': uint8 [H, W, 3]; 'disparity_left', 'disparity_right': float32
    [H, W], pixels, positive (left x matches right x - d_L; right x matches left x + d_R).

  Raises:
    ValueError: unknown or unsupported mixture, or a malformed image.
  """
  spec = mixtures.get_mixture(mixture_name)
  if mixture_name not in SUPPORTED_MIXTURES:
    raise ValueError(f'The classical de-anaglyph needs a channel-selection anaglyph '
                     f'({", ".join(SUPPORTED_MIXTURES)}); got {mixture_name!r}.')
  config = config or sgm.SgmConfig()
  image = colour_transfer.to_unit_float(mixture)
  matched = sgm.match(image[..., sorted(spec.left_channels.values())] * 255.0,
                      image[..., sorted(spec.right_channels.values())] * 255.0, config)
  d_left = matched['disparity_left'][None, ..., None]
  d_right = matched['disparity_right'][None, ..., None]

  batch = tf.constant(image[None] * 2.0 - 1.0)
  warped_left = (warp.reconstruct_left(batch, d_left)[0].numpy() + 1.0) * 0.5
  warped_right = (warp.reconstruct_right(batch, d_right)[0].numpy() + 1.0) * 0.5
  ok_left, ok_right = colour_restore.lr_consistency_mask(d_left, d_right, config.lr_threshold)
  own_left, own_right = dict(spec.left_channels), dict(spec.right_channels)
  fallback_left = _transfer_fallback(image, own_left, own_right, warped_left,
                                     ok_left[0, ..., 0].numpy() > 0.5, transfer_radius)
  fallback_right = _transfer_fallback(image, own_right, own_left, warped_right,
                                      ok_right[0, ..., 0].numpy() > 0.5, transfer_radius)
  restored = colour_restore.restore_views(batch, d_left, d_right, spec,
                                          fallback_left[None] * 2.0 - 1.0,
                                          fallback_right[None] * 2.0 - 1.0,
                                          threshold=config.lr_threshold)
  return {
      'left': colour_transfer.to_uint8((restored['left'][0].numpy() + 1.0) * 0.5),
      'right': colour_transfer.to_uint8((restored['right'][0].numpy() + 1.0) * 0.5),
      'disparity_left': matched['disparity_left'],
      'disparity_right': matched['disparity_right'],
  }
