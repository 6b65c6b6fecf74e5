"""The step loop shared by the small trainers (refiner, matching features): log lines,
checkpoints every few steps, and a checkpoint on SIGINT / SIGTERM and at the end, so that
re-running the same command continues from the newest one. A signal ends the loop with
`Interrupted` after that checkpoint, so that a tool exits non-zero, as the joint trainer's
does."""

import os
import signal
import time
from typing import Callable, Sequence, Tuple

from absl import logging
import numpy as np
import tensorflow as tf


class Interrupted(Exception):
  """SIGINT / SIGTERM stopped the loop; the newest checkpoint holds its last step.

  Attributes:
    exit_code: the shell's code for the signal (128 + its number).
  """

  def __init__(self, signal_name: str, step: int, checkpoint: str):
    super().__init__(f'Stopped by {signal_name} at step {step}; checkpoint {checkpoint} '
                     '(the same command resumes from it).')
    self.exit_code = 128 + signal.Signals[signal_name].value


def checkpointed(model: tf.keras.Model, optimizer, model_dir: str
                 ) -> Tuple[tf.Variable, tf.train.CheckpointManager]:
  """(step counter, manager) of a run's checkpoints (model, optimizer, step; the newest 3
  kept), restored from the newest one in `model_dir` when there is one."""
  step = tf.Variable(0, dtype=tf.int64, name='step')
  checkpoint = tf.train.Checkpoint(model=model, optimizer=optimizer, step=step)
  manager = tf.train.CheckpointManager(checkpoint, model_dir, max_to_keep=3)
  if manager.latest_checkpoint:
    checkpoint.restore(manager.latest_checkpoint)
    logging.info('Resumed from %s at step %d.', manager.latest_checkpoint, int(step))
  return step, manager


def warn_if_trained(model_dir: str, step: int, num_steps: int) -> None:
  """Says so when a resumed run is at num_steps or past it: nothing is left to train."""
  if step >= num_steps:
    logging.warning('%s is at step %d already, not below --num_steps=%d: nothing to train '
                    '(raise --num_steps to continue).', model_dir, step, num_steps)


def run_steps(one_step: Callable[[], Sequence[float]], step: tf.Variable, num_steps: int,
              manager: tf.train.CheckpointManager, checkpoint_every: int, log_every: int,
              log_format: str) -> None:
  """Calls `one_step` until `step` reaches num_steps or a signal asks to stop.

  Args:
    one_step: runs one optimizer step, increments `step`, returns the numbers to log.
    step: the checkpointed step counter.
    num_steps: the total to reach.
    manager: saves the checkpoints (numbered by step).
    checkpoint_every, log_every: steps between checkpoints / log lines.
    log_format: %-format of the mean of `one_step`'s numbers over the last log_every steps.

  Raises:
    Interrupted: a SIGINT / SIGTERM stopped the loop (after its checkpoint).
  """
  warn_if_trained(manager.directory, int(step), num_steps)
  stop = []
  previous = {s: signal.signal(s, lambda signum, _: stop.append(signal.Signals(signum).name))
              for s in (signal.SIGINT, signal.SIGTERM)}
  try:
    start, running = time.perf_counter(), []
    while int(step) < num_steps and not stop:
      running.append(one_step())
      if int(step) % log_every == 0:
        logging.info('step %d/%d  ' + log_format + '  %.2f steps/s', int(step), num_steps,
                     *np.mean(running, axis=0), len(running) / (time.perf_counter() - start))
        start, running = time.perf_counter(), []
      if int(step) % checkpoint_every == 0:
        manager.save(checkpoint_number=int(step))
  finally:
    for sig, handler in previous.items():
      signal.signal(sig, handler)
    if manager.latest_checkpoint != os.path.join(manager.directory, f'ckpt-{int(step)}'):
      manager.save(checkpoint_number=int(step))
  if stop:
    raise Interrupted(stop[0], int(step), manager.latest_checkpoint)
