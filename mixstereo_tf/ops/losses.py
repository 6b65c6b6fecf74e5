"""Loss terms of the paper's objective (section 3): pure functions, weights as arguments.

Every image argument is on the [0, 1] scale (docs/DESIGN.md, "Loss scales"): the constants
that come from monodepth (SSIM's C1 and C2, the 0.85 / 0.15 balance of the appearance loss,
the scale of the edge-aware weights) were set for it, and `training/objective.py` maps the network's
[-1, 1] views to it once for every term, the separation terms included.

Every scalar is a per-pixel mean: `1/N sum` in the paper, with each map (SSIM, L1, x and y
gradients) averaged over its own elements, monodepth's convention.
"""

import tensorflow as tf

# SSIM stabilisers for a dynamic range of 1 (Wang et al. 2004: K1 = 0.01, K2 = 0.03).
_SSIM_C1 = 0.01**2
_SSIM_C2 = 0.03**2


def _check_rank4(tensor: tf.Tensor, name: str) -> None:
  if tensor.shape.rank != 4:
    raise ValueError(f'{name} must be [B, H, W, C], got shape {tensor.shape}.')


def _gradients(tensor: tf.Tensor):
  """Forward differences: (d/du [B, H, W-1, C], d/dv [B, H-1, W, C])."""
  return (tensor[:, :, 1:, :] - tensor[:, :, :-1, :],
          tensor[:, 1:, :, :] - tensor[:, :-1, :, :])


def ssim(x: tf.Tensor, y: tf.Tensor) -> tf.Tensor:
  """Structural similarity map with 3x3 mean-pooled statistics.

  Means, variances and the covariance are 3x3 box averages ('VALID' pooling, population
  normalisation 1/9); C1 = 0.01^2 and C2 = 0.03^2 are the standard constants for a dynamic
  range of 1.

  Args:
    x: [B, H, W, C] image in [0, 1].
    y: [B, H, W, C] image in [0, 1].

  Returns:
    [B, H - 2, W - 2, C] SSIM map, 1 where the windows are identical.
  """
  x = tf.convert_to_tensor(x)
  y = tf.convert_to_tensor(y, dtype=x.dtype)
  _check_rank4(x, 'x')
  _check_rank4(y, 'y')
  pool = lambda t: tf.nn.avg_pool2d(t, ksize=3, strides=1, padding='VALID')
  mu_x = pool(x)
  mu_y = pool(y)
  sigma_x = pool(x * x) - mu_x * mu_x
  sigma_y = pool(y * y) - mu_y * mu_y
  sigma_xy = pool(x * y) - mu_x * mu_y
  numerator = (2.0 * mu_x * mu_y + _SSIM_C1) * (2.0 * sigma_xy + _SSIM_C2)
  denominator = (mu_x * mu_x + mu_y * mu_y + _SSIM_C1) * (sigma_x + sigma_y + _SSIM_C2)
  return numerator / denominator


def l1(a: tf.Tensor, b: tf.Tensor) -> tf.Tensor:
  """Mean absolute difference of two same-shaped tensors (paper eq. (3), L_c); scalar."""
  return tf.reduce_mean(tf.abs(a - b))


def appearance_loss(target: tf.Tensor, reconstruction: tf.Tensor, lambda_ssim: float,
                    lambda_l1: float) -> tf.Tensor:
  """Paper eq. (6), appearance loss L_w, for one view.

  L_w = lambda_ssim * mean(clip((1 - SSIM) / 2, 0, 1)) + lambda_l1 * mean(|I - I''|), on
  the [0, 1] scale monodepth's weights 0.85 / 0.15 were chosen for.

  Args:
    target: [B, H, W, C] true view in [0, 1].
    reconstruction: [B, H, W, C] view warped from the other one, in [0, 1].
    lambda_ssim: weight of the SSIM term (paper lambda_1).
    lambda_l1: weight of the L1 term (paper lambda_2).

  Returns:
    Scalar loss, 0 when the images are equal.
  """
  target = tf.convert_to_tensor(target)
  reconstruction = tf.convert_to_tensor(reconstruction, dtype=target.dtype)
  ssim_term = tf.clip_by_value((1.0 - ssim(target, reconstruction)) * 0.5, 0.0, 1.0)
  l1_term = tf.abs(target - reconstruction)
  return lambda_ssim * tf.reduce_mean(ssim_term) + lambda_l1 * tf.reduce_mean(l1_term)


def total_variation(image: tf.Tensor) -> tf.Tensor:
  """Paper eq. (4), image prior L_p = |grad F(I)|: anisotropic total variation.

  Normalised per pixel: mean(|d/du I|) + mean(|d/dv I|), each mean over its own map (all
  channels).

  Args:
    image: [B, H, W, C].

  Returns:
    Scalar, 0 for a constant image.
  """
  image = tf.convert_to_tensor(image)
  _check_rank4(image, 'image')
  du, dv = _gradients(image)
  return tf.reduce_mean(tf.abs(du)) + tf.reduce_mean(tf.abs(dv))


def edge_aware_smoothness(disparity: tf.Tensor, image: tf.Tensor) -> tf.Tensor:
  """Paper eq. (7), disparity smoothness L_s, in both directions.

  L_s = mean(|d/du d| exp(-|d/du I|)) + mean(|d/dv d| exp(-|d/dv I|)), where |d/du I| is the
  mean over colour channels of the absolute forward difference of the image (monodepth's
  weights; unlike monodepth's code the v term is kept).

  Args:
    disparity: [B, H, W, 1], in whatever unit the caller chose (pixels or width fraction).
    image: [B, H, W, C] the view the disparity is referenced to, in [0, 1].

  Returns:
    Scalar, 0 for a constant disparity.
  """
  disparity = tf.convert_to_tensor(disparity)
  image = tf.convert_to_tensor(image, dtype=disparity.dtype)
  _check_rank4(disparity, 'disparity')
  _check_rank4(image, 'image')
  if disparity.shape[-1] != 1:
    raise ValueError(f'disparity must have one channel, got shape {disparity.shape}.')
  d_du, d_dv = _gradients(disparity)
  i_du, i_dv = _gradients(image)
  weight_u = tf.exp(-tf.reduce_mean(tf.abs(i_du), axis=-1, keepdims=True))
  weight_v = tf.exp(-tf.reduce_mean(tf.abs(i_dv), axis=-1, keepdims=True))
  return (tf.reduce_mean(tf.abs(d_du) * weight_u) +
          tf.reduce_mean(tf.abs(d_dv) * weight_v))
