"""What a real anaglyph file does to a mixture, for training on realistic inputs.

Published anaglyphs come out of cameras, encoders and JPEG files, not out of `mixtures.mix`
on clean renders. `degrade` applies, with stateless randomness (one seed per element):
  * channel imbalance: per-channel gain U[0.9, 1.1] and gamma U[0.9, 1.1] (encoders and
    displays differ in how they weigh the channels);
  * vignetting: gain 1 - v r^2, r the distance to the centre over the half-diagonal,
    v ~ U[0, 0.3];
  * blur (p = 0.5): a Gaussian of sigma ~ U[0.3, 1.2] px;
  * sensor noise: Gaussian, sigma ~ U[0, 0.02] (on [0, 1]);
  * JPEG (p = 0.5): quality ~ U[60, 95] with 4:2:0 chroma subsampling, which smears the
    colour channels an anaglyph stores its views in.
Only the mixture is degraded: the views the losses compare against stay clean. Images are
[H, W, 3] float32 on [0, 1].
"""

import tensorflow as tf


def _gaussian_blur(image: tf.Tensor, sigma: tf.Tensor) -> tf.Tensor:
  radius = 3
  taps = tf.range(-radius, radius + 1, dtype=tf.float32)
  kernel = tf.exp(-0.5 * (taps / sigma) ** 2)
  kernel /= tf.reduce_sum(kernel)
  channels = tf.transpose(image, [2, 0, 1])[..., None]  # [3, H, W, 1]
  padded = tf.pad(channels, [[0, 0], [radius, radius], [radius, radius], [0, 0]], 'SYMMETRIC')
  out = tf.nn.conv2d(padded, tf.reshape(kernel, [1, -1, 1, 1]), 1, 'VALID')
  out = tf.nn.conv2d(out, tf.reshape(kernel, [-1, 1, 1, 1]), 1, 'VALID')
  return tf.transpose(out[..., 0], [1, 2, 0])


def parameters(seed: tf.Tensor) -> dict:
  """The random draws of `degrade` for a stateless seed [2]."""
  u = tf.random.stateless_uniform([12], seed)
  return {'gain': 0.9 + 0.2 * u[0:3], 'gamma': 0.9 + 0.2 * u[3:6], 'vignette': 0.3 * u[6],
          'blur': u[7] < 0.5, 'sigma': 0.3 + 0.9 * u[8], 'noise': 0.02 * u[9],
          'jpeg': u[10] < 0.5, 'quality': tf.cast(60.0 + 35.0 * u[11], tf.int32)}


def degrade(image: tf.Tensor, seed: tf.Tensor) -> tf.Tensor:
  """The mixture as a real file would hold it (module docstring); [H, W, 3] in [0, 1]."""
  params = parameters(seed)
  image = tf.clip_by_value(tf.pow(tf.clip_by_value(image, 0.0, 1.0), params['gamma']) *
                           params['gain'], 0.0, 1.0)
  height, width = tf.shape(image)[0], tf.shape(image)[1]
  y = (tf.cast(tf.range(height), tf.float32) - tf.cast(height - 1, tf.float32) / 2)[:, None]
  x = (tf.cast(tf.range(width), tf.float32) - tf.cast(width - 1, tf.float32) / 2)[None, :]
  radius2 = (x * x + y * y) / (tf.cast(height * height + width * width, tf.float32) / 4)
  image = image * (1.0 - params['vignette'] * radius2)[..., None]
  image = tf.cond(params['blur'], lambda: _gaussian_blur(image, params['sigma']),
                  lambda: image)
  noise = tf.random.stateless_normal(tf.shape(image), seed + [0, 1]) * params['noise']
  image = tf.clip_by_value(image + noise, 0.0, 1.0)
  return tf.cond(params['jpeg'],
                 lambda: tf.image.adjust_jpeg_quality(image, params['quality']),
                 lambda: image)
