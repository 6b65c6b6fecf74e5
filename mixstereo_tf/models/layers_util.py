"""Layer factories and the input-size check shared by the modules."""

import tensorflow as tf


def conv2d(filters: int, kernel: int, strides: int = 1, activation='relu', use_bias=True,
           name=None, dilation: int = 1) -> tf.keras.layers.Layer:
  return tf.keras.layers.Conv2D(filters, kernel, strides=strides, padding='same',
                                activation=activation, use_bias=use_bias, name=name,
                                dilation_rate=dilation)


def conv2d_transpose(filters: int, kernel: int, name=None) -> tf.keras.layers.Layer:
  return tf.keras.layers.Conv2DTranspose(filters, kernel, strides=2, padding='same',
                                         activation='relu', name=name)


class FusedBatchNorm(tf.keras.layers.BatchNormalization):
  """Keras batch normalisation whose training pass runs TF's fused kernel.

  Keras 3 normalises with separate moments, subtract and scale ops; on the stereo
  module's [2, 48, 128, 256, 32] volumes that took about twice as long, forward and
  backward, as one FusedBatchNormV3 (experiments/BENCHMARKS.md). Same variables, update
  rule (momentum, biased batch variance) and checkpoint keys as the Keras layer; the
  inference pass is Keras' own. Channels last, 4D or 5D inputs.
  """

  def call(self, inputs, training=None, mask=None):
    if not (training and self.trainable) or mask is not None or self.renorm:
      return super().call(inputs, training=training, mask=mask)
    x = tf.cast(inputs, tf.float32)  # As Keras: statistics in float32.
    shape = x.shape
    if self.axis not in (-1, len(shape) - 1) or len(shape) not in (4, 5):
      return super().call(inputs, training=training, mask=mask)
    ones = tf.ones(shape[-1:], tf.float32)
    y, mean, variance = tf.compat.v1.nn.fused_batch_norm(
        x, self.gamma if self.scale else ones, self.beta if self.center else 0.0 * ones,
        epsilon=self.epsilon, data_format='NHWC' if len(shape) == 4 else 'NDHWC',
        is_training=True)
    # The fused op returns the Bessel-corrected variance; Keras averages the biased one.
    count = tf.cast(tf.reduce_prod(tf.shape(x)[:-1]), tf.float32)
    variance *= (count - 1.0) / tf.maximum(count, 1.0)
    self.moving_mean.assign(self.moving_mean * self.momentum + mean * (1.0 - self.momentum))
    self.moving_variance.assign(self.moving_variance * self.momentum +
                                variance * (1.0 - self.momentum))
    return tf.cast(y, self.compute_dtype)


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


FLOAT32_LAYERS = ('head',)  # Layers whose outputs are added to float32 tensors.


def compute_in_bfloat16(model: tf.keras.layers.Layer, keep=FLOAT32_LAYERS) -> None:
  """Makes every convolution of `model` compute in bfloat16 (variables stay float32)
  except those named in `keep`, for inference (`core/precision.py`). A model's code casts
  a bfloat16 result to float32 where it leaves the convolutions (`tf.cast`; a no-op in
  float32), and its layers named in `keep` take bfloat16 inputs and compute in float32."""
  convolutions = (tf.keras.layers.Conv2D, tf.keras.layers.Conv2DTranspose,
                  tf.keras.layers.Conv3D, tf.keras.layers.Conv3DTranspose)
  for layer in model._flatten_layers(include_self=False):  # pylint: disable=protected-access
    if isinstance(layer, convolutions) and layer.name not in keep:
      layer.dtype_policy = 'mixed_bfloat16'


def check_size(image: tf.Tensor, multiple: int, what: str) -> None:
  """Raises ValueError when a static height or width is not a multiple of `multiple`."""
  height, width = image.shape[1], image.shape[2]
  for size, axis in ((height, 'height'), (width, 'width')):
    if size is not None and size % multiple:
      raise ValueError(
          f'{what} {axis} {size} is not a multiple of {multiple}; pad the image (edge '
          f'replication, as mixstereo_tf.unmixing.predictors does) or crop to a multiple of {multiple}.')
