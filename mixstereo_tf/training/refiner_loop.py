"""Training of the hybrid refiner (`models/refiner.py`) on cached examples
(`training/refiner_data.py`), supervised by the synthetic scenes' ground truth.

Loss (not in the paper; the paper's losses need no ground truth, these scenes have it):
  mean min(|d_L - d_L*|, c) + mean min(|d_R - d_R*|, c)  (pixels, every pixel: the scenes'
  disparities are defined everywhere; c = disparity_clip)
  + view_weight * mean |views - views*| (RGB on [0, 1]).
The clip: a fifth of the classical disparities on the training examples are off by more
than 8 px and carry 80 % of the plain L1; no local correction can reach them, and the
plain L1 traded accurate pixels for them (held-out bad-1 up from 28.7 % to 34.2 % after
500 steps). Clipped, the loss counts only errors a correction can fix, as bad-1 does.
Batches: `batch_size` random crops of random examples, each flipped upside down with
probability 1/2 (a vertical flip keeps the epipolar geometry). Every draw of step s comes
from the seed (seed, s), so a resumed run sees the batches an uninterrupted one would.
Checkpoints (model, optimizer, step) every `checkpoint_every` steps, on SIGINT/SIGTERM and
at the end; re-running the same command continues from the newest.
"""

import dataclasses
import os
from typing import Dict, Mapping

from absl import logging
import numpy as np
import tensorflow as tf

from mixstereo_tf.artifacts import runs
from mixstereo_tf.core import image_range
from mixstereo_tf.models import refiner
from mixstereo_tf.training import refiner_data
from mixstereo_tf.training import resumable


@dataclasses.dataclass(frozen=True)
class RefinerTrainConfig:
  """How the refiner is trained.

  Attributes:
    model_dir: checkpoints, config.json and the example shards (`examples/`) go here.
    num_shards: example shards to build and train on.
    shard_size: examples per shard.
    crop_height, crop_width: training crop (multiples of the refiner's size multiple).
    batch_size: crops per step.
    learning_rate: Adam step size (Adam, not the paper's RMSProp: this is not the paper's
      network; docs/DESIGN.md).
    num_steps: optimizer steps to reach (a resumed run continues to this total).
    view_weight: weight of the view L1 against the disparity L1 (pixels).
    disparity_clip: per-pixel disparity errors count up to this many pixels.
    checkpoint_every, log_every: steps between checkpoints / log lines.
    seed: seed of the initialisation and of every batch draw.
  """
  model_dir: str
  num_shards: int = 20
  shard_size: int = 100
  crop_height: int = 128
  crop_width: int = 256
  batch_size: int = 4
  learning_rate: float = 1e-3
  num_steps: int = 6000
  view_weight: float = 10.0
  disparity_clip: float = 4.0
  checkpoint_every: int = 500
  log_every: int = 100
  seed: int = 0

  def __post_init__(self):
    if not self.model_dir:
      raise ValueError('RefinerTrainConfig.model_dir is required.')
    for field in ('num_shards', 'shard_size', 'crop_height', 'crop_width', 'batch_size',
                  'num_steps', 'checkpoint_every', 'log_every'):
      if getattr(self, field) <= 0:
        raise ValueError(f'RefinerTrainConfig.{field} must be positive, got '
                         f'{getattr(self, field)}.')
    if not self.learning_rate > 0 or self.view_weight < 0 or not self.disparity_clip > 0:
      raise ValueError('RefinerTrainConfig.learning_rate and disparity_clip must be positive '
                       'and view_weight non-negative.')


def refiner_loss(outputs: Mapping[str, tf.Tensor], batch: Mapping[str, tf.Tensor],
                 view_weight: float, disparity_clip: float) -> Dict[str, tf.Tensor]:
  """The module docstring's loss.

  Args:
    outputs: RefinerNet outputs ('left', 'right' [B, H, W, 3] in [-1, 1];
      'disparity_left', 'disparity_right' [B, H, W, 1] signed pixels).
    batch: the true values under the same keys and units.
    view_weight: weight of the view term.
    disparity_clip: the largest error a disparity pixel counts, pixels.

  Returns:
    'disparity' (clipped, pixels), 'views' (on [0, 1]) and 'loss'.
  """
  disparity = sum(tf.reduce_mean(tf.minimum(tf.abs(outputs[k] - batch[k]), disparity_clip))
                  for k in ('disparity_left', 'disparity_right'))
  # Views are on [-1, 1]: half their L1 is the L1 on [0, 1].
  views = sum(tf.reduce_mean(tf.abs(outputs[k] - batch[k])) for k in ('left', 'right')) / 4.0
  return {'disparity': disparity, 'views': views, 'loss': disparity + view_weight * views}


def draw_batch(data: Mapping[str, np.ndarray], config: RefinerTrainConfig,
               step: int) -> Dict[str, np.ndarray]:
  """Step `step`'s batch: {'inputs' [B, h, w, 11], targets in network units}."""
  rng = np.random.default_rng([config.seed, step])
  count, height, width = data['mixture'].shape[:3]
  h, w = config.crop_height, config.crop_width
  if h > height or w > width:
    raise ValueError(f'RefinerTrainConfig crop {h}x{w} exceeds the {height}x{width} examples.')
  rows = []
  for _ in range(config.batch_size):
    i, y, x = rng.integers(count), rng.integers(height - h + 1), rng.integers(width - w + 1)
    flip = slice(None, None, -1) if rng.uniform() < 0.5 else slice(None)
    rows.append({k: data[k][i, y:y + h, x:x + w][flip] for k in refiner_data.KEYS})
  stacked = {k: np.stack([r[k] for r in rows]) for k in refiner_data.KEYS}
  batch = {'inputs': refiner.network_input(
      stacked['mixture'], stacked['classical_left'], stacked['classical_right'],
      stacked['classical_disparity_left'], stacked['classical_disparity_right'])}
  for key in ('left', 'right'):
    batch[key] = image_range.u8_to_signed(stacked[key]).astype(np.float32)
  for key in ('disparity_left', 'disparity_right'):
    batch[key] = stacked[key][..., None].astype(np.float32)
  return batch


def train(config: RefinerTrainConfig, examples: refiner_data.ExampleConfig,
          refiner_config: refiner.RefinerConfig, flags_text: str = None) -> str:
  """Builds the examples, trains (resuming), and returns the newest checkpoint prefix."""
  runs.write_run_files(config.model_dir, flags_text, train=config, examples=examples,
                       refiner=refiner_config.to_dict(),
                       pipeline={'mixture': examples.mixtures,
                                 'crop_height': config.crop_height,
                                 'crop_width': config.crop_width})
  folder = os.path.join(config.model_dir, 'examples')
  for shard in range(config.num_shards):
    logging.info('Examples: %s', refiner_data.build_shard(folder, shard, config.shard_size,
                                                          examples))
  data = refiner_data.load_shards(folder, config.num_shards)
  tf.keras.utils.set_random_seed(config.seed)
  model = refiner.build_refiner(refiner_config)
  optimizer = tf.keras.optimizers.Adam(config.learning_rate)
  step, manager = resumable.checkpointed(model, optimizer, config.model_dir)

  @tf.function(reduce_retracing=True)
  def train_step(batch):
    with tf.GradientTape() as tape:
      losses = refiner_loss(model(batch['inputs'], training=True), batch, config.view_weight,
                            config.disparity_clip)
    grads = tape.gradient(losses['loss'], model.trainable_variables)
    optimizer.apply_gradients(zip(grads, model.trainable_variables))
    return losses

  def one_step():
    losses = train_step(draw_batch(data, config, int(step)))
    step.assign_add(1)
    return [float(losses[k]) for k in ('loss', 'disparity', 'views')]

  resumable.run_steps(one_step, step, config.num_steps, manager, config.checkpoint_every,
                      config.log_every, 'loss %.4f  disparity %.3f px  views %.4f')
  return manager.latest_checkpoint
