r"""Trains the joint separation + stereo network (or an ablation) from stereo pairs.

  python -m mixstereo_tf.train --flagfile=experiments/demo.flags --model_dir=runs/demo

Re-running with the same --model_dir resumes from its newest checkpoint. SIGINT/SIGTERM
save a checkpoint and exit with 128 + the signal number.
"""

import math
import sys

from absl import app
from absl import flags
from absl import logging

from mixstereo_tf import mixtures
from mixstereo_tf import models
from mixstereo_tf import objective
from mixstereo_tf.data import pipeline
from mixstereo_tf.data import sources
from mixstereo_tf.training import config as config_lib
from mixstereo_tf.training import loop

FLAGS = flags.FLAGS

flags.DEFINE_string('model_dir', None, 'Checkpoints, summaries and saved flags go here.',
                    required=True)
flags.DEFINE_enum('mixture', 'anaglyph', mixtures.MIXTURE_NAMES, 'Composition operator f.')
flags.DEFINE_enum('dataset', 'sample', sources.DATASETS, 'Training data source.')
flags.DEFINE_string('data_dir', None, 'Dataset root (not needed for `sample`).')
flags.DEFINE_string('train_list', None, 'Split list of `left right` lines (kitti_raw).')
flags.DEFINE_boolean('skip_bad_pairs', False, 'Log and skip unreadable pairs.')
flags.DEFINE_list('middlebury_scale', [], 'Ground-truth disparity scale per Middlebury scene '
                  '(--dataset=middlebury) as scene:scale items, e.g. tsukuba:16,venus:8.')
flags.DEFINE_integer('crop_height', 256, 'Training crop height (paper: 256 KITTI, 384 '
                     'Middlebury); a multiple of 32.')
flags.DEFINE_integer('crop_width', 512, 'Training crop width (paper: 512 KITTI, 384 '
                     'Middlebury); a multiple of 32.')
flags.DEFINE_integer('batch_size', 1, 'Global batch size (paper: 1).')
flags.DEFINE_float('learning_rate', 1e-4, 'RMSProp learning rate (paper: 1e-4).')
flags.DEFINE_integer('num_steps', None, 'Total optimizer steps.')
flags.DEFINE_float('num_epochs', None, 'Epochs over the training list (instead of '
                   '--num_steps).')
flags.DEFINE_enum('mode', 'joint', objective.MODES, 'What to train.')
flags.DEFINE_string('init_checkpoint', None, 'Start from these weights (fine-tuning): a '
                    'checkpoint prefix or a run directory (its newest checkpoint).')
flags.DEFINE_enum('jit_compile', 'auto', config_lib.JIT_CHOICES,
                  'XLA for the forward/backward pass; auto = on GPU, off on CPU.')
flags.DEFINE_enum('strategy', 'default', config_lib.STRATEGIES, 'tf.distribute strategy.')
flags.DEFINE_boolean('mixed_precision', False, 'float16 (GPU) / bfloat16 (CPU) compute.')
flags.DEFINE_integer('seed', 0, 'Seed of initialisation and the input pipeline.')
flags.DEFINE_integer('checkpoint_every', 1000, 'Steps between checkpoints.')
flags.DEFINE_integer('summary_every', 100, 'Steps between scalar summaries.')
flags.DEFINE_integer('image_summary_every', 1000, 'Steps between image summaries.')
flags.DEFINE_integer('log_every', 10, 'Steps between progress lines.')
flags.DEFINE_boolean('augment', True, 'Photometric augmentation (monodepth).')
flags.DEFINE_boolean('flip', True, 'Random flip-and-swap of the views.')
# Architecture; the defaults are the paper's (17.1M parameters).
flags.DEFINE_integer('max_disparity', 96, 'Disparity levels at full resolution (paper: 96).')
flags.DEFINE_list('unet_widths', ['32', '64', '128', '256', '512', '512'],
                  'U-Net widths, full resolution first; one stride-2 level per extra entry.')
flags.DEFINE_integer('stereo_features', 32, 'Width of the 2D feature tower (GC-Net: 32).')
flags.DEFINE_integer('num_res_blocks', 8, 'Residual blocks of the 2D tower (GC-Net: 8).')
flags.DEFINE_list('volume_features', ['64', '64', '64', '128'],
                  'Widths of the 3D encoder levels (their number sets the depth); the '
                  'first 3D convolutions have --stereo_features.')
# Loss weights; the defaults are the paper's.
flags.DEFINE_float('alpha_c', 1.0, 'Content (L1) weight.')
flags.DEFINE_float('alpha_p', 0.2, 'Image prior (TV) weight.')
flags.DEFINE_float('omega_w', 1.0, 'Warp appearance weight.')
flags.DEFINE_float('omega_s', 0.05, 'Disparity smoothness weight.')
flags.DEFINE_float('lambda_ssim', 0.85, 'SSIM share of the appearance loss.')
flags.DEFINE_float('lambda_l1', 0.15, 'L1 share of the appearance loss.')
flags.DEFINE_enum('smoothness_scale', 'width', ('width', 'pixels'),
                  'Disparity units the smoothness term sees.')
# The embedded `sample` source.
flags.DEFINE_integer('sample_scenes', 2000, 'Procedural training scenes of `sample`.')
flags.DEFINE_integer('sample_height', None, 'Height of `sample` scenes (default: '
                     '--crop_height).')
flags.DEFINE_integer('sample_width', None, 'Width of `sample` scenes (default: --crop_width).')


def _ints(values, name):
  try:
    return tuple(int(v) for v in values)
  except ValueError:
    raise ValueError(f'--{name} must be a comma-separated list of integers, got '
                     f'{",".join(values)!r}.') from None


def build_configs():
  """Builds the frozen configs from the parsed flags (the only place FLAGS is read)."""
  data_config = sources.DataConfig(
      dataset=FLAGS.dataset, data_dir=FLAGS.data_dir, train_list=FLAGS.train_list,
      skip_bad_pairs=FLAGS.skip_bad_pairs, sample_scenes=FLAGS.sample_scenes,
      # `sample` scenes default to the crop size so that crops are not mostly padding.
      sample_height=FLAGS.sample_height or FLAGS.crop_height,
      sample_width=FLAGS.sample_width or FLAGS.crop_width,
      max_disparity=FLAGS.max_disparity,
      middlebury_scales=sources.parse_scene_scales(FLAGS.middlebury_scale))
  pipeline_config = pipeline.PipelineConfig(
      mixture=FLAGS.mixture, crop_height=FLAGS.crop_height, crop_width=FLAGS.crop_width,
      batch_size=FLAGS.batch_size, augment=FLAGS.augment, flip=FLAGS.flip, seed=FLAGS.seed,
      skip_bad_pairs=FLAGS.skip_bad_pairs)
  model_config = models.ModelConfig(
      separation_widths=_ints(FLAGS.unet_widths, 'unet_widths'),
      stereo_features=FLAGS.stereo_features, stereo_residual_blocks=FLAGS.num_res_blocks,
      stereo_3d_widths=_ints(FLAGS.volume_features, 'volume_features'),
      max_disparity=FLAGS.max_disparity)
  loss_config = objective.LossConfig(
      alpha_c=FLAGS.alpha_c, alpha_p=FLAGS.alpha_p, omega_w=FLAGS.omega_w,
      omega_s=FLAGS.omega_s, lambda_ssim=FLAGS.lambda_ssim, lambda_l1=FLAGS.lambda_l1,
      smoothness_scale=FLAGS.smoothness_scale)
  return data_config, pipeline_config, model_config, loss_config


def main(argv):
  del argv
  if (FLAGS.num_steps is None) == (FLAGS.num_epochs is None):
    raise app.UsageError('Give exactly one of --num_steps and --num_epochs.')
  try:
    data_config, pipeline_config, model_config, loss_config = build_configs()
    for name in ('crop_height', 'crop_width'):
      if getattr(FLAGS, name) % model_config.size_multiple:
        raise ValueError(f'--{name}={getattr(FLAGS, name)} must be a multiple of '
                         f'{model_config.size_multiple} for this architecture.')
    samples = sources.load_samples(data_config, split='train')
    num_steps = FLAGS.num_steps or math.ceil(
        FLAGS.num_epochs * len(samples) / FLAGS.batch_size)
    train_config = config_lib.TrainConfig(
        model_dir=FLAGS.model_dir, mode=FLAGS.mode, learning_rate=FLAGS.learning_rate,
        num_steps=num_steps, jit_compile=FLAGS.jit_compile, strategy=FLAGS.strategy,
        mixed_precision=FLAGS.mixed_precision, init_checkpoint=FLAGS.init_checkpoint,
        checkpoint_every=FLAGS.checkpoint_every, summary_every=FLAGS.summary_every,
        image_summary_every=FLAGS.image_summary_every, log_every=FLAGS.log_every,
        seed=FLAGS.seed)
  except ValueError as e:
    raise app.UsageError(str(e)) from None
  logging.info('Training on %d pairs from %s for %d steps.', len(samples), FLAGS.dataset,
               num_steps)
  try:
    result = loop.train(train_config, model_config, loss_config,
                        lambda: pipeline.train_dataset(samples, pipeline_config),
                        flags_text=FLAGS.flags_into_string(),
                        extra_configs={'data': data_config, 'pipeline': pipeline_config})
  except loop.NonFiniteLossError as e:
    logging.error('%s', e)
    sys.exit(f'error: {e}')
  if result.interrupted_by:
    sys.exit(128 + {'SIGINT': 2, 'SIGTERM': 15}[result.interrupted_by])


def run():
  """Console-script entry point (`mixstereo-train`)."""
  app.run(main)


if __name__ == '__main__':
  run()
