"""Where a training run executes: the distribution strategy, its device, its writers.

`loop.train` runs one step function under a `tf.distribute` strategy: one device, all local
devices (mirrored), or a multi-worker cluster (TF_CONFIG). The device type picks the
step's compilation and precision (`step.resolve_jit_compile`, `step.precision_policy`).
"""

import os
import tempfile
from typing import Tuple

import tensorflow as tf

from mixstereo_tf.training import config as config_lib


def make_strategy(name: str) -> tf.distribute.Strategy:
  """'default' (one device), 'mirrored' (all local devices), 'multi_worker' (TF_CONFIG)."""
  if name == 'default':
    return tf.distribute.get_strategy()
  if name == 'mirrored':
    return tf.distribute.MirroredStrategy()
  if name == 'multi_worker':
    return tf.distribute.MultiWorkerMirroredStrategy()
  raise ValueError(f'Unknown strategy {name!r}; valid: {config_lib.STRATEGIES}.')


def device_type(strategy: tf.distribute.Strategy) -> str:
  """'GPU' or 'CPU' (or 'TPU'): the device type the step runs on."""
  if strategy is tf.distribute.get_strategy() and not tf.distribute.has_strategy():
    # The default strategy places ops on the first GPU when there is one.
    return 'GPU' if tf.config.list_logical_devices('GPU') else 'CPU'
  devices = strategy.extended.worker_devices
  return tf.DeviceSpec.from_string(devices[0]).device_type or 'CPU'


def write_dir(strategy: tf.distribute.Strategy, model_dir: str) -> Tuple[bool, str]:
  """(is_chief, where this worker writes checkpoints).

  Under MultiWorkerMirroredStrategy every worker takes part in saving (it is a collective
  operation) but only the chief writes to `model_dir`; the others write to a scratch folder.
  """
  resolver = getattr(strategy, 'cluster_resolver', None)
  cluster = resolver.cluster_spec().as_dict() if resolver else {}
  if not cluster:
    return True, model_dir
  task_type, task_id = resolver.task_type, resolver.task_id
  chief = task_type == 'chief' or (task_type == 'worker' and task_id == 0 and
                                   'chief' not in cluster)
  if chief:
    return True, model_dir
  return False, os.path.join(tempfile.gettempdir(), f'mixstereo_{task_type}_{task_id}')


def check_batch(dataset: tf.data.Dataset, strategy: tf.distribute.Strategy) -> int:
  """The static batch size of a training dataset, which the strategy's replicas divide.

  Raises:
    ValueError: a dynamic batch size or one the replicas do not divide.
  """
  batch = dataset.element_spec['mixture'].shape[0]
  if batch is None:
    raise ValueError('The training dataset must have a static batch size (drop_remainder).')
  if batch % strategy.num_replicas_in_sync:
    raise ValueError(f'batch_size {batch} is not divisible by the '
                     f'{strategy.num_replicas_in_sync} replicas of the strategy.')
  return batch
