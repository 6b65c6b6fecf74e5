"""A prototype learned colourisation of the views (issue "Learned cross-channel matching",
item 3), measured, not shipped.

    python -m experiments.colouriser_prototype --photo_dir=photos/warps \
        --shared_dir=../shared/stereo_samples \
        [--colouriser_output=experiments/results/colouriser_prototype.md]

Data: `--colouriser_pairs` photo warps (`photo_warps.warped_pair`, seeds 2 x 10^9 on, which
neither the matching features' training nor validation draws; 192 x 384, depth range 96,
both signs), colour anaglyphs (FFmpeg for odd seeds, `mixtures` for even ones), the shipped
learned stage (`learned_matching.match` over the true range +- 3 px) and the shipped
restoration (`Family.restore`) on them. Per view, the network sees 10 channels: the
restored view, the other restored view warped by this view's disparity
(`views.sample_horizontal`), the mask of the channels the anaglyph copies for this eye, and
the left-right check; it outputs the view, the restored one plus a residual on the
channels the anaglyph does not copy (5 conv3x3 x 16, dilations 1-2-4-8-1, ReLU, a
zero-initialised 3-channel output: 8.5k parameters). Training: MSE to the true view, Adam
1e-3 (3e-4 after half the steps), batches of 8 random 128 x 256 crops, mirrored with
p = 0.5, both views of each pair. `--colouriser_degrade` degrades each view of a training
pair on its own before mixing, the targets as degraded (a real pair's cameras differ,
a warp's views do not): 'apart' blur (p = 0.5, sigma U[0.3, 0.9]) and noise (sigma
U[0, 4] grey levels); 'apart_camera' blur up to 1.0, noise up to 6, half the right views
shifted vertically by U[-0.5, 0.5] px (rectification) and half the views through an RGGB
mosaic and OpenCV's demosaicking. Rows: 'colouriser' the network's views, 'half' their
mean with the restored views (the choice made on validation warps, seeds 10^9 on, 256 x
512: the training photographs under new fields). Scenes: `same_channel.py`'s, colour
anaglyph; every camera unseen; the KITTI 2015 frame scored on its views alone.
"""

import os
import time

from absl import app
from absl import flags
import cv2
import numpy as np
import tensorflow as tf

from experiments import markdown
from experiments import same_channel  # Scenes, unmixers; also defines --shared_dir.
from experiments import validation  # --photo_dir and the validation warps.
from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import photo_warps
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.restoration import views
from mixstereo_tf.unmixing import families
from mixstereo_tf.unmixing import learned_matching

flags.DEFINE_integer('colouriser_pairs', 400, 'Training photo warps.')
flags.DEFINE_integer('colouriser_steps', 1200, 'Training steps.')
flags.DEFINE_enum('colouriser_degrade', 'none', ['none', 'apart', 'apart_camera'],
                  'Degrade the views of each training pair apart (module docstring).')
flags.DEFINE_string('colouriser_output', 'experiments/results/colouriser_prototype.md',
                    'Markdown report.')
FLAGS = flags.FLAGS

NAME = 'anaglyph'
TRAIN_SEED = 2 * 10 ** 9
WARP = photo_warps.WarpConfig(height=192, width=384, max_disparity=96)
VALIDATION = photo_warps.WarpConfig(height=256, width=512, max_disparity=96)
VALIDATION_PAIRS = 16


def features(own_u8, other_u8, disparity, consistent, side):
  """[H, W, 10] float32 inputs of one view (module docstring), values centred on 0."""
  spec = mixtures.get_mixture(NAME)
  copied = spec.left_channels if side == 'left' else spec.right_channels
  offset = -disparity if side == 'left' else disparity
  other = views.sample_horizontal(other_u8.astype(np.float32) / 255, offset)
  known = np.broadcast_to(np.array([c in copied for c in range(3)], np.float32),
                          disparity.shape + (3,))
  return np.concatenate([own_u8.astype(np.float32) / 255 - 0.5, other - 0.5, known,
                         consistent[..., None].astype(np.float32)], -1)


class Colouriser(tf.keras.Model):
  """The prototype network (module docstring): [B, H, W, 10] -> views [B, H, W, 3]."""

  def __init__(self, width=16, dilations=(1, 2, 4, 8, 1)):
    super().__init__()
    self.convs = [tf.keras.layers.Conv2D(width, 3, padding='same', dilation_rate=rate,
                                         activation='relu') for rate in dilations]
    self.head = tf.keras.layers.Conv2D(3, 3, padding='same', kernel_initializer='zeros')

  def call(self, inputs):
    hidden = inputs
    for conv in self.convs:
      hidden = conv(hidden)
    residual = self.head(hidden) * (1.0 - inputs[..., 6:9])
    return tf.clip_by_value(inputs[..., :3] + 0.5 + residual, 0.0, 1.0)


def stage_views(descriptors, pair, image):
  """(disparities, consistency, restored uint8 views) of the learned stage on `image`."""
  mixture = image.astype(np.float32) / 255
  low = int(np.floor(pair['disparity_left'].min())) - 3
  high = int(np.ceil(pair['disparity_left'].max())) + 3
  matched = learned_matching.match(descriptors, mixture, NAME, low, high)
  restored = families.of(NAME).restore(mixture, NAME, matched['disparity_left'],
                                       matched['disparity_right'])
  return ((matched['disparity_left'], matched['disparity_right']),
          (restored['consistent_left'], restored['consistent_right']),
          (image_range.unit_to_u8(restored['left']), image_range.unit_to_u8(restored['right'])))


def both_inputs(disparities, consistent, restored):
  """The left and right views' `features`."""
  return [features(restored[i], restored[1 - i], disparities[i], consistent[i], side)
          for i, side in enumerate(('left', 'right'))]


def demosaicked(view):
  """uint8 RGB [H, W, 3] (H, W even) through an RGGB mosaic and OpenCV's demosaicking."""
  mosaic = np.empty(view.shape[:2], np.uint8)
  mosaic[0::2, 0::2], mosaic[0::2, 1::2] = view[0::2, 0::2, 0], view[0::2, 1::2, 1]
  mosaic[1::2, 0::2], mosaic[1::2, 1::2] = view[1::2, 0::2, 1], view[1::2, 1::2, 2]
  return cv2.cvtColor(mosaic, cv2.COLOR_BayerBG2RGB)


def degraded_apart(pair, seed, camera):
  """`pair` with each view degraded on its own (`--colouriser_degrade`: 'apart', or with
  `camera` 'apart_camera')."""
  rng = np.random.default_rng(seed + (23 if camera else 17))
  out = dict(pair)
  for key in ('left', 'right'):
    view = pair[key].astype(np.float32)
    if camera and key == 'right' and rng.uniform() < 0.5:
      shift = np.float32([[1, 0, 0], [0, 1, rng.uniform(-0.5, 0.5)]])
      view = cv2.warpAffine(view, shift, view.shape[1::-1], flags=cv2.INTER_LINEAR,
                            borderMode=cv2.BORDER_REFLECT)
    if rng.uniform() < 0.5:
      view = cv2.GaussianBlur(view, (0, 0), rng.uniform(0.3, 1.0 if camera else 0.9))
    view = view + rng.normal(0, rng.uniform(0, 6 if camera else 4), view.shape)
    out[key] = np.clip(np.round(view), 0, 255).astype(np.uint8)
    if camera and rng.uniform() < 0.5:
      out[key] = demosaicked(out[key])
  return out


def training_set(descriptors, atlas):
  """(inputs [2N, H, W, 10], true views [2N, H, W, 3] in [0, 1]) of the training warps."""
  inputs, targets = [], []
  for seed in range(TRAIN_SEED, TRAIN_SEED + FLAGS.colouriser_pairs):
    pair = photo_warps.warped_pair(seed, WARP, atlas)
    if FLAGS.colouriser_degrade != 'none':
      pair = degraded_apart(pair, seed, FLAGS.colouriser_degrade == 'apart_camera')
    image = realworld.make_anaglyph(pair, NAME, 'ffmpeg' if seed % 2 else 'ours')
    inputs += both_inputs(*stage_views(descriptors, pair, image))
    targets += [pair['left'], pair['right']]
  return np.stack(inputs), np.stack(targets).astype(np.float32) / 255


def train(inputs, targets):
  """A `Colouriser` trained on `training_set`'s arrays (module docstring)."""
  model = Colouriser()
  optimizer = tf.keras.optimizers.Adam(1e-3)

  @tf.function
  def step(x, y):
    with tf.GradientTape() as tape:
      loss = tf.reduce_mean(tf.square(model(x) - y))
    optimizer.apply_gradients(zip(tape.gradient(loss, model.trainable_variables),
                                  model.trainable_variables))
    return loss

  rng = np.random.default_rng(0)
  for number in range(FLAGS.colouriser_steps):
    index = rng.integers(len(inputs), size=8)
    y0, x0 = rng.integers(0, inputs.shape[1] - 127), rng.integers(0, inputs.shape[2] - 255)
    x = inputs[index, y0:y0 + 128, x0:x0 + 256]
    y = targets[index, y0:y0 + 128, x0:x0 + 256]
    if rng.uniform() < 0.5:
      x, y = x[:, :, ::-1], y[:, :, ::-1]
    step(tf.constant(x), tf.constant(y))
    if number == FLAGS.colouriser_steps // 2:
      optimizer.learning_rate.assign(3e-4)
  return model


def variants(model, restored, inputs):
  """{row: (left, right) float views on the 0..255 scale}."""
  net = [model(x[None]).numpy()[0] * 255 for x in inputs]
  return {'learned': tuple(v.astype(np.float32) for v in restored),
          'colouriser': tuple(np.round(v) for v in net),
          'half': tuple(np.round((r + n) / 2) for r, n in zip(restored, net))}


def psnrs(views_, pair):
  """RGB PSNR (dB) of (left, right) views on the 0..255 scale against the pair's."""
  return np.array([metrics.psnr(np.clip(v, 0, 255), pair[s])
                   for v, s in zip(views_, ('left', 'right'))])


def evaluate(model, descriptors, atlas):
  """{group: {row: mean (L, R) dB}}: validation warps, then the evaluation scenes."""
  groups = {}
  for pair in validation.photo_pairs(VALIDATION, VALIDATION_PAIRS, atlas):
    image = realworld.make_anaglyph(pair, NAME, 'ffmpeg')
    disparities, consistent, restored = stage_views(descriptors, pair, image)
    rows = variants(model, restored, both_inputs(disparities, consistent, restored))
    groups.setdefault('validation warps', []).append(
        {k: psnrs(v, pair) for k, v in rows.items()})
  for scene, data in same_channel.scenes(FLAGS.shared_dir, views_only=True):
    pair = same_channel.without_estimated_truth(
        data, realworld.window_align(data, same_channel.FRACTION))
    image = realworld.make_anaglyph(pair, NAME, 'ffmpeg')
    classical = same_channel.unmixer(NAME, 'classical')(image)
    out = same_channel.unmixer(NAME, 'learned')(image)
    d = (out['disparity_left'], out['disparity_right'])
    consistent = views.lr_consistency(*d)
    rows = variants(model, (out['left'], out['right']),
                    both_inputs(d, consistent, (out['left'], out['right'])))
    row = {'classical': psnrs((classical['left'], classical['right']), pair)}
    row.update({k: psnrs(v, pair) for k, v in rows.items()})
    groups.setdefault(same_channel.group(scene), []).append(row)
  return {g: {k: np.mean([r[k] for r in rows], 0) for k in rows[0]}
          for g, rows in groups.items()}


def main(argv):
  del argv
  start = time.perf_counter()
  atlas = validation.required_atlas()
  descriptors = learned_matching.descriptor_function(
      pretrained.load_model(pretrained.get('anaglyph_matching')))
  tf.keras.utils.set_random_seed(0)
  model = train(*training_set(descriptors, atlas))
  means = evaluate(model, descriptors, atlas)
  lines = ['| scenes | row | views L / R (dB) | minus classical | minus learned |',
           '| --- ' * 5 + '|']
  for group, rows in means.items():
    for row, value in rows.items():
      minus = lambda k: (' / '.join(f'{x:+.2f}' for x in value - rows[k]) if k in rows  # pylint: disable=cell-var-from-loop
                         else '-')
      lines.append(f'| {group} | {row} | {value[0]:.2f} / {value[1]:.2f} | '
                   f"{minus('classical')} | {minus('learned')} |")
  text = ['# A prototype learned colouriser on the learned stage (colour anaglyph)', '',
          f'Written by `python -m experiments.colouriser_prototype --photo_dir='
          f'{FLAGS.photo_dir} --shared_dir={FLAGS.shared_dir} --colouriser_degrade='
          f'{FLAGS.colouriser_degrade}` in '
          f'{time.perf_counter() - start:.0f} s on {os.cpu_count()} CPU cores; '
          f'{FLAGS.colouriser_pairs} training pairs, {FLAGS.colouriser_steps} steps. '
          'See the module docstring. On 2026-11-28 each of its three '
          'settings gave the views of its scratch run to 0.01 dB on the same machine; '
          'scratch runs of the recipe on other draws of training pairs differed by up to '
          '0.16 dB a view (docs/LEARNED_MATCHING.md).', ''] + lines
  markdown.write(FLAGS.colouriser_output, text)


if __name__ == '__main__':
  app.run(main)
