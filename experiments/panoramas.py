"""Panoramas and strips: mixtures much wider than a frame, planned by frames or by width.

    python -m experiments.panoramas --photo_dir=photos/warps

A panorama, or a strip cut from a frame, is wider than a frame without larger disparities.
The planning copies (encoding detection, eye order, disparity ranges, a double image's
self-matching; `core/planning_copies.py`) are sized by the frame width, at most
WIDEST_ASPECT times the height, since 2026-11-29; before, by the whole width (a 3072 x 128
strip's 320-px copy was 13 px high). Both are run here: the second by setting
`planning_copies.WIDEST_ASPECT` so high that every image is one frame, which is exactly the
code before (the library reads the constant at each call).

Images, 5 : 1 to 24 : 1: strips of the real pairs at hand (Motorcycle rows 190-309 and
220-279, SceneFlow rows 300-399, their truth cut alike) and validation photo warps
(`validation.photo_pairs`' photographs and seeds, sizes `WARPS`, positive disparities up to
51 px). Each as a colour anaglyph (our operator) with `--mixture=auto`, and as a double
image (a = 1/2) with `--mixture=diplopia`: the default method and the classical one
through `mixstereo_tf.unmix`, scored on the truth's visible pixels (bad-1: |d - d*| > 1 px)
and by the views' RGB PSNR. Then encoding detection alone (`detection.detect`) on the real
strips and `--panorama_detections` more photo warps (sizes `WARPS` in turn, seeds
10^9 + 100 on), each mixed in every encoding of `ENCODINGS` (our operators): read right,
refused (no anaglyph, or too thin) or misread.
"""

import os
import sys
import time

from absl import app
from absl import flags
import numpy as np
from PIL import Image
import skimage.data

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
import mixstereo_tf
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.core import planning_copies
from mixstereo_tf.data import disparity_io
from mixstereo_tf.data import photo_warps
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.unmixing import detection

from experiments import markdown
from experiments import validation  # --photo_dir, the pairs.

flags.DEFINE_string('sceneflow_dir', '../shared/stereo_samples/sceneflow_A-0032-0006',
                    'The SceneFlow pair (left.png, right.png, disp_left.pfm, occ_left.png); '
                    "'' leaves its strip out.")
flags.DEFINE_integer('panorama_detections', 16, 'Photo warps of the detection table.')
flags.DEFINE_string('panoramas_output', 'experiments/results/panoramas.md', 'Markdown report.')
FLAGS = flags.FLAGS

WARPS = ((256, 2048), (192, 3072), (128, 3072), (320, 1600))
PLANS = {'by frame (shipped)': planning_copies.WIDEST_ASPECT, 'by width (before)': 1e9}
MIXTURES = ('auto', 'diplopia')
METHODS = ('model', 'classical')
ENCODINGS = ('anaglyph', 'half_color', 'gray', 'dubois_ffmpeg', 'green_magenta')


def _strip(pair: dict, top: int, rows: int) -> dict:
  return {key: value[top:top + rows] for key, value in pair.items()}


def images() -> dict:
  """{name: pair} ('left', 'right' uint8, 'disparity_left', 'nonocc_left')."""
  left, right, truth = skimage.data.stereo_motorcycle()
  known = np.isfinite(truth)
  moto = {'left': left, 'right': right, 'disparity_left': np.where(known, truth, 0.0),
          'nonocc_left': known}
  pairs = {'Motorcycle rows 190-309': _strip(moto, 190, 120),
           'Motorcycle rows 220-279': _strip(moto, 220, 60)}
  if FLAGS.sceneflow_dir:
    folder = FLAGS.sceneflow_dir
    truth, valid = disparity_io.read_disparity(os.path.join(folder, 'disp_left.pfm'))
    occluded = np.asarray(Image.open(os.path.join(folder, 'occ_left.png'))) > 0
    rgb = lambda name: np.asarray(Image.open(os.path.join(folder, name)).convert('RGB'))
    pairs['SceneFlow rows 300-399'] = _strip(
        {'left': rgb('left.png'), 'right': rgb('right.png'), 'disparity_left': truth,
         'nonocc_left': valid & ~occluded}, 300, 100)
  atlas = validation.required_atlas()
  for index, (height, width) in enumerate(WARPS):
    config = photo_warps.WarpConfig(height=height, width=width, max_disparity=64,
                                    window_probability=0.0)
    pairs[f'photo warp {width} x {height}'] = photo_warps.warped_pair(
        validation.PHOTO_SEED + index, config, atlas)
  return pairs


def _mixed(pair: dict, name: str) -> np.ndarray:
  mixed = mixtures.mix(name, image_range.u8_to_signed(pair['left']),
                       image_range.u8_to_signed(pair['right']))
  return image_range.signed_to_u8(mixed.numpy())


def score(pair: dict, mixture: str, method: str) -> str:
  """One cell: the mixture unmixed, or the error it raised."""
  mixed = _mixed(pair, 'anaglyph' if mixture == 'auto' else mixture)
  start = time.perf_counter()
  try:
    out = mixstereo_tf.unmix(mixed, mixture=mixture, method=method)
  except ValueError as e:
    return f'refused: {str(e).split(";")[0]}'
  seconds = time.perf_counter() - start
  error = np.abs(out.disparity - pair['disparity_left'])[pair['nonocc_left']]
  psnr = lambda key: metrics.psnr(getattr(out, key).astype(float), pair[key].astype(float))
  read = f'{out.info["mixture"]}, ' if mixture == 'auto' else ''
  low, high = out.info['disparity_range']
  return (f'{read}[{low}, {high}], {100 * np.mean(error > 1):.1f}%, {psnr("left"):.2f} / '
          f'{psnr("right"):.2f} dB, {seconds:.1f} s')


def detections(pairs: list) -> list:
  """Markdown rows: per encoding and plan, how `pairs`' mixtures were read."""
  lines = ['## Encoding detection', '',
           f'{len(pairs)} images (the real strips and photo warps): read right / refused / '
           'misread (as what).', '', '| encoding | ' + ' | '.join(PLANS) + ' |',
           '| --- |' + ' --- |' * len(PLANS)]
  for name in ENCODINGS:
    cells = []
    for widest in PLANS.values():
      planning_copies.WIDEST_ASPECT = widest
      read = []
      for pair in pairs:
        try:
          read.append(detection.detect(_mixed(pair, name)).name)
        except ValueError:
          read.append(None)
      wrong = [r for r in read if r not in (name, None)]
      cells.append(f'{read.count(name)} / {read.count(None)} / {len(wrong)}' +
                   (f' ({", ".join(sorted(set(wrong)))})' if wrong else ''))
    lines.append(f'| {name} | ' + ' | '.join(cells) + ' |')
  return lines + ['']


def more_warps(count: int) -> list:
  """The detection table's photo warps (module docstring)."""
  atlas = validation.required_atlas()
  return [photo_warps.warped_pair(validation.PHOTO_SEED + 100 + index, photo_warps.WarpConfig(
      height=WARPS[index % len(WARPS)][0], width=WARPS[index % len(WARPS)][1],
      max_disparity=64, window_probability=0.0), atlas) for index in range(count)]


def main(argv):
  del argv
  start = time.perf_counter()
  pairs = images()
  text = ['# Panoramas and strips: planned by frames or by width', '',
          f'Written by `python -m experiments.panoramas {" ".join(sys.argv[1:])}` in '
          f'{{seconds}} s on {os.cpu_count()} CPU cores (module docstring). Each cell: the '
          'encoding read (`--mixture=auto`), the disparity range searched, bad-1, the views\' '
          'PSNR (left / right), seconds.', '']
  first = next(iter(pairs.values()))
  for mixture in MIXTURES:
    for method in METHODS:
      score(first, mixture, method)  # Models loaded and compiled before anything is timed.
      text += [f'## --mixture={mixture}, --method={method}', '',
               '| image | ' + ' | '.join(PLANS) + ' |', '| --- |' + ' --- |' * len(PLANS)]
      for name, pair in pairs.items():
        cells = []
        for widest in PLANS.values():
          planning_copies.WIDEST_ASPECT = widest
          cells.append(score(pair, mixture, method))
        text.append(f'| {name} ({pair["left"].shape[1]} x {pair["left"].shape[0]}) | ' +
                    ' | '.join(cells) + ' |')
      text.append('')
  real = [pair for name, pair in pairs.items() if not name.startswith('photo')]
  text += detections(real + more_warps(FLAGS.panorama_detections))
  planning_copies.WIDEST_ASPECT = PLANS['by frame (shipped)']
  text[2] = text[2].replace('{seconds}', f'{time.perf_counter() - start:.0f}')
  markdown.write(FLAGS.panoramas_output, text)


if __name__ == '__main__':
  app.run(main)
