"""The train tool's stages of the classical route (not in the paper): their flags and
trainers, by --architecture (`TRAINERS`): 'refiner', the hybrid refiner
(`training/refiner_loop.py`), and 'features', the learned matching / echo features
(`training/feature_loop.py`). `mixstereo_tf/train.py` defines the other flags and trains
the paper's joint network.
"""

import sys

from absl import app
from absl import flags
from absl import logging

from mixstereo_tf.artifacts import runs
from mixstereo_tf.cli import flag_errors
from mixstereo_tf.data import photo_warps
from mixstereo_tf.models import matching_features
from mixstereo_tf.models import refiner
from mixstereo_tf.training import feature_loop
from mixstereo_tf.training import refiner_data
from mixstereo_tf.training import refiner_loop
from mixstereo_tf.training import resumable

FLAGS = flags.FLAGS

flags.DEFINE_float('clean_probability', refiner_data.ExampleConfig.clean_probability,
                   'With --degrade, the share of refiner examples left clean (anaglyphs '
                   'made digitally from clean pairs; not in the paper).')
flags.DEFINE_float('large_probability', refiner_data.ExampleConfig.large_probability,
                   'The share of refiner examples cut from a scene twice as large and deep '
                   '(photo-sized disparities and occlusions; not in the paper).')
flags.DEFINE_float('weighted_probability', refiner_data.ExampleConfig.weighted_probability,
                   'The share of double-image refiner examples mixed as a L + (1 - a) R with '
                   'a drawn from [0.3, 0.7] and estimated by their classical stage '
                   '(--mixing_weight=auto; not in the paper).')
flags.DEFINE_integer('refiner_disparity_features', refiner.RefinerConfig.disparity_features,
                     '--architecture=refiner: width of the disparity refinement network (its '
                     'cost grows with the square; not in the paper).')
flags.DEFINE_string('refiner_base', refiner_data.ExampleConfig.base, '--architecture=refiner: '
                    'the shipped stage (a --pretrained name, e.g. anaglyph_matching) the '
                    'refiner is trained on and runs on, instead of the classical method (not '
                    'in the paper).')
flags.DEFINE_integer('feature_width', matching_features.FeatureConfig.width,
                     '--architecture=features: descriptor length (channels per convolution).')
flags.DEFINE_boolean('photo_warps', photo_warps.WarpConfig.photo_warps,
                     '--architecture=features: each pair is one photograph warped by a drawn '
                     'disparity field (data/photo_warps.py); --nophoto_warps: procedural '
                     'scenes textured from the same photographs (the ablation).')
flags.DEFINE_integer('feature_layers', matching_features.FeatureConfig.layers,
                     '--architecture=features: 3x3 convolutions per eye branch.')
flags.DEFINE_list('feature_dilations', list(matching_features.FeatureConfig.dilations),
                  '--architecture=features: the dilation of each of the --feature_layers '
                  'convolutions (comma-separated); empty: all 1.')
flags.DEFINE_list('real_pairs', list(feature_loop.FeatureTrainConfig.real_pairs),
                  '--architecture=features: real stereo pairs with ground truth trained on '
                  'beside the warps (data/real_pairs.py: motorcycle, or folders of the '
                  'SceneFlow or KITTI object layout); never an evaluation scene.')
flags.DEFINE_float('real_pair_probability', feature_loop.FeatureTrainConfig.real_probability,
                   '--architecture=features: the share of examples cut from --real_pairs.')
flags.DEFINE_string('init_from', feature_loop.FeatureTrainConfig.init_from,
                    '--architecture=features: a shipped features model (--pretrained name) '
                    'whose weights start the run (fine-tuning).')


# Config fields behind differently named flags (of this module and of train.py).
RENAMED = {'DataConfig.split_list': 'train_list', 'ExampleConfig.base': 'refiner_base',
           'FeatureTrainConfig.real_probability': 'real_pair_probability',
           'RefinerConfig.disparity_features': 'refiner_disparity_features'}


def int_tuple(values, name: str):
  """A flag's list of strings as a tuple of ints, or ValueError naming --`name`."""
  try:
    return tuple(int(v) for v in values)
  except ValueError:
    raise ValueError(f'--{name} must be a comma-separated list of integers, got '
                     f'{",".join(values)!r}.') from None


def train_refiner() -> None:
  """--architecture=refiner: `training/refiner_loop.py` on the flags it reads."""
  if FLAGS.num_steps is None:
    raise app.UsageError('--architecture=refiner needs --num_steps.')
  try:
    shard_size = refiner_loop.RefinerTrainConfig.shard_size
    examples = refiner_data.ExampleConfig(
        mixtures=FLAGS.mixture or 'anaglyphs', height=FLAGS.sample_height or FLAGS.crop_height,
        width=FLAGS.sample_width or FLAGS.crop_width, max_disparity=FLAGS.max_disparity,
        degrade=FLAGS.degrade, clean_probability=FLAGS.clean_probability,
        large_probability=FLAGS.large_probability,
        weighted_probability=FLAGS.weighted_probability, texture_dir=FLAGS.texture_dir,
        base=FLAGS.refiner_base)
    config = refiner_loop.RefinerTrainConfig(
        model_dir=FLAGS.model_dir, num_shards=-(-FLAGS.sample_scenes // shard_size),
        crop_height=FLAGS.crop_height, crop_width=FLAGS.crop_width,
        batch_size=FLAGS.batch_size, learning_rate=FLAGS.learning_rate,
        num_steps=FLAGS.num_steps, checkpoint_every=FLAGS.checkpoint_every,
        log_every=FLAGS.log_every, seed=FLAGS.seed)
    architecture = refiner.RefinerConfig(disparity_features=FLAGS.refiner_disparity_features)
  except ValueError as e:
    raise flag_errors.usage_error(e, RENAMED) from None
  logging.info('Training the refiner on %d examples for %d steps.',
               config.num_shards * shard_size, config.num_steps)
  try:
    refiner_loop.train(config, examples, architecture, FLAGS.flags_into_string())
  except runs.RunDirError as e:
    raise flag_errors.usage_error(e, RENAMED) from None
  except resumable.Interrupted as e:
    logging.warning('%s', e)
    sys.exit(e.exit_code)


def train_features() -> None:
  """--architecture=features: `training/feature_loop.py` on the flags it reads."""
  if FLAGS.num_steps is None:
    raise app.UsageError('--architecture=features needs --num_steps.')
  names = FLAGS.mixture or 'anaglyphs'
  try:
    warp = photo_warps.WarpConfig(
        height=FLAGS.crop_height, width=FLAGS.crop_width, max_disparity=FLAGS.max_disparity,
        window_probability=feature_loop.window_probability(names),
        photo_warps=FLAGS.photo_warps)
    low, count = feature_loop.candidates(FLAGS.max_disparity, names)
    config = feature_loop.FeatureTrainConfig(
        model_dir=FLAGS.model_dir, texture_dir=FLAGS.texture_dir, mixtures=names,
        batch_size=FLAGS.batch_size,
        learning_rate=FLAGS.learning_rate, num_steps=FLAGS.num_steps, min_disparity=low,
        num_disparities=count, degrade_probability=0.7 if FLAGS.degrade else 0.0,
        real_pairs=tuple(FLAGS.real_pairs), real_probability=FLAGS.real_pair_probability,
        init_from=FLAGS.init_from, checkpoint_every=FLAGS.checkpoint_every,
        log_every=FLAGS.log_every, seed=FLAGS.seed)
    features = matching_features.FeatureConfig(
        FLAGS.feature_width, FLAGS.feature_layers,
        int_tuple(FLAGS.feature_dilations, 'feature_dilations'))
  except ValueError as e:
    raise flag_errors.usage_error(e, RENAMED) from None
  logging.info('Training the matching features for %d steps.', config.num_steps)
  try:
    feature_loop.train(config, warp, features, FLAGS.flags_into_string())
  except runs.RunDirError as e:
    raise flag_errors.usage_error(e, RENAMED) from None
  except resumable.Interrupted as e:
    logging.warning('%s', e)
    sys.exit(e.exit_code)


# --architecture -> its trainer (the joint network is train.py's own).
TRAINERS = {'refiner': train_refiner, 'features': train_features}
