"""Differentiable horizontal bilinear sampling: view reconstruction from disparity.

Rectified stereo only needs 1-D sampling along image rows (the spatial-transformer sampler
of Jaderberg et al. restricted to x, as in monodepth). Offsets and disparities are in
pixels. Sign conventions follow docs/DESIGN.md: the left pixel `x` matches the right pixel
`x - d_L`, the right pixel `x` matches the left pixel `x + d_R`.

Border: sample positions are clamped to [0, W - 1] (edge replication), so a position left
of the image reads column 0 and one right of it reads column W - 1. `in_bounds_mask` tells
which samples were inside. Everything uses static-shape ops (floor, clamp, a width-axis
gather with `batch_dims=2`) and compiles with XLA; gradients reach both the image and the
offset (the offset's gradient is zero where the position was clamped).
"""

import tensorflow as tf


def _check_image_and_offset(image: tf.Tensor, offset: tf.Tensor, image_name: str,
                            offset_name: str) -> None:
  if image.shape.rank != 4:
    raise ValueError(f'{image_name} must be [B, H, W, C], got shape {image.shape}.')
  if offset.shape.rank != 4 or offset.shape[-1] != 1:
    raise ValueError(f'{offset_name} must be [B, H, W, 1], got shape {offset.shape}.')
  if not image.shape[:3].is_compatible_with(offset.shape[:3]):
    raise ValueError(f'{offset_name} shape {offset.shape} does not match {image_name} '
                     f'shape {image.shape} in [B, H, W].')


def _sample_positions(offset: tf.Tensor) -> tf.Tensor:
  """x + offset for every pixel: [B, H, W] float, unclamped."""
  width = tf.shape(offset)[2]
  columns = tf.cast(tf.range(width), offset.dtype)
  return columns[tf.newaxis, tf.newaxis, :] + offset[..., 0]


def sample_horizontal(image: tf.Tensor, offset: tf.Tensor) -> tf.Tensor:
  """Samples each image row at x + offset with linear interpolation.

  Args:
    image: [B, H, W, C] float.
    offset: [B, H, W, 1], pixels, same dtype as `image`; positive reads to the right.

  Returns:
    [B, H, W, C]: output (y, x) = image row y linearly interpolated at
    clamp(x + offset(y, x), 0, W - 1) (edge replication outside the image).

  Raises:
    ValueError: if `image` or `offset` has the wrong rank or mismatched shape.
  """
  image = tf.convert_to_tensor(image)
  offset = tf.convert_to_tensor(offset, dtype=image.dtype)
  _check_image_and_offset(image, offset, 'image', 'offset')
  max_x = tf.cast(tf.shape(image)[2] - 1, image.dtype)
  x = tf.clip_by_value(_sample_positions(offset), 0.0, max_x)
  x0 = tf.floor(x)
  # The gradient with respect to the offset flows through `frac`; floor has none.
  frac = (x - x0)[..., tf.newaxis]
  i0 = tf.cast(x0, tf.int32)
  i1 = tf.minimum(i0 + 1, tf.shape(image)[2] - 1)
  v0 = tf.gather(image, i0, axis=2, batch_dims=2)
  v1 = tf.gather(image, i1, axis=2, batch_dims=2)
  return v0 + frac * (v1 - v0)


def reconstruct_left(right: tf.Tensor, disparity_left: tf.Tensor) -> tf.Tensor:
  """The left view rebuilt from the right one: right sampled at x - d_L.

  Args:
    right: [B, H, W, C] image (or any per-pixel map) in the right view.
    disparity_left: [B, H, W, 1], pixels, positive, left-referenced.

  Returns:
    [B, H, W, C] in the left view's frame, edge-replicated at the border.
  """
  return sample_horizontal(right, -tf.convert_to_tensor(disparity_left))


def reconstruct_right(left: tf.Tensor, disparity_right: tf.Tensor) -> tf.Tensor:
  """The right view rebuilt from the left one: left sampled at x + d_R.

  Args:
    left: [B, H, W, C] image (or any per-pixel map) in the left view.
    disparity_right: [B, H, W, 1], pixels, positive, right-referenced.

  Returns:
    [B, H, W, C] in the right view's frame, edge-replicated at the border.
  """
  return sample_horizontal(left, disparity_right)


def in_bounds_mask(offset: tf.Tensor) -> tf.Tensor:
  """1 where the sample position x + offset lies in [0, W - 1], else 0.

  Args:
    offset: [B, H, W, 1], pixels (use -d_L for `reconstruct_left`, d_R for
      `reconstruct_right`).

  Returns:
    [B, H, W, 1] float mask of the offset's dtype.
  """
  offset = tf.convert_to_tensor(offset)
  if offset.shape.rank != 4 or offset.shape[-1] != 1:
    raise ValueError(f'offset must be [B, H, W, 1], got shape {offset.shape}.')
  x = _sample_positions(offset)
  max_x = tf.cast(tf.shape(offset)[2] - 1, offset.dtype)
  inside = tf.logical_and(x >= 0.0, x <= max_x)
  return tf.cast(inside, offset.dtype)[..., tf.newaxis]
