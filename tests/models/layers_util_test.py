"""Tests of the shared layers: the fused batch norm against Keras' own."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.models import layers_util


def _twins(shape):
  """A Keras BatchNormalization and a FusedBatchNorm with the same non-trivial weights."""
  keras_bn, fused_bn = tf.keras.layers.BatchNormalization(), layers_util.FusedBatchNorm()
  keras_bn.build(shape)
  fused_bn.build(shape)
  channels = shape[-1]
  values = {'gamma': np.linspace(0.5, 2.0, channels), 'beta': np.linspace(-1, 1, channels),
            'moving_mean': np.full(channels, 0.3), 'moving_variance': np.full(channels, 2.0)}
  for layer in (keras_bn, fused_bn):
    for name, value in values.items():
      getattr(layer, name).assign(value.astype(np.float32))
  return keras_bn, fused_bn


def _train_pass(layer, x, jit_compile=False):
  @tf.function(jit_compile=jit_compile)
  def run():
    with tf.GradientTape() as tape:
      tape.watch(x)
      y = layer(x, training=True)
      loss = tf.reduce_sum(y * tf.sin(y))  # A non-trivial upstream gradient.
    return [y] + tape.gradient(loss, [x, layer.gamma, layer.beta])

  return [t.numpy() for t in run()] + [layer.moving_mean.numpy(),
                                       layer.moving_variance.numpy()]


@pytest.mark.parametrize('shape', [[2, 4, 6, 8, 3], [2, 6, 8, 3]])
@pytest.mark.parametrize('jit_compile', [False, True])
def test_fused_batch_norm_trains_exactly_like_keras(shape, jit_compile):
  x = tf.random.stateless_normal(shape, [1, 2]) * 3.0 + 1.0
  keras_bn, fused_bn = _twins(shape)
  want = _train_pass(keras_bn, x)
  got = _train_pass(fused_bn, x, jit_compile)
  names = ('y', 'dx', 'dgamma', 'dbeta', 'moving_mean', 'moving_variance')
  for name, w, g in zip(names, want, got):
    np.testing.assert_allclose(g, w, rtol=1e-4, atol=1e-4, err_msg=name)
  # The moving statistics moved (momentum 0.99 towards the batch's mean ~1, variance ~9).
  assert np.all(got[4] > 0.3) and np.all(got[5] > 2.0)


def test_fused_batch_norm_inference_uses_the_moving_statistics():
  x = tf.random.stateless_normal([1, 4, 4, 2], [3, 4])
  keras_bn, fused_bn = _twins(x.shape)
  np.testing.assert_allclose(fused_bn(x, training=False).numpy(),
                             keras_bn(x, training=False).numpy(), atol=1e-6)
  gamma, beta = np.linspace(0.5, 2.0, 2), np.linspace(-1, 1, 2)
  expected = (x.numpy() - 0.3) / np.sqrt(2.0 + 1e-3) * gamma + beta
  np.testing.assert_allclose(fused_bn(x, training=False).numpy(), expected, atol=1e-5)


def test_bfloat16_convolutions_keep_the_heads_and_the_outputs_in_float32():
  """The refiner with bfloat16 convolutions: its heads (added to float32 views and
  disparities) stay float32, the outputs are float32 and within bfloat16's rounding of the
  float32 model's (its heads made non-zero so that the networks matter)."""
  from mixstereo_tf.models import refiner  # pylint: disable=import-outside-toplevel
  config = refiner.RefinerConfig(view_widths=(8, 8), disparity_features=8, dilations=(1, 2))
  model = refiner.build_refiner(config)
  rng = np.random.default_rng(0)
  model.set_weights([rng.normal(0, 0.1, w.shape).astype(np.float32)
                     for w in model.get_weights()])
  inputs = tf.constant(np.concatenate([rng.uniform(-0.9, 0.9, (1, 16, 32, 9)),
                                       rng.uniform(0, 8, (1, 16, 32, 2))], -1), tf.float32)
  expected = {k: v.numpy() for k, v in model(inputs).items()}
  layers_util.compute_in_bfloat16(model)
  dtypes = [(layer.name, layer.compute_dtype)
            for layer in model._flatten_layers(include_self=False)  # pylint: disable=protected-access
            if isinstance(layer, tf.keras.layers.Conv2D)]
  assert {dtype for name, dtype in dtypes if name == 'head'} == {'float32'}
  assert [name for name, dtype in dtypes if dtype == 'float32'] == ['head', 'head']
  out = model(inputs)
  for key, value in expected.items():
    assert out[key].dtype == tf.float32
    scale = np.abs(value).max()
    np.testing.assert_allclose(out[key], value, atol=0.03 * scale)
    assert np.abs(out[key].numpy() - value).max() > 0  # It did compute in bfloat16.
