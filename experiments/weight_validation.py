"""The mixing weight's estimate (`--mixing_weight=auto`) judged on validation double images.

    python -m experiments.weight_validation --photo_dir=photos/warps

Validation pairs: the photographs of `--photo_dir` (experiments/get_photos.sh; those the
learned stages train on, never an evaluation scene) under drawn disparity fields
(`photo_warps.warped_pair`, seeds 10^9 on, which training never draws; 256 x 512, depth
range 96, positive disparities), each also reduced to 320 px wide (INTER_AREA): fewer
echoes, as in a small image. Mixed as I = a L + (1 - a) R for a in WEIGHTS, rounded to 8
bits. Per image the classical self-matching (`diplopia.unmix_diplopia`, a = 1/2) gives the
disparities and their left-right check (`views.lr_consistency`, 1 px); from the same echo
histogram (`diplopia_weight.echo_histogram`) the shipped estimate (`echo_peak`) and the
histogram's mode (Gaussian-smoothed by 3 bins: the estimate before 2026-11-29), and the
layers solved with each and with the true a (`diplopia_layers.separate_layers`): mean
absolute error of a and the views' RGB PSNR (mean of both eyes).
"""

import os
import sys
import time

from absl import app
from absl import flags
import cv2
import numpy as np

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import diplopia_layers
from mixstereo_tf.classical import diplopia_weight
from mixstereo_tf.core import image_range
from mixstereo_tf.data import photo_warps
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.restoration import views

from experiments import markdown
from experiments import validation  # --photo_dir, the pairs.

flags.DEFINE_integer('weight_pairs', 16, 'Warped photo pairs.')
flags.DEFINE_string('weight_validation_output', 'experiments/results/weight_validation.md',
                    'Markdown report.')
FLAGS = flags.FLAGS

WARP = photo_warps.WarpConfig(height=256, width=512, max_disparity=96, window_probability=0.0)
WEIGHTS = (0.3, 0.4, 0.5, 0.6, 0.7)
WIDTHS = (512, 320)
ESTIMATES = ('mode (before)', 'fitted peak (shipped)', 'true a')


def histogram_mode(counts: np.ndarray) -> float:
  """The estimate before 2026-11-29: the mode of the echo histogram smoothed by 3 bins."""
  kernel = np.exp(-0.5 * (np.arange(-8, 9) / 3.0) ** 2)
  return float(diplopia_weight.RATIO_BINS[np.argmax(np.convolve(counts, kernel, 'same'))])


def _reduced(image: np.ndarray, width: int) -> np.ndarray:
  if image.shape[1] <= width:
    return image
  height = round(image.shape[0] * width / image.shape[1])
  return cv2.resize(image, (width, height), interpolation=cv2.INTER_AREA)


def score(left: np.ndarray, right: np.ndarray, weight: float) -> dict:
  """{estimate name: (a, views' mean RGB PSNR)} of the double image of (left, right)."""
  mixed = np.clip(np.rint(weight * left.astype(np.float64) + (1 - weight) * right), 0, 255)
  image01 = image_range.to_unit(mixed.astype(np.uint8))
  out = diplopia.unmix_diplopia(mixed.astype(np.uint8))
  consistent = views.lr_consistency(out['disparity_left'], out['disparity_right'])[0]
  counts = diplopia_weight.echo_histogram(image01, out['disparity_left'], consistent)
  found = {ESTIMATES[0]: 0.5 if counts is None else histogram_mode(counts),
           ESTIMATES[1]: 0.5 if counts is None else diplopia_weight.echo_peak(counts),
           ESTIMATES[2]: weight}
  scores = {}
  for name, estimate in found.items():
    layers = diplopia_layers.separate_layers(image01, out['disparity_right'], weight=estimate)
    psnr = [metrics.psnr(image_range.unit_to(layers[key], np.uint8), view)
            for key, view in (('left', left), ('right', right))]
    scores[name] = (estimate, float(np.mean(psnr)))
  return scores


def evaluate(atlas, count: int) -> dict:
  """{(width, a, estimate name): [(a found, views PSNR) per pair]}."""
  rows = {}
  for index, pair in enumerate(validation.photo_pairs(WARP, count, atlas)):
    for width in WIDTHS:
      left, right = (_reduced(pair[key], width) for key in ('left', 'right'))
      for weight in WEIGHTS:
        for name, value in score(left, right, weight).items():
          rows.setdefault((width, weight, name), []).append(value)
    print(f'pair {index + 1} of {count}', file=sys.stderr, flush=True)
  return rows


def table(rows: dict, width: int) -> list:
  """Markdown rows of one width: per estimate, mean |error| of a and views per a, then all."""
  lines = [f'### {width} px wide', '',
           '| estimate | ' + ' | '.join(f'a = {w}' for w in WEIGHTS) + ' | all |',
           '| --- |' + ' --- |' * (len(WEIGHTS) + 1)]
  for name in ESTIMATES:
    cells, errors, psnrs = [], [], []
    for weight in WEIGHTS:
      found = np.array(rows[(width, weight, name)])
      error, psnr = np.abs(found[:, 0] - weight), found[:, 1]
      errors.append(error.mean())
      psnrs.append(psnr.mean())
      cells.append(f'{error.mean():.3f} (max {error.max():.2f}), {psnr.mean():.2f} dB')
    lines.append(f'| {name} | ' + ' | '.join(cells) +
                 f' | {np.mean(errors):.4f}, {np.mean(psnrs):.2f} dB |')
  return lines + ['']


def main(argv):
  del argv
  start = time.perf_counter()
  rows = evaluate(validation.required_atlas(), FLAGS.weight_pairs)
  text = ['# The mixing weight estimate on validation double images', '',
          f'Written by `python -m experiments.weight_validation {" ".join(sys.argv[1:])}` '
          f'in {time.perf_counter() - start:.0f} s on {os.cpu_count()} CPU cores (module '
          f'docstring). {FLAGS.weight_pairs} photo-warp pairs; each cell: mean absolute error '
          'of a (the largest), the views\' mean RGB PSNR with that a.', '']
  for width in WIDTHS:
    text += table(rows, width)
  markdown.write(FLAGS.weight_validation_output, text)


if __name__ == '__main__':
  app.run(main)
