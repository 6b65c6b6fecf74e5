"""The learned matching stage's range planning against the census matcher's, on validation
pairs (the choice of `learned_matching.estimate_range`, docs/LEARNED_MATCHING.md).

    python -m experiments.range_validation --photo_dir=photos/warps

Validation pairs as experiments/matching_validation.py (the training photographs under new
drawn disparity fields, seeds 10^9 on, 256 x 512, both signs), each made by FFmpeg into the
colour, half-colour, Dubois, green-magenta half-colour and amber-blue Dubois anaglyphs. Per
encoding and planner (census: `Family.estimate_range`; learned (shipped): the learned
stage's own, `learned_matching.estimate_range`; both: their intersection): the
share of true left disparities inside the planned range (coverage), the range's width
over the true 0.5-99.5 percentile width (mean and largest), and the shipped learned stage
run over that range (`learned_matching.learned_unmix`): bad-1 over the visible left pixels
and the views' RGB PSNR.
"""

import sys
import time

from absl import app
from absl import flags
import numpy as np

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.unmixing import families
from mixstereo_tf.unmixing import learned_matching

from experiments import markdown
from experiments import matching_validation
from experiments import validation  # --photo_dir, the pairs.

flags.DEFINE_integer('range_pairs', 12, 'Warped photo pairs (each in every encoding).')
flags.DEFINE_string('range_output', 'experiments/results/range_validation.md',
                    'Markdown report.')
FLAGS = flags.FLAGS

# The learned plan intersected with the census plan's (`intersect_census_range`).
INTERSECTED = learned_matching.LearnedMatchConfig(intersect_census_range=True)
ENCODINGS = ('anaglyph', 'half_color', 'dubois_ffmpeg', 'green_magenta_half',
             'amber_blue_dubois')


def _assess(pair, image, name, planned, descriptors) -> tuple:
  """(coverage, width ratio, bad-1, PSNR L, PSNR R) of range `planned` for `pair`."""
  truth = pair['disparity_left'].ravel()  # Exact at every left pixel.
  inside = np.mean((truth >= planned[0]) & (truth <= planned[1]))
  width = np.percentile(truth, 99.5) - np.percentile(truth, 0.5)
  out = learned_matching.learned_unmix(descriptors, image, name, planned)
  scores = validation.scores(out['disparity_left'], pair, pair['nonocc_left'],
                             out['left'].astype(np.float64), out['right'].astype(np.float64))
  return (float(inside), (planned[1] - planned[0]) / max(1.0, float(width)),
          scores['bad1'], scores['psnr_left'], scores['psnr_right'])


def evaluate(count: int):
  """{(encoding, planner): [`_assess` tuple per pair]}."""
  descriptors = learned_matching.descriptor_function(
      pretrained.load_model(pretrained.get('anaglyph_matching')))
  planners = {'census': lambda image, name: families.of(name).estimate_range(
                  image, name, (0, 0)),
              'learned (shipped)': lambda image, name: learned_matching.estimate_range(
                  descriptors, image, name),
              'both': lambda image, name: learned_matching.estimate_range(
                  descriptors, image, name, config=INTERSECTED)}
  rows = {}
  pairs = validation.photo_pairs(matching_validation.WARP, count, validation.required_atlas())
  for number, pair in enumerate(pairs):
    for name in ENCODINGS:
      image = realworld.make_anaglyph(pair, name, 'ffmpeg')
      for label, plan in planners.items():
        rows.setdefault((name, label), []).append(
            _assess(pair, image, name, plan(image, name), descriptors))
    print(f'pair {number + 1}/{count}', file=sys.stderr, flush=True)
  return rows


def main(argv):
  del argv
  start = time.perf_counter()
  rows = evaluate(FLAGS.range_pairs)
  text = ['# Range planning on validation pairs', '',
          f'Written by `python -m experiments.range_validation --photo_dir=...` in '
          f'{time.perf_counter() - start:.0f} s on 2 CPU cores, {FLAGS.range_pairs} photo-warp '
          'pairs (module docstring). coverage: share of true disparities inside the planned '
          'range; width: planned width over the true 0.5-99.5 percentile width; bad-1 and '
          'views: the shipped learned stage over the planned range (means).', '',
          '| encoding | planner | coverage (mean) | coverage (lowest) | width (mean) | '
          'width (largest) | bad-1 | views L / R (dB) |', '| --- ' * 8 + '|']
  for (name, label), values in rows.items():
    values = np.array(values)
    mean = values.mean(axis=0)
    text.append(f'| {name} | {label} | {100 * mean[0]:.1f}% | '
                f'{100 * values[:, 0].min():.1f}% | {mean[1]:.2f}x | '
                f'{values[:, 1].max():.2f}x | {100 * mean[2]:.1f}% | '
                f'{mean[3]:.2f} / {mean[4]:.2f} |')
  markdown.write(FLAGS.range_output, text)


if __name__ == '__main__':
  app.run(main)
