"""Layer factories and the input-size check shared by the modules."""

import tensorflow as tf


def conv2d(filters: int, kernel: int, strides: int = 1, activation='relu', use_bias=True,
           name=None) -> tf.keras.layers.Layer:
  return tf.keras.layers.Conv2D(filters, kernel, strides=strides, padding='same',
                                activation=activation, use_bias=use_bias, name=name)


def conv2d_transpose(filters: int, kernel: int, name=None) -> tf.keras.layers.Layer:
  return tf.keras.layers.Conv2DTranspose(filters, kernel, strides=2, padding='same',
                                         activation='relu', name=name)


def tracked(owner: tf.keras.layers.Layer, name: str, layers):
  """Makes each layer of a list an attribute of `owner`, and returns the list.

  Keras 3 keeps layers held in lists for its own variable collection, but
  `tf.train.Checkpoint` only follows attributes; without this, checkpoints silently miss
  every layer kept in a list.
  """
  layers = list(layers)
  for index, layer in enumerate(layers):
    setattr(owner, f'{name}_{index}', layer)
  return layers


def check_size(image: tf.Tensor, multiple: int, what: str) -> None:
  """Raises ValueError when a static height or width is not a multiple of `multiple`."""
  height, width = image.shape[1], image.shape[2]
  for size, axis in ((height, 'height'), (width, 'width')):
    if size is not None and size % multiple:
      raise ValueError(
          f'{what} {axis} {size} is not a multiple of {multiple}; pad the image (edge '
          f'replication, as mixstereo_tf.inference does) or crop to a multiple of {multiple}.')
