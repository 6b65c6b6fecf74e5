"""The paper's training objective L = L_C + L_D (section 3.1, eq. (1)) and its weights.

`LossConfig` is the only place loss weights live. The separation loss L_C (eqs. (2)-(4))
compares the separated views with the true ones; the stereo loss L_D (eqs. (5)-(7)) is
self-supervised by the TRUE stereo pair: the true right view warped by the predicted left
disparity must match the true left view, and symmetrically. The stereo module's input is
the separated pair, so in joint training the stereo loss reaches the separation network
only through the disparities.

Loss scale: the network works on [-1, 1] (paper section 3.4), and EVERY term sees images
mapped once to [0, 1]: the content L1 and TV prior as much as the appearance and
smoothness terms, whose monodepth constants were set for that range. So a pixel error of
0.1 costs the same in L_C as in L_D (docs/DESIGN.md, "Loss scales").

Every returned term is a float scalar; the dictionaries have flat string keys for logging.
"""

import dataclasses
import math
import numbers
from typing import Dict, Mapping, Sequence

import tensorflow as tf

from mixstereo_tf.core import image_range
from mixstereo_tf.ops import losses
from mixstereo_tf.ops import warp

MODES = ('joint', 'separation_only', 'stereo_only')
VIEWS = ('left', 'right')
SMOOTHNESS_SCALES = ('width', 'pixels')

_WEIGHT_FIELDS = ('alpha_c', 'alpha_p', 'omega_w', 'omega_s', 'lambda_ssim', 'lambda_l1',
                  'omega_gt')


@dataclasses.dataclass(frozen=True)
class LossConfig:
  """Loss weights; defaults are the paper's (section 3.4).

  Attributes:
    alpha_c: separation content (L1) weight, eq. (2).
    alpha_p: separation TV-prior weight, eq. (2).
    omega_w: stereo appearance weight, eq. (5).
    omega_s: stereo smoothness weight, eq. (5).
    lambda_ssim: SSIM share of the appearance loss (paper lambda_1), eq. (6).
    lambda_l1: L1 share of the appearance loss (paper lambda_2), eq. (6).
    smoothness_scale: unit of the disparity the smoothness term sees: 'width' (pixels / image
      width) or 'pixels' (docs/DESIGN.md: measured in experiments/results/fidelity.md).
    omega_gt: weight of an L1 loss on the disparities against ground truth where the batch
      has it (`supervised_losses`; synthetic scenes). Not in the paper, which trains from
      stereo pairs only: 0 there.
  """
  alpha_c: float = 1.0
  alpha_p: float = 0.2
  omega_w: float = 1.0
  omega_s: float = 0.05
  lambda_ssim: float = 0.85
  lambda_l1: float = 0.15
  smoothness_scale: str = 'width'
  omega_gt: float = 0.0

  def __post_init__(self):
    for field in _WEIGHT_FIELDS:
      value = getattr(self, field)
      if not isinstance(value, numbers.Real) or not 0.0 <= value < math.inf:
        raise ValueError(f'LossConfig.{field} must be a finite non-negative number, '
                         f'got {value!r}.')
    if self.smoothness_scale not in SMOOTHNESS_SCALES:
      raise ValueError(f'LossConfig.smoothness_scale must be one of {SMOOTHNESS_SCALES}, '
                       f'got {self.smoothness_scale!r}.')


def separation_losses(predicted: Mapping[str, tf.Tensor], truth: Mapping[str, tf.Tensor],
                      config: LossConfig, views: Sequence[str] = VIEWS
                      ) -> Dict[str, tf.Tensor]:
  """Paper eqs. (2)-(4): per separated view alpha_c * L_c + alpha_p * L_p.

  Args:
    predicted: 'left' / 'right' [B, H, W, 3] separated views, [-1, 1].
    truth: 'left' / 'right' [B, H, W, 3] true views, [-1, 1].
    config: the weights.
    views: the views the separation network predicts (monocular: only 'right').

  Returns:
    'separation/content_<view>' (unweighted L1), 'separation/tv_<view>' (unweighted TV of
    the prediction) for each of `views`, both on the [0, 1] scale (module docstring), and
    'separation/total' (their weighted sum).
  """
  out = {}
  total = 0.0
  for view in views:
    pred, gt = (image_range.signed_to_unit(images[view]) for images in (predicted, truth))
    content = losses.l1(pred, gt)  # Paper eq. (3), L_c.
    tv = losses.total_variation(pred)  # Paper eq. (4), L_p.
    out[f'separation/content_{view}'] = content
    out[f'separation/tv_{view}'] = tv
    total += config.alpha_c * content + config.alpha_p * tv
  out['separation/total'] = total
  return out


def _smoothness_disparity(disparity: tf.Tensor, config: LossConfig) -> tf.Tensor:
  if config.smoothness_scale == 'width':
    return disparity / tf.cast(tf.shape(disparity)[2], disparity.dtype)
  return disparity


def stereo_losses(disparity_left: tf.Tensor, disparity_right: tf.Tensor, gt_left: tf.Tensor,
                  gt_right: tf.Tensor, config: LossConfig) -> Dict[str, tf.Tensor]:
  """Paper eq. (5): L_D = omega_w (L_w^l + L_w^r) + omega_s (L_s^l + L_s^r).

  Args:
    disparity_left: [B, H, W, 1], pixels, positive, left-referenced.
    disparity_right: [B, H, W, 1], pixels, positive, right-referenced.
    gt_left: [B, H, W, 3] true left view, [-1, 1].
    gt_right: [B, H, W, 3] true right view, [-1, 1].
    config: the weights.

  Returns:
    'stereo/appearance_left' (eq. (6): true left vs true right sampled at x - d_L),
    'stereo/appearance_right' (true right vs true left sampled at x + d_R),
    'stereo/smoothness_left', 'stereo/smoothness_right' (eq. (7), weighted by the true
    view's gradients, disparity in `config.smoothness_scale` units), all unweighted and
    with the images on the [0, 1] scale (module docstring), and 'stereo/total' (the
    weighted sum).
  """
  out = {}
  total = 0.0
  gt_left, gt_right = image_range.signed_to_unit(gt_left), image_range.signed_to_unit(gt_right)
  for view, disparity, target, reconstruction in (
      ('left', disparity_left, gt_left, warp.reconstruct_left(gt_right, disparity_left)),
      ('right', disparity_right, gt_right, warp.reconstruct_right(gt_left, disparity_right))):
    appearance = losses.appearance_loss(target, reconstruction, config.lambda_ssim,
                                        config.lambda_l1)
    smoothness = losses.edge_aware_smoothness(_smoothness_disparity(disparity, config),
                                              target)
    out[f'stereo/appearance_{view}'] = appearance
    out[f'stereo/smoothness_{view}'] = smoothness
    total += config.omega_w * appearance + config.omega_s * smoothness
  out['stereo/total'] = total
  return out


def supervised_losses(outputs: Mapping[str, tf.Tensor], batch: Mapping[str, tf.Tensor],
                      config: LossConfig) -> Dict[str, tf.Tensor]:
  """omega_gt * mean |d - d_gt| over the valid ground-truth pixels of both views.

  Args:
    outputs: 'disparity_left', 'disparity_right' [B, H, W, 1], pixels.
    batch: the same keys (ground truth, pixels) and 'valid_left', 'valid_right' (0/1).
    config: the weights.

  Returns:
    'stereo/supervised' (unweighted, mean over the valid pixels of both views; 0 when
    none) and 'stereo/supervised_total' (weighted).
  """
  error, count = 0.0, 0.0
  for view in VIEWS:
    valid = tf.cast(batch[f'valid_{view}'], tf.float32)
    error += tf.reduce_sum(valid * tf.abs(outputs[f'disparity_{view}'] -
                                          batch[f'disparity_{view}']))
    count += tf.reduce_sum(valid)
  supervised = error / tf.maximum(count, 1.0)
  return {'stereo/supervised': supervised,
          'stereo/supervised_total': config.omega_gt * supervised}


def _require(mapping: Mapping[str, tf.Tensor], keys, name: str, mode: str) -> None:
  missing = [k for k in keys if k not in mapping]
  if missing:
    raise ValueError(f'{name} lacks keys {missing} needed by mode {mode!r}.')


def total_loss(outputs: Mapping[str, tf.Tensor], batch: Mapping[str, tf.Tensor],
               config: LossConfig, mode: str,
               separated_views: Sequence[str] = VIEWS) -> Dict[str, tf.Tensor]:
  """Paper eq. (1), L = L_C + L_D, or one of its halves for the ablations.

  Args:
    outputs: model outputs; 'left', 'right' ([B, H, W, 3], [-1, 1]) for the modes with a
      separation loss, 'disparity_left', 'disparity_right' ([B, H, W, 1], pixels) for the
      modes with a stereo loss.
    batch: 'left', 'right', the true views ([B, H, W, 3], [-1, 1]).
    config: the weights.
    mode: 'joint' (L_C + L_D), 'separation_only' (L_C) or 'stereo_only' (L_D).
    separated_views: the views L_C counts (monocular: 'right' only, the left view being
      the input itself).

  Returns:
    'loss' (the scalar to minimise) and every term of the active losses, the ground-truth
    term (`supervised_losses`) when `config.omega_gt` > 0.

  Raises:
    ValueError: for an unknown mode or missing keys.
  """
  if mode not in MODES:
    raise ValueError(f'Unknown mode {mode!r}; valid modes are {MODES}.')
  _require(batch, ('left', 'right'), 'batch', mode)
  out = {}
  loss = 0.0
  if mode in ('joint', 'separation_only'):
    _require(outputs, separated_views, 'outputs', mode)
    out.update(separation_losses(outputs, batch, config, separated_views))
    loss += out['separation/total']
  if mode in ('joint', 'stereo_only'):
    _require(outputs, ('disparity_left', 'disparity_right'), 'outputs', mode)
    out.update(stereo_losses(outputs['disparity_left'], outputs['disparity_right'],
                             batch['left'], batch['right'], config))
    loss += out['stereo/total']
    if config.omega_gt > 0:
      _require(batch, ('disparity_left', 'disparity_right', 'valid_left', 'valid_right'),
               'batch', mode)
      out.update(supervised_losses(outputs, batch, config))
      loss += out['stereo/supervised_total']
  out['loss'] = loss
  return out
