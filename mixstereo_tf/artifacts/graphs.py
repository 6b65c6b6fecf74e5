"""The networks' uint8 graphs on images of any size: padding to the network's multiple.

The networks need inputs whose height and width are multiples of `size_multiple` (32 for
the paper's model). An image of any size is padded at the bottom and the right by edge
replication, run, and the outputs are cropped back. Padding does not move the image
content, so disparities keep their units (pixels of the input image). `serving_function`
is the graph shared by the `unmixing.predictors.Unmixer` and the SavedModel (`serving`).
"""

from typing import Callable, Dict

import numpy as np
import tensorflow as tf

from mixstereo_tf import models
from mixstereo_tf.core import image_range

Outputs = Dict[str, np.ndarray]


def pad_to_multiple(image: tf.Tensor, multiple: int) -> tf.Tensor:
  """Pads height and width at the bottom / right to multiples of `multiple`.

  Edge replication: padded rows and columns copy the last row / column. Works on dynamic
  shapes (for serving graphs).

  Args:
    image: [B, H, W, C] or [H, W, C], any dtype.
    multiple: positive int.

  Returns:
    The padded image, [.., ceil(H / m) m, ceil(W / m) m, C]; `image[..., :H, :W, :]` of it
    is the input.
  """
  if multiple <= 0:
    raise ValueError(f'multiple must be positive, got {multiple}.')
  image = tf.convert_to_tensor(image)
  shape = tf.shape(image)
  for axis in (-3, -2):
    size = shape[axis]
    padded = (size + multiple - 1) // multiple * multiple
    image = tf.gather(image, tf.minimum(tf.range(padded), size - 1), axis=image.shape.rank + axis)
  return image


def crop_to(image: tf.Tensor, height, width) -> tf.Tensor:
  """Inverse of `pad_to_multiple`: the top-left [.., height, width, C] of `image`."""
  return image[..., :height, :width, :]


def _padded_input(image: tf.Tensor, multiple: int) -> tf.Tensor:
  """uint8 [H, W, 3] -> padded [1, H', W', 3] network input in [-1, 1]."""
  return image_range.u8_to_signed(pad_to_multiple(image, multiple))[tf.newaxis]


def serving_function(model: models.MixStereoNet) -> Callable[[tf.Tensor], Dict[str, tf.Tensor]]:
  """The uint8-in graph of a joint model, shared by the `Unmixer` and the SavedModel.

  Returns:
    fn(image uint8 [H, W, 3]) -> {'left', 'right': uint8 [H, W, 3], 'disparity',
    'disparity_right': float32 [H, W] pixels (left- and right-referenced)}.
  """
  multiple = model.size_multiple

  def unmix(image: tf.Tensor) -> Dict[str, tf.Tensor]:
    height, width = tf.shape(image)[0], tf.shape(image)[1]
    outputs = model(_padded_input(image, multiple), training=False)
    result = {key: image_range.signed_to_u8(crop_to(outputs[key][0], height, width))
              for key in ('left', 'right')}
    for key, name in (('disparity_left', 'disparity'), ('disparity_right', 'disparity_right')):
      result[name] = tf.cast(crop_to(outputs[key][0], height, width)[..., 0], tf.float32)
    return result

  return unmix


def pair_function(model: models.MixStereoNet) -> Callable[[np.ndarray, np.ndarray], Outputs]:
  """The stereo module of a joint model on a clean uint8 pair (the 'oracle' method).

  Both views are padded like mixtures; returns {'disparity_left', 'disparity_right'}
  ([H, W] float32 pixels).
  """
  multiple = model.size_multiple

  @tf.function(input_signature=[tf.TensorSpec([None, None, 3], tf.uint8)] * 2)
  def disparities(left, right):
    height, width = tf.shape(left)[0], tf.shape(left)[1]
    out = model.compute_disparity(_padded_input(left, multiple),
                                  _padded_input(right, multiple), training=False)
    return {key: crop_to(tf.cast(out[key][0], tf.float32), height, width)[..., 0]
            for key in ('disparity_left', 'disparity_right')}

  return lambda left, right: {key: value.numpy() for key, value in
                              disparities(tf.constant(left), tf.constant(right)).items()}
