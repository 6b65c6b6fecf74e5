"""Frozen training configuration, built once from flags by `mixstereo_tf.train`."""

import dataclasses
from typing import Optional

from mixstereo_tf.training import objective
from mixstereo_tf.training import optimizers

JIT_CHOICES = ('auto', 'true', 'false')
STRATEGIES = ('default', 'mirrored', 'multi_worker')


@dataclasses.dataclass(frozen=True)
class TrainConfig:
  """How to train; the model, data and loss have configs of their own.

  Attributes:
    model_dir: checkpoints, TensorBoard logs and the saved flags go here.
    mode: 'joint' (the paper), 'separation_only' (the ablation) or 'stereo_only' (the stereo
      module on clean pairs: the oracle).
    learning_rate: RMSProp learning rate (paper: 1e-4).
    optimizer: 'rmsprop_tf1' (the paper's TF1 RMSProp: accumulator started at one, epsilon
      1e-10) or 'rmsprop_keras' (Keras 3's RMSprop); see `training/optimizers.py`.
    num_steps: optimizer steps to reach (a resumed run continues to this total).
    jit_compile: 'auto' (XLA where the benchmark found it faster: GPU yes, CPU no), 'true'
      or 'false'.
    strategy: 'default' (one device), 'mirrored' (all local devices) or 'multi_worker'
      (MultiWorkerMirroredStrategy from TF_CONFIG).
    mixed_precision: float16 compute with float32 variables and dynamic loss scaling on a
      GPU, bfloat16 (no scaling) on a CPU (`step.precision_policy`; docs/GPU.md).
    deterministic: op determinism (`tf.config.experimental.enable_op_determinism`): two
      runs of one configuration on one machine give identical weights (the seeds are
      always set from `seed`); slower on a GPU.
    init_checkpoint: weights to start from when model_dir has no checkpoint (fine-tuning).
    checkpoint_every: steps between checkpoints (one is also written on SIGINT/SIGTERM,
      on an exception, and at the end).
    summary_every: steps between TensorBoard scalar summaries.
    image_summary_every: steps between TensorBoard image summaries.
    log_every: steps between progress log lines.
    max_checkpoints: checkpoints kept.
    seed: seed of the weight initialisation (the pipeline has its own).
  """
  model_dir: str
  mode: str = 'joint'
  learning_rate: float = 1e-4
  optimizer: str = 'rmsprop_tf1'
  num_steps: int = 100000
  jit_compile: str = 'auto'
  strategy: str = 'default'
  mixed_precision: bool = False
  deterministic: bool = False
  init_checkpoint: Optional[str] = None
  checkpoint_every: int = 1000
  summary_every: int = 100
  image_summary_every: int = 1000
  log_every: int = 10
  max_checkpoints: int = 3
  seed: int = 0

  def __post_init__(self):
    if not self.model_dir:
      raise ValueError('TrainConfig.model_dir is required.')
    if not 0 <= self.seed < 2**32:
      raise ValueError(f'TrainConfig.seed must be in [0, 2**32), got {self.seed}.')
    if self.mode not in objective.MODES:
      raise ValueError(f'TrainConfig.mode must be one of {objective.MODES}, got {self.mode!r}.')
    if self.jit_compile not in JIT_CHOICES:
      raise ValueError(f'TrainConfig.jit_compile must be one of {JIT_CHOICES}, '
                       f'got {self.jit_compile!r}.')
    if self.strategy not in STRATEGIES:
      raise ValueError(f'TrainConfig.strategy must be one of {STRATEGIES}, '
                       f'got {self.strategy!r}.')
    if self.optimizer not in optimizers.OPTIMIZERS:
      raise ValueError(f'TrainConfig.optimizer must be one of {tuple(optimizers.OPTIMIZERS)}, '
                       f'got {self.optimizer!r}.')
    if not self.learning_rate > 0:
      raise ValueError(f'TrainConfig.learning_rate must be positive, got {self.learning_rate}.')
    for field in ('num_steps', 'checkpoint_every', 'summary_every', 'image_summary_every',
                  'log_every', 'max_checkpoints'):
      if getattr(self, field) <= 0:
        raise ValueError(f'TrainConfig.{field} must be positive, got {getattr(self, field)}.')

