"""Large double images: self-matching at full size or on a reduced copy, on validation pairs.

    python -m experiments.large_diplopia --photo_dir=photos/warps

The choice of `DiplopiaConfig.max_width` (docs/LEARNED_DIPLOPIA.md "Large images"). For
each size, photo-warp double images (`validation.photo_pairs`, seeds 10^9 on, which
training never draws; the photographs of --photo_dir read 1200 px on their long side,
zoom 0.5-0.8, positive disparities up to 0.8 x `SIZES`' depth, about 6% of the width;
independent noise sigma 2 on each view, as a camera adds) go through `diplopia.unmix_diplopia` over
[1, true maximum + 3] with the self-matching reduced f times (max_width = ceil(W / f);
f = 1: max_width 0, never reduced) and the layers at full size. The 4000 x 3000 pairs
are the 2000 x 1500 renders enlarged twice (bicubic; truth nearest-sampled and doubled),
then noised: the atlas holds no photograph that large. Scores: bad-1 and bad-3 over the
visible pixels with a true disparity of at least 1 px, both views' RGB PSNR, seconds a
pair (one run on the machine at hand).
"""

import math
import os
import sys
import time

from absl import app
from absl import flags
import cv2
import numpy as np

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.classical import diplopia
from mixstereo_tf.data import photo_warps

from experiments import markdown
from experiments import validation  # --photo_dir, the pairs, their scores.

flags.DEFINE_integer('large_pairs', 3, 'Pairs per size.', lower_bound=1)
flags.DEFINE_string('large_output', 'experiments/results/large_diplopia.md',
                    'Markdown report.')
FLAGS = flags.FLAGS

# (height, width, WarpConfig.max_disparity, enlargement, reductions f): the rendered size
# and depth, how many times it is enlarged, and the self-matching reductions scored.
SIZES = ((720, 1280, 96, 1, (1, 2)), (1080, 1920, 144, 1, (1, 2)),
         (1500, 2000, 200, 1, (1, 2, 4)), (1500, 2000, 200, 2, (1, 2, 4, 8)))
ATLAS_LONG_SIDE = 1200


def _pair(pair, enlargement: int, seed: int):
  """The pair enlarged `enlargement` times, with independent noise on each view."""
  if enlargement > 1:
    height, width = pair['left'].shape[:2]
    size = (width * enlargement, height * enlargement)
    pair = {'left': cv2.resize(pair['left'], size, interpolation=cv2.INTER_CUBIC),
            'right': cv2.resize(pair['right'], size, interpolation=cv2.INTER_CUBIC),
            'disparity_left': cv2.resize(pair['disparity_left'], size,
                                         interpolation=cv2.INTER_NEAREST) * enlargement,
            'nonocc_left': cv2.resize(pair['nonocc_left'].astype(np.uint8), size,
                                      interpolation=cv2.INTER_NEAREST) > 0}
  return validation.noisy(pair, seed)


def evaluate(atlas, size, count: int):
  """{f: mean scores over `count` pairs} at one size of SIZES."""
  height, width, depth, enlargement, reductions = size
  config = photo_warps.WarpConfig(height=height, width=width, max_disparity=depth,
                                  window_probability=0.0, zoom_range=(0.5, 0.8))
  rows = {f: [] for f in reductions}
  for number, rendered in enumerate(validation.photo_pairs(config, count, atlas)):
    pair = _pair(rendered, enlargement, number)
    truth = pair['disparity_left']
    scored = pair['nonocc_left'] & (truth >= 1)
    image = np.round((pair['left'].astype(np.float32) + pair['right']) / 2).astype(np.uint8)
    for f in reductions:
      max_width = 0 if f == 1 else math.ceil(image.shape[1] / f)
      start = time.perf_counter()
      out = diplopia.unmix_diplopia(image, (1, int(np.ceil(truth.max())) + 3),
                                    diplopia.DiplopiaConfig(max_width=max_width))
      seconds = time.perf_counter() - start
      error = np.abs(out['disparity_left'] - truth)[scored]
      rows[f].append(dict(validation.scores(out['disparity_left'], pair, scored,
                                            out['left'], out['right']),
                          bad3=float(np.mean(error > 3.0)), seconds=seconds))
    print(f'{width * enlargement}x{height * enlargement}: pair {number + 1}/{count}',
          file=sys.stderr, flush=True)
  return {f: {key: float(np.mean([r[key] for r in rows[f]])) for key in rows[f][0]}
          for f in reductions}


def main(argv):
  del argv
  start = time.perf_counter()
  atlas = validation.required_atlas(long_side=ATLAS_LONG_SIDE)
  shipped = diplopia.DiplopiaConfig().max_width
  lines = ['| size | reduced f times (matched width) | bad-1 | bad-3 | views L / R (dB) | '
           'seconds a pair |', '| --- | --- | --- | --- | --- | --- |']
  for size in SIZES:
    height, width, _, enlargement, _ = size
    full = width * enlargement
    for f, mean in evaluate(atlas, size, FLAGS.large_pairs).items():
      mark = ' (shipped)' if f == max(1, math.ceil(full / shipped)) else ''
      lines.append(f"| {full} x {height * enlargement} | {f} ({math.ceil(full / f)} px)"
                   f"{mark} | {100 * mean['bad1']:.1f}% | {100 * mean['bad3']:.1f}% | "
                   f"{mean['psnr_left']:.2f} / {mean['psnr_right']:.2f} | "
                   f"{mean['seconds']:.1f} |")
  text = ['# Large double images: the self-matching reduced or not', '',
          f'Written by `python -m experiments.large_diplopia` in '
          f'{time.perf_counter() - start:.0f} s on {os.cpu_count()} CPU cores, '
          f'{FLAGS.large_pairs} validation pairs a size (module docstring); the shipped '
          f'`DiplopiaConfig.max_width` is {shipped}.', '', *lines, '']
  markdown.write(FLAGS.large_output, text)


if __name__ == '__main__':
  app.run(main)
