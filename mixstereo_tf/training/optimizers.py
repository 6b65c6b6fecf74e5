"""The paper's optimizer, RMSProp (section 3.4: "optimized using RMSProp ... 1e-4").

The paper trained with TensorFlow in 2018, i.e. TF1's `tf.train.RMSPropOptimizer` with its
defaults (decay 0.9, momentum 0, epsilon 1e-10) and its mean-square accumulator started at
ONE. Per variable, with gradient g:

    ms  <- rho * ms + (1 - rho) * g^2           (ms starts at 1)
    var <- var - lr * g / sqrt(ms + epsilon)

Keras 3's `RMSprop` starts the accumulator at zero and uses epsilon 1e-7: its first steps
are ~lr * sign(g) (about 3.16 lr for rho 0.9) whatever the gradient's size, while TF1's
are ~lr * g, a warm-up of a few tens of steps in which tiny gradients move their variables
by tiny amounts. `OPTIMIZERS` offers both; 'rmsprop_tf1' is the default of new runs and of
the paper's flagfiles (docs/DESIGN.md).
"""

from typing import Callable, Dict

import keras
import tensorflow as tf


class TF1RMSprop(keras.optimizers.Optimizer):
  """RMSProp with TF1's semantics (module docstring); momentum 0, not centred."""

  def __init__(self, learning_rate=1e-4, rho: float = 0.9, epsilon: float = 1e-10,
               initial_accumulator: float = 1.0, name: str = 'tf1_rmsprop', **kwargs):
    super().__init__(learning_rate=learning_rate, name=name, **kwargs)
    self.rho = rho
    self.epsilon = epsilon
    self.initial_accumulator = initial_accumulator

  def build(self, var_list):
    if self.built:
      return
    super().build(var_list)
    self._mean_squares = self.add_optimizer_variables(
        var_list, 'rms', initializer=keras.initializers.Constant(self.initial_accumulator))

  def update_step(self, gradient, variable, learning_rate):
    """ms <- rho ms + (1 - rho) g^2; var <- var - lr g / sqrt(ms + epsilon)."""
    ops = keras.ops
    lr = ops.cast(learning_rate, variable.dtype)
    gradient = ops.cast(gradient, variable.dtype)
    mean_square = self._mean_squares[self._get_variable_index(variable)]
    self.assign(mean_square, ops.add(ops.multiply(self.rho, mean_square),
                                     ops.multiply(1.0 - self.rho, ops.square(gradient))))
    self.assign_sub(variable, ops.divide(ops.multiply(lr, gradient),
                                         ops.sqrt(ops.add(mean_square, self.epsilon))))

  def get_config(self):
    config = super().get_config()
    config.update(rho=self.rho, epsilon=self.epsilon,
                  initial_accumulator=self.initial_accumulator)
    return config


OPTIMIZERS: Dict[str, Callable[[float], keras.optimizers.Optimizer]] = {
    'rmsprop_tf1': TF1RMSprop,
    'rmsprop_keras': lambda learning_rate: tf.keras.optimizers.RMSprop(learning_rate),
}


def make_optimizer(name: str, learning_rate: float) -> keras.optimizers.Optimizer:
  """The optimizer called `name` (a key of OPTIMIZERS) at `learning_rate`."""
  if name not in OPTIMIZERS:
    raise ValueError(f'Unknown TrainConfig.optimizer={name!r}; valid: '
                     f'{", ".join(OPTIMIZERS)}.')
  return OPTIMIZERS[name](learning_rate)
