"""The training loop: strategy, checkpoints that survive interruptions, summaries, progress.

Checkpoints (`tf.train.CheckpointManager` in `model_dir`) hold the model, the optimizer
state and its step counter. One is written every `checkpoint_every` steps, at the end, on
SIGINT/SIGTERM (the loop finishes the running step, saves and returns), and when a step
raises. A non-finite loss raises `NonFiniteLossError` naming the step WITHOUT saving, so the
last good checkpoint stays the newest.
"""

import dataclasses
import math
import os
import signal
import time
from typing import Callable, Optional, Tuple

from absl import logging
import tensorflow as tf

from mixstereo_tf import models
from mixstereo_tf.artifacts import runs
from mixstereo_tf.ops import conv3d
from mixstereo_tf.training import config as config_lib
from mixstereo_tf.training import distribution
from mixstereo_tf.training import objective
from mixstereo_tf.training import optimizers
from mixstereo_tf.training import resumable
from mixstereo_tf.training import step as step_lib
from mixstereo_tf.training import summaries


class NonFiniteLossError(FloatingPointError):
  """The loss became NaN or infinite; the message names the step."""


@dataclasses.dataclass(frozen=True)
class TrainResult:
  """What a call to `train` did."""
  start_step: int
  final_step: int
  interrupted_by: Optional[str]
  last_checkpoint: Optional[str]
  final_loss: float
  steps_per_second: float
  num_replicas: int


class _StopSignals:
  """Turns SIGINT/SIGTERM into a flag the loop checks between steps."""

  def __init__(self):
    self.received: Optional[str] = None
    self._previous = {}

  def __enter__(self):
    for signum in (signal.SIGINT, signal.SIGTERM):
      self._previous[signum] = signal.signal(signum, self._handle)
    return self

  def _handle(self, signum, frame):
    del frame
    self.received = signal.Signals(signum).name

  def __exit__(self, *exc):
    for signum, handler in self._previous.items():
      signal.signal(signum, handler)


@dataclasses.dataclass
class _Session:
  """Everything a run needs once set up: where it writes and what it trains."""
  strategy: tf.distribute.Strategy
  write_dir: str
  chief: bool
  model_config: models.ModelConfig
  model: tf.keras.Model
  optimizer: tf.keras.optimizers.Optimizer
  trainer: step_lib.TrainStep
  checkpoint: tf.train.Checkpoint
  manager: tf.train.CheckpointManager


def _prepare(config: config_lib.TrainConfig, model_config: models.ModelConfig,
             flags_text: Optional[str], configs: dict
             ) -> Tuple[tf.distribute.Strategy, bool, str, models.ModelConfig, bool]:
  """Step 1: the strategy, the run directory's files and the device-dependent choices.

  Returns (strategy, is_chief, write_dir, model_config with conv3d resolved, jit).
  """
  strategy = distribution.make_strategy(config.strategy)
  chief, write_dir = distribution.write_dir(strategy, config.model_dir)
  if chief:
    runs.write_run_files(config.model_dir, flags_text, **configs)
  device_type = distribution.device_type(strategy)
  jit = step_lib.resolve_jit_compile(config.jit_compile, device_type)
  if model_config.conv3d_implementation == 'auto':
    model_config = dataclasses.replace(
        model_config, conv3d_implementation=conv3d.auto_implementation(device_type, jit))
  policy = step_lib.precision_policy(config.mixed_precision, device_type)
  tf.keras.mixed_precision.set_global_policy(policy)
  if config.deterministic:  # Process-wide, like the policy; XLA follows it on GPUs.
    tf.config.experimental.enable_op_determinism()
  tf.keras.utils.set_random_seed(config.seed)
  logging.info('Strategy %s with %d replica(s) on %s; jit_compile=%s; conv3d %s; mode=%s; '
               '%s; deterministic=%s.', config.strategy, strategy.num_replicas_in_sync,
               device_type, jit, model_config.conv3d_implementation, config.mode, policy,
               config.deterministic)
  return strategy, chief, write_dir, model_config, jit


def _build(config: config_lib.TrainConfig, model_config: models.ModelConfig,
           loss_config: objective.LossConfig, strategy: tf.distribute.Strategy, chief: bool,
           write_dir: str, jit: bool) -> _Session:
  """Step 2: model, optimizer (paper: RMSProp, 1e-4), train step and checkpoint manager."""
  with strategy.scope():
    model = models.build_model(model_config)
    optimizer = optimizers.make_optimizer(config.optimizer, config.learning_rate)
    if tf.keras.mixed_precision.global_policy().compute_dtype == 'float16':
      optimizer = tf.keras.mixed_precision.LossScaleOptimizer(optimizer)
    trainer = step_lib.TrainStep(model, optimizer, loss_config, config.mode, strategy, jit)
    optimizer.build(trainer.variables)
    checkpoint = tf.train.Checkpoint(model=model, optimizer=optimizer)
  manager = tf.train.CheckpointManager(checkpoint, write_dir,
                                       max_to_keep=config.max_checkpoints)
  return _Session(strategy, write_dir, chief, model_config, model, optimizer, trainer,
                  checkpoint, manager)


def _restore_or_initialise(session: _Session, config: config_lib.TrainConfig) -> int:
  """Step 3: resume from the run's newest checkpoint, else read `init_checkpoint`'s
  model weights (fine-tuning), else keep the fresh initialisation. Returns the step."""
  latest = tf.train.latest_checkpoint(config.model_dir)  # Every worker resumes the chief's.
  if latest:
    session.checkpoint.restore(latest).assert_existing_objects_matched()
    logging.info('Resumed from %s at step %d.', latest,
                 int(session.optimizer.iterations.numpy()))
  elif config.init_checkpoint:
    try:
      _, init = runs.resolve_checkpoint(config.init_checkpoint)
      status = tf.train.Checkpoint(model=session.model).read(init)
      status.expect_partial().assert_existing_objects_matched()  # Optimizer slots unread.
    except AssertionError:
      raise runs.RunDirError(
          f'--init_checkpoint={config.init_checkpoint}: lacks weights of this '
          f'{type(session.model).__name__} (a refiner or feature stage run? Its '
          "architecture flags must be this run's; see its config.json)") from None
    except (ValueError, tf.errors.OpError) as e:
      raise runs.RunDirError(
          f'--init_checkpoint={config.init_checkpoint}: {str(e).splitlines()[0]} (its '
          "architecture flags must be this run's; see its config.json)") from None
    logging.info('Initialised the model from %s.', init)
  return int(session.optimizer.iterations.numpy())


def _due(step: int, every: int, last: int = -1) -> bool:
  """The cadence of every periodic action: at multiples of `every`, and at `last`."""
  return step % every == 0 or step == last


def _check_finite(loss: float, gradient_norm: float, session: _Session, step: int,
                  skipped: int = 0) -> None:
  # 40 updates in a row skipped by loss scaling (scale < 2^-25): the gradients are broken.
  if not (math.isfinite(loss) and skipped < 40 and (session.trainer.loss_scaled or
                                                    math.isfinite(gradient_norm))):
    raise NonFiniteLossError(
        f'Non-finite loss {loss} (gradient norm {gradient_norm}, {skipped} updates skipped '
        f'in a row) at step {step}; '
        f'stopping. The last good checkpoint is {session.manager.latest_checkpoint} '
        '(not overwritten).')


def _periodic(session: _Session, config: config_lib.TrainConfig, step: int,
              result: Tuple[dict, dict, dict], rate: float,
              last_save: Optional[str]) -> Optional[str]:
  """Summaries, log line, checkpoint due at `step` of `result`; returns the newest save."""
  scalars, outputs, batch = result
  if _due(step, config.summary_every):
    summaries.write_scalars({k: float(v) for k, v in scalars.items()}, step,
                            {'learning_rate': config.learning_rate, 'steps_per_second': rate})
  if _due(step, config.image_summary_every):
    local = session.strategy.experimental_local_results(batch)[0]
    summaries.write_images(local, outputs, step, session.model_config.max_disparity)
  if _due(step, config.log_every, config.num_steps):
    eta = (config.num_steps - step) / rate if rate > 0 else math.nan
    logging.info('step %d/%d  loss %.4f  %.3f steps/s  ETA %.0f s', step, config.num_steps,
                 float(scalars['loss']), rate, eta)
  if _due(step, config.checkpoint_every):
    last_save = session.manager.save(checkpoint_number=step)
  return last_save


def _run_steps(session: _Session, config: config_lib.TrainConfig,
               dataset: tf.data.Dataset, start_step: int) -> TrainResult:
  """Step 4: the step loop with its summary, log and checkpoint cadences."""
  writer = (tf.summary.create_file_writer(os.path.join(config.model_dir, 'train'))
            if session.chief else tf.summary.create_noop_writer())
  iterator = iter(session.strategy.experimental_distribute_dataset(dataset))
  step, loss, rate, skipped = start_step, math.nan, 0.0, 0
  last_save = session.manager.latest_checkpoint
  tick, tick_step = None, step
  with _StopSignals() as signals, writer.as_default():
    try:
      while step < config.num_steps and signals.received is None:
        batch = next(iterator)
        scalars, outputs = session.trainer(batch)
        previous, step = step, int(session.optimizer.iterations.numpy())
        skipped = skipped + 1 if step == previous else 0
        loss = float(scalars['loss'])
        _check_finite(loss, float(scalars['metrics/gradient_norm']), session, step, skipped)
        if skipped:  # Loss scaling skipped the update (inf gradients): no new step.
          continue
        if tick is None:  # The first step includes tracing and compilation.
          tick, tick_step = time.perf_counter(), step
        elif step > tick_step:
          rate = (step - tick_step) / (time.perf_counter() - tick)
        last_save = _periodic(session, config, step, (scalars, outputs, batch), rate, last_save)
    except NonFiniteLossError:
      raise
    except BaseException:
      # A crash in the data or the step: keep the weights of the last completed step, if
      # this run completed one (before that, the newest checkpoint already holds them).
      if step > start_step:
        last_save = session.manager.save(checkpoint_number=step)
      logging.error('Training failed at step %d; newest checkpoint: %s.', step, last_save)
      raise
    if last_save is None or int(last_save.rsplit('-', 1)[-1]) != step:
      last_save = session.manager.save(checkpoint_number=step)
    if signals.received:
      logging.warning('Stopped by %s at step %d; checkpoint %s.', signals.received, step,
                      last_save)
  writer.flush()
  return TrainResult(start_step=start_step, final_step=step,
                     interrupted_by=signals.received, last_checkpoint=last_save,
                     final_loss=loss, steps_per_second=rate,
                     num_replicas=session.strategy.num_replicas_in_sync)


def train(config: config_lib.TrainConfig, model_config: models.ModelConfig,
          loss_config: objective.LossConfig,
          dataset_fn: Callable[[int], tf.data.Dataset],
          flags_text: Optional[str] = None,
          extra_configs: Optional[dict] = None) -> TrainResult:
  """Trains (or resumes training) until `config.num_steps` optimizer steps.

  Args:
    config: the training configuration.
    model_config: the architecture.
    loss_config: the loss weights.
    dataset_fn: `dataset_fn(start)` returns the training dataset of GLOBAL batches (it is
      split over replicas) from batch `start` on: a resumed run continues the stream.
    flags_text: the command line flags, saved as `flags.txt` beside the checkpoints.
    extra_configs: other configs (data, pipeline) to record in `config.json`.

  Returns:
    A TrainResult.

  Raises:
    NonFiniteLossError: the loss became non-finite; the newest checkpoint is the last good.
  """
  configs = dict(train=config, model=model_config, loss=loss_config, **(extra_configs or {}))
  strategy, chief, write_dir, model_config, jit = _prepare(config, model_config, flags_text,
                                                           configs)
  session = _build(config, model_config, loss_config, strategy, chief, write_dir, jit)
  start_step = _restore_or_initialise(session, config)
  resumable.warn_if_trained(config.model_dir, start_step, config.num_steps)
  dataset = dataset_fn(start_step)
  distribution.check_batch(dataset, strategy)
  return _run_steps(session, config, dataset, start_step)
