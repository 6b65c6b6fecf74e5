"""The borrowed channels' finest detail scaled by the camera's shared share (issue "Learned
cross-channel matching", item 3; `restoration/borrowed_detail.py`): chosen on validation
photo warps, then read on the evaluation frames.

    python -m experiments.borrowed_detail --photo_dir=photos/warps \
        [--shared_dir=../shared/stereo_samples] \
        [--borrowed_output=experiments/results/borrowed_detail.md]

Part 1, the choice: 16 validation photo warps (the training photographs under new drawn
disparity fields, seeds 10^9 on, 256 x 512), each as rendered ('clean': both views share
the photograph's own noise, as no camera pair does), with each view degraded on its own
('apart': blur and noise; 'camera': also a vertical offset and a Bayer mosaic;
`colouriser_prototype.degraded_apart`), made into FFmpeg colour anaglyphs, kept lossless
or stored as quality-90 4:2:0 JPEG. The classical method matches each once; its
disparities are restored with `RestoreConfig.borrowed_detail_sigma` 0 (off) and each
candidate. Part 2, read after: the scenes and window alignment of `same_channel.md`, the
encodings scaled (colour and amber-blue: `borrowed_detail.own_pair`; green-magenta's red
and blue are not), the classical method and the learned stage (the default), off against
the shipped sigma.
Reported: mean RGB PSNR gain of both views (L / R) and the worst image's, and k.
"""

import dataclasses
import os
import time

from absl import app
from absl import flags
import cv2
import numpy as np

from mixstereo_tf.core import mixtures
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.restoration import borrowed_detail
from mixstereo_tf.restoration import views
from mixstereo_tf.data import photo_warps
from mixstereo_tf.unmixing import predictors
from experiments import colouriser_prototype
from experiments import markdown
from experiments import same_channel  # Also defines --shared_dir.
from experiments import validation  # --photo_dir.

flags.DEFINE_string('borrowed_output', 'experiments/results/borrowed_detail.md',
                    'Markdown report.')
FLAGS = flags.FLAGS

SHIPPED = views.RestoreConfig().borrowed_detail_sigma
CANDIDATES = (0.7, 1.0, 1.4)
CONDITIONS = ('clean', 'apart', 'camera')
STORAGES = ('png', 'jpeg')
PAIRS = 16
WARP = photo_warps.WarpConfig(height=256, width=512, max_disparity=96)
ENCODINGS = ('anaglyph', 'amber_blue')


def _config(sigma):
  return dataclasses.replace(views.RestoreConfig(), borrowed_detail_sigma=sigma)


def _gains(image, name, out, pair, sigmas):
  """{sigma: (gain L, gain R) in dB over sigma 0} of `out`'s disparities restored."""
  psnrs = {}
  for sigma in (0.0,) + tuple(sigmas):
    restored = views.restore_views(image.astype(np.float32) / 255.0, name,
                                   out['disparity_left'], out['disparity_right'],
                                   config=_config(sigma))
    psnrs[sigma] = np.array([metrics.psnr(np.rint(restored[k] * 255.0),
                                          pair[k].astype(np.float64))
                             for k in ('left', 'right')])
  return {sigma: psnrs[sigma] - psnrs[0.0] for sigma in sigmas}


def _share(image, name, sigma=SHIPPED):
  spec = mixtures.get_mixture(name)
  return borrowed_detail.shared_share(image.astype(np.float32) / 255.0,
                                      borrowed_detail.own_pair(spec), sigma)


def _stored(image, storage):
  if storage == 'png':
    return image
  _, data = cv2.imencode('.jpg', image[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, 90])
  return cv2.imdecode(data, cv2.IMREAD_COLOR)[..., ::-1]


def validation_rows(atlas):
  """(condition, storage, k, {sigma: gains}) of every validation image (part 1)."""
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(mixture='anaglyph',
                                                                method='classical'))
  for number, pair in enumerate(validation.photo_pairs(WARP, PAIRS, atlas)):
    seed = validation.PHOTO_SEED + number
    for condition in CONDITIONS:
      degraded = pair if condition == 'clean' else colouriser_prototype.degraded_apart(
          pair, seed, condition == 'camera')
      for storage in STORAGES:
        image = _stored(realworld.make_anaglyph(degraded, 'anaglyph', 'ffmpeg'), storage)
        yield (condition, storage, _share(image, 'anaglyph'),
               _gains(image, 'anaglyph', unmixer(image), degraded, CANDIDATES))


def evaluation_rows(shared_dir):
  """(group, encoding, method, k, {SHIPPED: gains}) of every evaluation run (part 2)."""
  for group, _, pair in same_channel.pairs(shared_dir, views_only=True):
    for name in ENCODINGS:
      image = realworld.make_anaglyph(pair, name, 'ffmpeg')
      for method in ('classical', 'learned'):
        out = same_channel.unmixer(name, method)(image)
        yield group, name, method, _share(image, name), _gains(image, name, out, pair,
                                                               (SHIPPED,))


def _cell(gains):
  gains = np.array(gains)
  return (f'{gains[:, 0].mean():+.3f} / {gains[:, 1].mean():+.3f} '
          f'(worst {gains[:, 0].min():+.2f} / {gains[:, 1].min():+.2f})')


def validation_table(rows):
  """Markdown lines of part 1: per condition and storage, mean k and each candidate."""
  lines = ['| views | stored | k (mean, range) | ' + ' | '.join(
      f'sigma {s:g}: gain L / R (dB)' for s in CANDIDATES) + ' |',
           '| --- ' * (3 + len(CANDIDATES)) + '|']
  for condition in CONDITIONS:
    for storage in STORAGES:
      these = [r for r in rows if r[:2] == (condition, storage)]
      ks = [r[2] for r in these]
      lines.append(f'| {condition} | {storage} | {np.mean(ks):.2f} ({min(ks):.2f}-'
                   f'{max(ks):.2f}) | ' + ' | '.join(_cell([r[3][s] for r in these])
                                                      for s in CANDIDATES) + ' |')
  lines.append('| all | | | ' + ' | '.join(_cell([r[3][s] for r in rows])
                                           for s in CANDIDATES) + ' |')
  return lines


def evaluation_table(rows):
  """Markdown lines of part 2: per scene group, encoding and method."""
  lines = ['| scenes | encoding | method | k | gain L / R (dB) |', '| --- ' * 5 + '|']
  for key in dict.fromkeys(r[:3] for r in rows):
    these = [r for r in rows if r[:3] == key]
    lines.append(f'| {" | ".join(key)} | {np.mean([r[3] for r in these]):.2f} | '
                 f'{_cell([r[4][SHIPPED] for r in these])} |')
  return lines


def main(argv):
  del argv
  start = time.perf_counter()
  chosen = validation_table(list(validation_rows(validation.required_atlas())))
  read = evaluation_table(list(evaluation_rows(FLAGS.shared_dir)))
  command = (f'python -m experiments.borrowed_detail --photo_dir={FLAGS.photo_dir}' +
             (f' --shared_dir={FLAGS.shared_dir}' if FLAGS.shared_dir else ''))
  text = ["# The borrowed channels' finest detail, scaled", '',
          f'Written by `{command}` in {time.perf_counter() - start:.0f} s on '
          f'{os.cpu_count()} CPU cores (module docstring). Gains: RGB PSNR of the uint8 '
          'views over the same disparities restored with the scaling off '
          "(`borrowed_detail_sigma=0`); k: the correlation of the mixture's two channels "
          "of one eye in the finest band over that in a reference band, the share of that "
          f'band that is scene (`borrowed_detail.shared_share`, sigma {SHIPPED:g}).', '',
          f'## The choice ({PAIRS} validation photo warps, classical disparities, colour '
          'anaglyphs)', '', *chosen, '',
          f'## Read after: the evaluation frames, sigma {SHIPPED:g} (the shipped value)', '',
          *read, '']
  markdown.write(FLAGS.borrowed_output, text)


if __name__ == '__main__':
  app.run(main)
