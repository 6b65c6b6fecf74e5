"""Anaglyph colour restoration from estimated disparities (paper section 4.2).

"The original color can be found by warping the corresponding channels based on the
estimated disparity maps": a channel-selection anaglyph keeps some channels of each view
exactly (`MixtureSpec.left_channels` / `right_channels`, view channel -> mixture channel).
For each view:
  * its own observed channels are copied from the mixture;
  * channels the other view observed are warped from the mixture with the disparity
    (`warp.reconstruct_left` / `reconstruct_right`), where the left-right consistency check
    passes;
  * everything else (channels neither view kept, and pixels failing the check, i.e.
    occlusions, inconsistent estimates and matches outside the image) comes from a fallback,
    the separation network's own prediction. This stands in for Joulin and Kang's
    occlusion post-processing, which the paper adopts without details.

Images are in [-1, 1], disparities in pixels (docs/DESIGN.md). Inputs may be tensors or
NumPy arrays, batched [B, H, W, C] or single [H, W, C]; outputs match the input rank.
"""

from typing import Dict, Tuple

import tensorflow as tf

from mixstereo_tf import mixtures
from mixstereo_tf.ops import warp


def _as_batched(value, name: str, channels=None) -> tf.Tensor:
  tensor = tf.cast(tf.convert_to_tensor(value), tf.float32)
  if tensor.shape.rank == 3:
    tensor = tensor[tf.newaxis]
  if tensor.shape.rank != 4:
    raise ValueError(f'{name} must be [B, H, W, C] or [H, W, C], got shape {tensor.shape}.')
  if channels is not None and tensor.shape[-1] != channels:
    raise ValueError(f'{name} must have {channels} channel(s), got shape {tensor.shape}.')
  return tensor


def _lr_consistency(disparity_left: tf.Tensor, disparity_right: tf.Tensor,
                    threshold: float) -> Tuple[tf.Tensor, tf.Tensor]:
  """Batched consistency masks; see `lr_consistency_mask`."""
  # The right disparity seen from each left pixel, and vice versa.
  right_at_left = warp.reconstruct_left(disparity_right, disparity_left)
  left_at_right = warp.reconstruct_right(disparity_left, disparity_right)
  consistent_left = tf.cast(tf.abs(disparity_left - right_at_left) <= threshold, tf.float32)
  consistent_right = tf.cast(tf.abs(disparity_right - left_at_right) <= threshold, tf.float32)
  return (consistent_left * warp.in_bounds_mask(-disparity_left),
          consistent_right * warp.in_bounds_mask(disparity_right))


def lr_consistency_mask(disparity_left, disparity_right,
                        threshold: float = 1.0) -> Tuple[tf.Tensor, tf.Tensor]:
  """Left-right consistency of a pair of disparity maps.

  A left pixel x is consistent when its match x - d_L(x) lies in [0, W - 1] and
  |d_L(x) - d_R(x - d_L(x))| <= threshold (d_R linearly interpolated); a right pixel x when
  x + d_R(x) lies in [0, W - 1] and |d_R(x) - d_L(x + d_R(x))| <= threshold.

  Args:
    disparity_left: [B, H, W, 1] (or [H, W, 1]), pixels, positive, left-referenced.
    disparity_right: same shape, pixels, positive, right-referenced.
    threshold: largest accepted disagreement, pixels.

  Returns:
    (consistent_left, consistent_right): float32 0/1 masks shaped like the inputs.
  """
  if not threshold >= 0:
    raise ValueError(f'threshold must be non-negative, got {threshold!r}.')
  single = tf.convert_to_tensor(disparity_left).shape.rank == 3
  d_left = _as_batched(disparity_left, 'disparity_left', channels=1)
  d_right = _as_batched(disparity_right, 'disparity_right', channels=1)
  masks = _lr_consistency(d_left, d_right, threshold)
  return tuple(m[0] for m in masks) if single else masks


def _restore_view(mixture: tf.Tensor, fallback: tf.Tensor, own: Dict[int, int],
                  other: Dict[int, int], warped_mixture: tf.Tensor,
                  consistent: tf.Tensor) -> tf.Tensor:
  """One view: own channels copied, the other view's warped where consistent, else fallback."""
  channels = []
  for c in range(fallback.shape[-1]):
    if c in own:
      channels.append(mixture[..., own[c]:own[c] + 1])
    elif c in other:
      channels.append(tf.where(consistent > 0.5, warped_mixture[..., other[c]:other[c] + 1],
                               fallback[..., c:c + 1]))
    else:
      channels.append(fallback[..., c:c + 1])
  return tf.concat(channels, axis=-1)


def restore_views(mixture, disparity_left, disparity_right, spec: mixtures.MixtureSpec,
                  fallback_left, fallback_right,
                  threshold: float = 1.0) -> Dict[str, tf.Tensor]:
  """Restores both views' colours from a channel-selection mixture and disparities.

  Args:
    mixture: [B, H, W, 3] (or [H, W, 3]) mixture image, [-1, 1].
    disparity_left: [B, H, W, 1], pixels, positive, left-referenced.
    disparity_right: [B, H, W, 1], pixels, positive, right-referenced.
    spec: the mixture operator that made `mixture` (its channel maps drive the copy).
    fallback_left: [B, H, W, 3] left view used where nothing better is known, [-1, 1].
    fallback_right: [B, H, W, 3] right view likewise.
    threshold: left-right consistency threshold, pixels.

  Returns:
    'left', 'right': restored views, float32, shaped like `mixture`, [-1, 1];
    'occluded_left', 'occluded_right': float32 0/1 masks [..., 1], 1 where the consistency
    check failed. For a mixture without surviving channels (e.g. diplopia) the views are
    the fallbacks unchanged.
  """
  if not threshold >= 0:
    raise ValueError(f'threshold must be non-negative, got {threshold!r}.')
  single = tf.convert_to_tensor(mixture).shape.rank == 3
  mixture = _as_batched(mixture, 'mixture', channels=3)
  fallback_left = _as_batched(fallback_left, 'fallback_left', channels=3)
  fallback_right = _as_batched(fallback_right, 'fallback_right', channels=3)
  d_left = _as_batched(disparity_left, 'disparity_left', channels=1)
  d_right = _as_batched(disparity_right, 'disparity_right', channels=1)
  for name, tensor in (('fallback_left', fallback_left), ('fallback_right', fallback_right),
                       ('disparity_left', d_left), ('disparity_right', d_right)):
    if not tensor.shape[:3].is_compatible_with(mixture.shape[:3]):
      raise ValueError(f'{name} shape {tensor.shape} does not match mixture shape '
                       f'{mixture.shape} in [B, H, W].')

  consistent_left, consistent_right = _lr_consistency(d_left, d_right, threshold)
  own_left, own_right = dict(spec.left_channels), dict(spec.right_channels)
  if own_left or own_right:
    left = _restore_view(mixture, fallback_left, own_left, own_right,
                         warp.reconstruct_left(mixture, d_left), consistent_left)
    right = _restore_view(mixture, fallback_right, own_right, own_left,
                          warp.reconstruct_right(mixture, d_right), consistent_right)
  else:
    left, right = fallback_left, fallback_right
  out = {'left': left, 'right': right,
         'occluded_left': 1.0 - consistent_left, 'occluded_right': 1.0 - consistent_right}
  return {k: v[0] for k, v in out.items()} if single else out
