r"""Trains the joint separation + stereo network (or an ablation) from stereo pairs.

  python -m mixstereo_tf.train --flagfile=experiments/demo.flags --model_dir=runs/demo

Re-running with the same --model_dir resumes from its newest checkpoint. SIGINT/SIGTERM
save a checkpoint and exit with 128 + the signal number. Every default comes from the
config dataclasses (models.ModelConfig, objective.LossConfig, data.pipeline.PipelineConfig,
data.sources.DataConfig, training.config.TrainConfig): the paper's configuration.
"""

from mixstereo_tf.cli import startup  # pylint: disable=unused-import (first: quiet TF)

import math  # pylint: disable=g-bad-import-order
import re
import sys
from typing import Tuple

from absl import app
from absl import flags
from absl import logging
import tensorflow as tf

from mixstereo_tf import models
from mixstereo_tf.artifacts import runs
from mixstereo_tf.cli import device
from mixstereo_tf.cli import flag_errors
from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.cli import stage_training
from mixstereo_tf.data import pipeline
from mixstereo_tf.data import sources
from mixstereo_tf.training import config as config_lib
from mixstereo_tf.training import loop
from mixstereo_tf.training import objective
from mixstereo_tf.training import optimizers
from mixstereo_tf.unmixing import families

FLAGS = flags.FLAGS
_DATA = cli_flags.defaults(sources.DataConfig)
_PIPE = cli_flags.defaults(pipeline.PipelineConfig)
_TRAIN = cli_flags.defaults(config_lib.TrainConfig)
_MODEL = cli_flags.defaults(models.ModelConfig)
_LOSS = cli_flags.defaults(objective.LossConfig)

cli_flags.define_mixture()
cli_flags.define_data()
cli_flags.define_max_disparity()
flags.DEFINE_string('model_dir', None, 'Checkpoints, summaries and saved flags go here.',
                    required=True)
flags.DEFINE_enum('dataset', _DATA['dataset'], sources.DATASETS, 'Training data source.')
flags.DEFINE_string('train_list', _DATA['split_list'], 'Split list of `left right` lines '
                    '(kitti_raw), or of scene names (middlebury: only those are read).')
flags.DEFINE_boolean('fit_disparity', _DATA['fit_disparity'], 'middlebury: shrink a scene '
                     'deeper than --max_disparity by the smallest integer factor that fits '
                     '(block means; ground truth / factor) before cropping.')
flags.DEFINE_boolean('skip_bad_pairs', _DATA['skip_bad_pairs'], 'Log and skip unreadable pairs.')
flags.DEFINE_boolean('allow_evaluation_scenes', _DATA['allow_evaluation_scenes'],
                     "Train on the paper's evaluation scenes (Middlebury Tsukuba, Venus, "
                     'Sawtooth, Map, Cones, Teddy, Aloe, Motorcycle; the KITTI 2015 training '
                     'frames), which are refused otherwise.')
flags.DEFINE_integer('crop_height', _PIPE['crop_height'], 'Training crop height (paper: 256 '
                     'KITTI, 384 Middlebury); a multiple of the size multiple (32).')
flags.DEFINE_integer('crop_width', _PIPE['crop_width'], 'Training crop width (paper: 512 KITTI, '
                     '384 Middlebury); a multiple of the size multiple (32).')
flags.DEFINE_integer('batch_size', _PIPE['batch_size'], 'Global batch size (paper: 1).')
flags.DEFINE_float('learning_rate', _TRAIN['learning_rate'], 'RMSProp learning rate (paper: '
                   '1e-4).')
flags.DEFINE_enum('optimizer', _TRAIN['optimizer'], tuple(optimizers.OPTIMIZERS),
                  "rmsprop_tf1: the paper's TF1 RMSProp (accumulator from one, epsilon "
                  "1e-10); rmsprop_keras: Keras 3's RMSprop.")
flags.DEFINE_integer('num_steps', None, 'Total optimizer steps.', lower_bound=1)
flags.DEFINE_float('num_epochs', None, 'Epochs over the training list (instead of '
                   '--num_steps), > 0.')
flags.register_validator('num_epochs', lambda value: value is None or value > 0,
                         '--num_epochs must be positive.')
flags.DEFINE_enum('mode', _TRAIN['mode'], objective.MODES, 'What to train.')
flags.DEFINE_string('init_checkpoint', _TRAIN['init_checkpoint'], 'Start from these weights '
                    '(fine-tuning): a checkpoint prefix or a run directory.')
flags.DEFINE_enum('jit_compile', _TRAIN['jit_compile'], config_lib.JIT_CHOICES,
                  'XLA for the forward/backward pass; auto = on GPU, off on CPU.')
flags.DEFINE_enum('strategy', _TRAIN['strategy'], config_lib.STRATEGIES,
                  'tf.distribute strategy.')
flags.DEFINE_boolean('mixed_precision', _TRAIN['mixed_precision'],
                     'float16 compute with loss scaling (GPU) / bfloat16 (CPU); float32 '
                     'variables, soft-argmin and losses (not in the paper).')
flags.DEFINE_boolean('deterministic', _TRAIN['deterministic'],
                     'Op determinism: two runs of one flagfile on one machine give '
                     'identical weights (slower on a GPU).')
flags.DEFINE_integer('seed', _TRAIN['seed'], 'Seed of initialisation and the input pipeline.',
                     lower_bound=0, upper_bound=2**32 - 1)
flags.DEFINE_integer('checkpoint_every', _TRAIN['checkpoint_every'], 'Steps between checkpoints.')
flags.DEFINE_integer('summary_every', _TRAIN['summary_every'], 'Steps between scalar summaries.')
flags.DEFINE_integer('image_summary_every', _TRAIN['image_summary_every'],
                     'Steps between image summaries.')
flags.DEFINE_integer('log_every', _TRAIN['log_every'], 'Steps between progress lines.')
flags.DEFINE_boolean('augment', _PIPE['augment'], 'Photometric augmentation (monodepth).')
flags.DEFINE_boolean('flip', _PIPE['flip'], 'Random flip-and-swap of the views.')
# Architecture; the defaults are the paper's (17.1M parameters).
flags.DEFINE_list('unet_widths', [str(w) for w in _MODEL['separation_widths']],
                  'U-Net widths, full resolution first; one stride-2 level per extra entry.')
flags.DEFINE_integer('stereo_features', _MODEL['stereo_features'],
                     'Width of the 2D feature tower (GC-Net: 32).')
flags.DEFINE_integer('num_res_blocks', _MODEL['stereo_residual_blocks'],
                     'Residual blocks of the 2D tower (GC-Net: 8).')
flags.DEFINE_list('volume_features', [str(w) for w in _MODEL['stereo_3d_widths']],
                  'Widths of the 3D encoder levels (their number sets the depth); the '
                  'first 3D convolutions have --stereo_features.')
# Loss weights; the defaults are the paper's.
flags.DEFINE_float('alpha_c', _LOSS['alpha_c'], 'Content (L1) weight.')
flags.DEFINE_float('alpha_p', _LOSS['alpha_p'], 'Image prior (TV) weight.')
flags.DEFINE_float('omega_w', _LOSS['omega_w'], 'Warp appearance weight.')
flags.DEFINE_float('omega_s', _LOSS['omega_s'], 'Disparity smoothness weight.')
flags.DEFINE_float('lambda_ssim', _LOSS['lambda_ssim'], 'SSIM share of the appearance loss.')
flags.DEFINE_float('lambda_l1', _LOSS['lambda_l1'], 'L1 share of the appearance loss.')
flags.DEFINE_enum('smoothness_scale', _LOSS['smoothness_scale'], objective.SMOOTHNESS_SCALES,
                  'Disparity units the smoothness term sees.')
flags.DEFINE_float('omega_gt', _LOSS['omega_gt'], 'Weight of an L1 loss on ground-truth '
                   'disparity where the data has it (not in the paper: 0).')
flags.DEFINE_boolean('census_cost', _MODEL['census_cost'], 'Give the 3D network the census '
                     "matching cost of its views (the classical matcher's cost; not in the "
                     'paper).')
# The embedded `sample` source.
flags.DEFINE_integer('sample_scenes', _DATA['sample_scenes'],
                     'Procedural training scenes of `sample`.', lower_bound=1)
flags.DEFINE_integer('sample_height', None, 'Height of `sample` scenes (default: '
                     '--crop_height).')
flags.DEFINE_integer('sample_width', None, 'Width of `sample` scenes (default: --crop_width).')
flags.DEFINE_string('texture_dir', _DATA['texture_dir'], 'A folder of photographs texturing '
                    'the `sample` training scenes (default: scikit-image pictures).')
flags.DEFINE_boolean('realistic_scenes', _DATA['realistic_scenes'], '`sample` training '
                     'scenes with ground planes, thin poles and more layers.')
flags.DEFINE_boolean('degrade', _PIPE['degrade'], 'Degrade each mixture like a real file '
                     '(noise, blur, JPEG, vignetting, channel imbalance; not in the paper).')
flags.DEFINE_enum('architecture', 'joint', ('joint', *stage_training.TRAINERS), "joint: the "
                  "paper's network; refiner: the hybrid that refines the classical result "
                  '(models/refiner.py; trained on cached `sample` examples with ground truth, '
                  'from --sample_scenes, --sample_height/width, --max_disparity, --mixture, '
                  '--texture_dir, --degrade, --clean_probability, --large_probability, '
                  '--weighted_probability; not in the '
                  'paper); features: the learned matching features of anaglyphs, or with '
                  '--mixture=diplopia the echo features of double images '
                  '(models/matching_features.py; trained on photographs of --texture_dir warped '
                  'by drawn disparity fields, --crop_height x --crop_width, --max_disparity, '
                  '--mixture, --degrade, --feature_width, --feature_layers, --feature_dilations; '
                  'not in the paper).')
def build_configs():
  """Builds the frozen configs from the parsed flags (the only place FLAGS is read)."""
  data_config = sources.DataConfig(
      dataset=FLAGS.dataset, data_dir=FLAGS.data_dir, split_list=FLAGS.train_list,
      skip_bad_pairs=FLAGS.skip_bad_pairs, sample_scenes=FLAGS.sample_scenes,
      # `sample` scenes default to the crop size so that crops are not mostly padding.
      sample_height=FLAGS.sample_height or FLAGS.crop_height,
      sample_width=FLAGS.sample_width or FLAGS.crop_width,
      max_disparity=FLAGS.max_disparity, middlebury_scales=cli_flags.middlebury_scales(),
      allow_evaluation_scenes=FLAGS.allow_evaluation_scenes, texture_dir=FLAGS.texture_dir,
      realistic_scenes=FLAGS.realistic_scenes, fit_disparity=FLAGS.fit_disparity)
  pipeline_config = pipeline.PipelineConfig(
      mixture=FLAGS.mixture or _PIPE['mixture'], crop_height=FLAGS.crop_height,
      crop_width=FLAGS.crop_width, batch_size=FLAGS.batch_size, augment=FLAGS.augment,
      flip=FLAGS.flip, seed=FLAGS.seed, skip_bad_pairs=FLAGS.skip_bad_pairs,
      degrade=FLAGS.degrade)
  model_config = models.ModelConfig(
      separation_widths=stage_training.int_tuple(FLAGS.unet_widths, 'unet_widths'),
      stereo_features=FLAGS.stereo_features, stereo_residual_blocks=FLAGS.num_res_blocks,
      stereo_3d_widths=stage_training.int_tuple(FLAGS.volume_features, 'volume_features'),
      max_disparity=FLAGS.max_disparity, census_cost=FLAGS.census_cost,
      # Monocular depth (I = I_L): the input is the left view (paper section 3.1).
      input_is_left=families.input_is_left(pipeline_config.mixture))
  loss_config = objective.LossConfig(
      alpha_c=FLAGS.alpha_c, alpha_p=FLAGS.alpha_p, omega_w=FLAGS.omega_w,
      omega_s=FLAGS.omega_s, lambda_ssim=FLAGS.lambda_ssim, lambda_l1=FLAGS.lambda_l1,
      smoothness_scale=FLAGS.smoothness_scale, omega_gt=FLAGS.omega_gt)
  return data_config, pipeline_config, model_config, loss_config


def _train_config(num_steps: int) -> config_lib.TrainConfig:
  return config_lib.TrainConfig(
      model_dir=FLAGS.model_dir, mode=FLAGS.mode, learning_rate=FLAGS.learning_rate,
      optimizer=FLAGS.optimizer,
      num_steps=num_steps, jit_compile=FLAGS.jit_compile, strategy=FLAGS.strategy,
      mixed_precision=FLAGS.mixed_precision, deterministic=FLAGS.deterministic,
      init_checkpoint=FLAGS.init_checkpoint,
      checkpoint_every=FLAGS.checkpoint_every, summary_every=FLAGS.summary_every,
      image_summary_every=FLAGS.image_summary_every, log_every=FLAGS.log_every,
      seed=FLAGS.seed)


def _op_error_line(error: tf.errors.OpError) -> Tuple[str, bool]:
  """(the line of a TensorFlow error that says what failed, whether the input pipeline
  raised it): a Python error raised inside the pipeline names the list, line and file;
  else the first line naming an op (the model's own errors open with Keras' "Exception
  encountered when calling ..." and say what failed in a later line)."""
  lines = [line.split('[[')[0].strip() for line in error.message.splitlines()]
  inner = [line[line.index('ValueError: '):] for line in lines if 'ValueError: ' in line]
  if inner:
    return inner[-1], True
  lines = [line for line in lines if line and not line.startswith('Exception encountered')]
  named = [line for line in lines if '{{function_node' in line or '[Op:' in line]
  line = (named or lines or [type(error).__name__])[0]
  return re.sub(r'\x1b\[[0-9;]*m|\{\{function_node [^}]*\}\}\s*', '', line), False


def _one_training_length() -> None:
  """Exactly one of --num_steps and --num_epochs; one typed on the command line replaces the
  other read from a --flagfile (a short try of a recipe)."""
  names = ('num_steps', 'num_epochs')
  given = [name for name in names if getattr(FLAGS, name) is not None]
  if len(given) == 2:
    typed = flag_errors.typed_flags(sys.argv, names)
    if len(typed) != 1:
      raise app.UsageError('Give exactly one of --num_steps and --num_epochs (both given: '
                           f'--num_steps={FLAGS.num_steps}, --num_epochs={FLAGS.num_epochs}).')
    dropped = next(name for name in names if name not in typed)
    logging.info('--%s=%s on the command line replaces --%s=%s of the flagfile.', typed[0],
                 getattr(FLAGS, typed[0]), dropped, getattr(FLAGS, dropped))
    setattr(FLAGS, dropped, None)
  elif not given:
    raise app.UsageError('Give exactly one of --num_steps and --num_epochs.')


def main(argv):
  flag_errors.refuse_arguments(argv)
  device.log_line()
  if FLAGS.architecture in stage_training.TRAINERS:
    stage_training.TRAINERS[FLAGS.architecture]()
    return
  _one_training_length()
  try:
    data_config, pipeline_config, model_config, loss_config = build_configs()
    for name in ('crop_height', 'crop_width'):
      value = getattr(FLAGS, name)
      if value % model_config.size_multiple or value < model_config.smallest_input:
        raise ValueError(f'--{name}={value} must be a multiple of '
                         f'{model_config.size_multiple} for this architecture, at least '
                         f'{model_config.smallest_input}.')
    samples = sources.list_samples(data_config, split='train')
    num_steps = FLAGS.num_steps or max(1, math.ceil(
        FLAGS.num_epochs * len(samples) / FLAGS.batch_size))
    train_config = _train_config(num_steps)
  except ValueError as e:
    raise flag_errors.usage_error(e, stage_training.RENAMED) from None
  logging.info('Training on %d pairs from %s for %d steps.', len(samples), FLAGS.dataset,
               num_steps)
  try:
    result = loop.train(train_config, model_config, loss_config,
                        lambda start: pipeline.train_dataset(samples, pipeline_config, start),
                        flags_text=FLAGS.flags_into_string(),
                        extra_configs={'data': data_config, 'pipeline': pipeline_config})
  except runs.RunDirError as e:
    raise flag_errors.usage_error(e, stage_training.RENAMED) from None
  except loop.NonFiniteLossError as e:
    logging.error('%s', e)
    sys.exit(f'error: {e}')
  except tf.errors.OpError as e:  # E.g. a pair of the list that does not decode.
    line, from_data = _op_error_line(e)
    hint = '; --skip_bad_pairs drops pairs that fail to decode' if from_data else ''
    sys.exit(f'error: {line} (the newest checkpoint holds the last completed step: fix the '
             f'cause and run the same command to resume{hint})')
  if result.interrupted_by:
    sys.exit(128 + {'SIGINT': 2, 'SIGTERM': 15}[result.interrupted_by])


def run():
  """Console-script entry point (`mixstereo-train`)."""
  cli_flags.run_binary(main, __doc__)


if __name__ == '__main__':
  run()
