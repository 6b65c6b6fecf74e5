"""Training of the learned matching features (`models/matching_features.py`) on
photographs warped by drawn disparity fields (`data/photo_warps.py`), for anaglyphs (two
branches, one per eye) or for double images (`EchoFeatures`: the 'here' descriptor of the
mixture at x against the 'there' descriptor at x - d; the mixing weight a of
I = a L + (1 - a) R is drawn from `weight_range`, the warps keep positive disparities: no
window alignment).

Example (`draw_batch`): a warped pair, one encoding of `mixtures` drawn uniformly, mixed,
degraded like a real file with p = `degrade_probability` (`data/degrade.py`), quantised to
8 bits; the mixture's eye channels (`mixtures.MixtureSpec.eye_channels`) go to the 'single'
and 'pair' branches, whichever eye each carries; flipped upside down with p = 1/2 (keeps
the epipolar geometry).
Loss: `feature_loss.matching_loss`.
Every draw of step s comes from (seed, s), so a resumed run sees the batches an
uninterrupted one would. Checkpoints every `checkpoint_every` steps, on SIGINT/SIGTERM and
at the end; re-running the same command continues from the newest.
"""

import dataclasses
from typing import Callable, Dict, Sequence, Tuple

import numpy as np
import tensorflow as tf

from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.artifacts import runs
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import degrade
from mixstereo_tf.data import photo_warps
from mixstereo_tf.data import real_pairs
from mixstereo_tf.data import texture_atlas
from mixstereo_tf.models import matching_features
from mixstereo_tf.training import feature_loss
from mixstereo_tf.training import resumable

DIPLOPIA = 'diplopia'  # The double-image encoding (`mixtures`), trained alone.


def is_double(names: str) -> bool:
  """Whether `names` (`mixtures.parse_names` text) asks for the double-image features."""
  return mixtures.parse_names(names) == (DIPLOPIA,)


@dataclasses.dataclass(frozen=True)
class FeatureTrainConfig:
  """How the matching features are trained.

  Attributes:
    model_dir: checkpoints and config.json go here.
    texture_dir: a folder of photographs (None: scikit-image's training photographs).
    mixtures: encodings drawn from (`mixtures.parse_names` text): anaglyphs, or 'diplopia'
      alone (the echo features).
    batch_size: pairs per step.
    learning_rate: Adam step size.
    num_steps: optimizer steps to reach (a resumed run continues to this total).
    min_disparity, num_disparities: the candidates of the loss, signed pixels.
    logit_scale: cosine -> logit factor.
    degrade_probability: share of mixtures degraded like real files.
    weight_range: diplopia: the left eye's weight a, drawn uniformly from this range.
    real_pairs: real stereo pairs with ground truth (`data/real_pairs.load` sources) whose
      crops replace a warp with p = `real_probability` (0: the warps alone, drawn exactly
      as before the option existed).
    init_from: a shipped features model (`artifacts/pretrained` name) whose weights start
      a new run (fine-tuning); '' starts from random weights.
    checkpoint_every, log_every: steps between checkpoints / log lines.
    seed: seed of the initialisation and of every draw.
  """
  model_dir: str
  texture_dir: str = None
  mixtures: str = 'anaglyphs'
  batch_size: int = 4
  learning_rate: float = 1e-3
  num_steps: int = 4000
  min_disparity: int = -40
  num_disparities: int = 96
  logit_scale: float = 10.0
  degrade_probability: float = 0.7
  weight_range: tuple = (0.3, 0.7)
  real_pairs: tuple = ()
  real_probability: float = 0.0
  init_from: str = ''
  checkpoint_every: int = 250
  log_every: int = 50
  seed: int = 0

  def __post_init__(self):
    if not self.model_dir:
      raise ValueError('FeatureTrainConfig.model_dir is required.')
    names = mixtures.parse_names(self.mixtures)
    bad = [n for n in names if not mixtures.get_mixture(n).is_anaglyph]
    if bad and not is_double(self.mixtures):
      raise ValueError(f'FeatureTrainConfig.mixtures must be anaglyph encodings or '
                       f'{DIPLOPIA!r} alone; got {bad}.')
    low, high = self.weight_range
    if not 0.0 < low <= high < 1.0:
      raise ValueError(f'FeatureTrainConfig.weight_range needs 0 < low <= high < 1, got '
                       f'{self.weight_range}.')
    for field in ('batch_size', 'num_steps', 'num_disparities', 'checkpoint_every',
                  'log_every'):
      if getattr(self, field) <= 0:
        raise ValueError(f'FeatureTrainConfig.{field} must be positive, got '
                         f'{getattr(self, field)}.')
    if not 0.0 <= self.real_probability <= 1.0:
      raise ValueError(f'FeatureTrainConfig.real_probability must lie in [0, 1], got '
                       f'{self.real_probability}.')
    if self.real_probability > 0 and not self.real_pairs:
      raise ValueError('FeatureTrainConfig.real_probability > 0 needs '
                       'FeatureTrainConfig.real_pairs.')
    if not self.learning_rate > 0 or not self.logit_scale > 0:
      raise ValueError('FeatureTrainConfig.learning_rate and logit_scale must be positive.')


def candidates(max_disparity: int, names: str = 'anaglyphs'):
  """(min_disparity, num_disparities) of the loss for warps of `max_disparity`
  (`photo_warps.WarpConfig`) mixed by `names`: disparities lie in [1, 0.8 max] before window
  alignment, which moves them down by at most 0.7 of that span, so [-5/8 max, 7/8 max) holds
  them; double images are not window-aligned and search lags [1, max)."""
  if is_double(names):
    return 1, max_disparity - 1
  low = -(5 * max_disparity) // 8
  return low, (7 * max_disparity) // 8 - low


def window_probability(names: str) -> float:
  """The warps' chance of window alignment for `names`: none for double images, whose
  disparities are positive by convention (docs/DESIGN.md), else the WarpConfig default."""
  if is_double(names):
    return 0.0
  return photo_warps.WarpConfig.window_probability


def textures(config: FeatureTrainConfig) -> texture_atlas.TextureAtlas:
  """The photographs of the warps (long side at most 1024 px, blurred by sigma 1).

  Raises:
    ValueError: a file of the folder looks like an evaluation image.
  """
  if config.texture_dir:
    photo_warps.refuse_evaluation_photos(config.texture_dir)
    return texture_atlas.load_texture_dir(config.texture_dir, 1.0, 1024)
  return texture_atlas.load_textures('train')


def _mix(rng, config: FeatureTrainConfig, pair) -> Tuple[np.ndarray, str]:
  """A drawn encoding's mixture of the pair (diplopia: weight a from `weight_range`),
  degraded with p = `degrade_probability`, 8-bit: float32 [H, W, 3] in [0, 1]; the name."""
  names = mixtures.parse_names(config.mixtures)
  name = names[rng.integers(len(names))]
  left, right = (image_range.u8_to_signed(pair[k]) for k in ('left', 'right'))
  if name == DIPLOPIA:
    mixed = mixtures.mix_double(left, right, rng.uniform(*config.weight_range))
  else:
    mixed = mixtures.mix(name, left, right)
  mixed = image_range.signed_to_unit(mixed)
  if rng.uniform() < config.degrade_probability:
    mixed = degrade.degrade(mixed, tf.constant(rng.integers(2 ** 31, size=2), tf.int32))
  return image_range.unit_to_u8(np.asarray(mixed)).astype(np.float32) / 255.0, name


def _anaglyph_inputs(mixture: np.ndarray, name: str) -> Dict[str, np.ndarray]:
  single, pair, single_is_left = matching_features.eye_inputs(mixture, name)
  return {'single': single, 'pair': pair, 'single_is_left': single_is_left}


def _anaglyph_descriptors(model, batch):
  single, pair = model((batch['single'], batch['pair']), training=True)
  is_left = batch['single_is_left'][:, None, None, None]
  return tf.where(is_left, single, pair), tf.where(is_left, pair, single)


def _echo_descriptors(model, batch):
  return model(batch['mixture'], training=True)


@dataclasses.dataclass(frozen=True)
class Kind:
  """How one kind of features is built and fed.

  Attributes:
    build: FeatureConfig -> the model with its variables.
    inputs: (mixture float [H, W, 3], encoding name) -> the model inputs of one example.
    descriptors: (model, batch) -> (left, right) unit descriptors [B, H, W, C].
  """
  build: Callable[[matching_features.FeatureConfig], tf.keras.Model]
  inputs: Callable[[np.ndarray, str], Dict[str, np.ndarray]]
  descriptors: Callable


# The shipped model kinds (`artifacts/pretrained`) these features train.
KINDS = {
    'features': Kind(matching_features.build_features, _anaglyph_inputs,
                     _anaglyph_descriptors),
    'echo_features': Kind(matching_features.build_echo_features,
                          lambda mixture, name: {'mixture': mixture}, _echo_descriptors),
}


def kind_name(config: FeatureTrainConfig) -> str:
  """'echo_features' for double images, 'features' for anaglyphs."""
  return 'echo_features' if is_double(config.mixtures) else 'features'


def _pair(rng, config: FeatureTrainConfig, warp: photo_warps.WarpConfig, atlas, real):
  """A warp of a photograph, or with p = real_probability a crop of a real pair."""
  if config.real_probability > 0 and rng.uniform() < config.real_probability:
    return real_pairs.crop(rng, real[rng.integers(len(real))], warp.height, warp.width,
                           warp.max_disparity, warp.window_probability)
  return photo_warps.warped_pair(int(rng.integers(2 ** 31)), warp, atlas)


def _example(rng, config: FeatureTrainConfig, warp: photo_warps.WarpConfig, atlas, real):
  pair = _pair(rng, config, warp, atlas, real)
  mixture, name = _mix(rng, config, pair)
  example = KINDS[kind_name(config)].inputs(mixture, name)
  example.update(disparity=pair['disparity_left'], valid=pair['nonocc_left'])
  flip = slice(None, None, -1) if rng.uniform() < 0.5 else slice(None)
  return {k: v[flip] if np.ndim(v) >= 2 else v for k, v in example.items()}


def draw_batch(config: FeatureTrainConfig, warp: photo_warps.WarpConfig, atlas,
               step: int, real: Sequence[Dict[str, np.ndarray]] = ()
               ) -> Dict[str, np.ndarray]:
  """Step `step`'s batch: the kind's inputs (anaglyphs: single [B, H, W, 1], pair
  [B, H, W, 2], single_is_left [B]; diplopia: mixture [B, H, W, 3]), disparity [B, H, W]
  (signed pixels), valid [B, H, W]; `real`: the loaded `config.real_pairs`."""
  rng = np.random.default_rng([config.seed, step])
  rows = [_example(rng, config, warp, atlas, real) for _ in range(config.batch_size)]
  return {k: np.stack([r[k] for r in rows]) for k in rows[0]}


def start_from(model: tf.keras.Model, name: str, kind: str) -> None:
  """Sets `model`'s weights to those of shipped model `name`.

  Raises:
    ValueError: `name` is not a shipped model of `kind`, or its weights do not fit.
  """
  entry = pretrained.get(name)
  if entry.kind != kind:
    raise ValueError(f'--init_from={name} is a {entry.kind!r} model; this run trains '
                     f'{kind!r}.')
  values = pretrained.load_model(entry).get_weights()
  if [v.shape for v in values] != [tuple(w.shape) for w in model.weights]:
    raise ValueError(f'--init_from={name}: its architecture ({entry.config}) differs from '
                     'this run\'s feature flags.')
  model.set_weights(values)


def train(config: FeatureTrainConfig, warp: photo_warps.WarpConfig,
          feature_config: matching_features.FeatureConfig, flags_text: str = None) -> str:
  """Trains (resuming from `config.model_dir`) and returns the newest checkpoint prefix."""
  runs.write_run_files(config.model_dir, flags_text, train=config, warp=warp,
                       features=feature_config.to_dict())
  atlas = textures(config)
  tf.keras.utils.set_random_seed(config.seed)
  kind = KINDS[kind_name(config)]
  model = kind.build(feature_config)
  optimizer = tf.keras.optimizers.Adam(config.learning_rate)
  step, manager = resumable.checkpointed(model, optimizer, config.model_dir)
  if config.init_from and int(step) == 0:
    start_from(model, config.init_from, kind_name(config))
  real = [real_pairs.load(source) for source in config.real_pairs]

  @tf.function(reduce_retracing=True)
  def train_step(batch):
    with tf.GradientTape() as tape:
      left, right = kind.descriptors(model, batch)
      losses = feature_loss.matching_loss(
          left, right, batch['disparity'], batch['valid'], config.min_disparity,
          config.num_disparities, config.logit_scale)
    grads = tape.gradient(losses['loss'], model.trainable_variables)
    optimizer.apply_gradients(zip(grads, model.trainable_variables))
    return losses

  def one_step():
    losses = train_step(draw_batch(config, warp, atlas, int(step), real))
    step.assign_add(1)
    return [float(losses['loss']), float(losses['accuracy'])]

  resumable.run_steps(one_step, step, config.num_steps, manager, config.checkpoint_every,
                 config.log_every, 'loss %.4f  accuracy %.3f')
  return manager.latest_checkpoint
