"""The custom train step: forward, the paper's objective, backward, RMSProp update.

The forward and backward pass (where all the convolutions are) is one `tf.function` that
XLA may compile; the optimizer update runs outside it because under a distribution strategy
it all-reduces the gradients across replicas (a cross-replica `merge_call`, which XLA
cannot contain).
"""

from typing import Dict, List, Tuple

import tensorflow as tf

from mixstereo_tf.training import objective


def resolve_jit_compile(setting: str, device_type: str) -> bool:
  """Maps `--jit_compile` to a bool for the device type at hand ('CPU', 'GPU', ...).

  'auto' follows experiments/BENCHMARKS.md: XLA on GPUs (the design target), not on CPUs,
  where the XLA CPU backend was measured to make this conv-heavy step several times slower.
  """
  if setting == 'true':
    return True
  if setting == 'false':
    return False
  if setting == 'auto':
    return device_type.upper() == 'GPU'
  raise ValueError(f"jit_compile must be 'auto', 'true' or 'false', got {setting!r}.")


def precision_policy(mixed_precision: bool, device_type: str) -> str:
  """The Keras dtype policy of `--mixed_precision` on a device type ('CPU', 'GPU', ...).

  Off: 'float32'. On: 'mixed_float16' on a GPU (Tensor Cores; the loop adds dynamic loss
  scaling), 'mixed_bfloat16' elsewhere (float16 has no fast CPU kernels; bfloat16 has
  float32's range, so no loss scaling). Variables, batch-norm statistics, the soft-argmin
  and every loss stay float32 (docs/GPU.md).
  """
  if not mixed_precision:
    return 'float32'
  return 'mixed_float16' if device_type.upper() == 'GPU' else 'mixed_bfloat16'


def trainable_variables(model: tf.keras.Model, mode: str) -> List[tf.Variable]:
  """The variables a mode trains: all (joint), the U-Net only, or the stereo network only."""
  if mode == 'joint':
    return list(model.trainable_variables)
  if mode == 'separation_only':
    return list(model.separation.trainable_variables)
  if mode == 'stereo_only':
    return list(model.stereo.trainable_variables)
  raise ValueError(f'Unknown mode {mode!r}; valid modes are {objective.MODES}.')


def forward(model: tf.keras.Model, batch: Dict[str, tf.Tensor], mode: str,
            training: bool) -> Dict[str, tf.Tensor]:
  """Runs the parts of the model a mode uses; outputs are cast to float32."""
  if mode == 'joint':
    outputs = model(batch['mixture'], training=training)
  elif mode == 'separation_only':
    outputs = model.separate(batch['mixture'], training=training)
  elif mode == 'stereo_only':
    # The oracle: the stereo module sees the clean pair.
    outputs = model.compute_disparity(batch['left'], batch['right'], training=training)
  else:
    raise ValueError(f'Unknown mode {mode!r}; valid modes are {objective.MODES}.')
  return {k: tf.cast(v, tf.float32) for k, v in outputs.items()}


def separation_psnr(outputs: Dict[str, tf.Tensor],
                    batch: Dict[str, tf.Tensor]) -> Dict[str, tf.Tensor]:
  """PSNR (dB) of the separated views against the true ones, images in [-1, 1]."""
  out = {}
  for view in ('left', 'right'):
    if view in outputs:
      predicted = tf.clip_by_value(outputs[view], -1.0, 1.0)
      out[f'metrics/psnr_{view}'] = tf.reduce_mean(tf.image.psnr(predicted, batch[view], 2.0))
  return out


class TrainStep:
  """Builds the distributed train step for a model, optimizer, objective and mode.

  Calling the instance with a distributed batch runs one step on every replica and returns
  (scalars, outputs): scalars are the loss terms and metrics averaged over replicas,
  outputs are the first replica's model outputs (for image summaries).
  """

  def __init__(self, model: tf.keras.Model, optimizer, loss_config: objective.LossConfig,
               mode: str, strategy: tf.distribute.Strategy, jit_compile: bool):
    self.model = model
    self.optimizer = optimizer
    self.loss_config = loss_config
    self.mode = mode
    self.strategy = strategy
    self.variables = trainable_variables(model, mode)
    # Monocular: the left view is the input itself, only the right one is separated.
    self.separated_views = (('right',) if model.model_config.input_is_left
                            else objective.VIEWS)
    # Dynamic loss scaling makes inf gradients a normal event (the step is skipped).
    self.loss_scaled = isinstance(optimizer, tf.keras.mixed_precision.LossScaleOptimizer)
    self._gradients = tf.function(self._loss_and_gradients, jit_compile=jit_compile)
    self._step = tf.function(self._distributed_step)

  def _loss_and_gradients(self, batch):
    """The XLA-compilable part: forward, objective, backward, on numeric tensors only."""
    with tf.GradientTape() as tape:
      outputs = forward(self.model, batch, self.mode, training=True)
      scalars = objective.total_loss(outputs, batch, self.loss_config, self.mode,
                                     self.separated_views)
      # Each replica's loss is a mean over its share of the global batch; the gradients are
      # summed across replicas, so dividing by their number gives the global mean.
      loss = scalars['loss'] / self.strategy.num_replicas_in_sync
      if self.loss_scaled:
        loss = self.optimizer.scale_loss(loss)
    gradients = tape.gradient(loss, self.variables)
    scalars.update(separation_psnr(outputs, batch))
    # NaN gradients with a finite loss would silently poison the weights: the loop checks
    # this norm as well as the loss. Under loss scaling the gradients carry the scale
    # (the optimizer divides it out before applying them): so does the norm, until here.
    norm = tf.linalg.global_norm(gradients)
    if self.loss_scaled:
      scale = tf.cast(self.optimizer.scale_loss(tf.constant(1.0)), norm.dtype)
      norm = norm / scale
      scalars['metrics/loss_scale'] = scale
    scalars['metrics/gradient_norm'] = norm
    return scalars, outputs, gradients

  def _replica_step(self, batch):
    # XLA takes no string arguments: the pipeline's `name` (and any other non-numeric
    # entry) stays outside the compiled function.
    numeric = {k: v for k, v in batch.items() if v.dtype != tf.string}
    scalars, outputs, gradients = self._gradients(numeric)
    self.optimizer.apply_gradients(zip(gradients, self.variables))
    return scalars, outputs

  def _distributed_step(self, batch):
    scalars, outputs = self.strategy.run(self._replica_step, args=(batch,))
    scalars = {k: self.strategy.reduce(tf.distribute.ReduceOp.MEAN, v, axis=None)
               for k, v in scalars.items()}
    first = lambda x: self.strategy.experimental_local_results(x)[0]
    return scalars, tf.nest.map_structure(first, outputs)

  def __call__(self, batch) -> Tuple[Dict[str, tf.Tensor], Dict[str, tf.Tensor]]:
    return self._step(batch)
