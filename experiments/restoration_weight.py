"""A restoration weight (`RestoreConfig.prior_weight` or `.colour_line_weight`), chosen on
validation data.

    python experiments/restoration_weight.py [--restoration_field=prior_weight] \
        [--restoration_weight_output=experiments/results/restoration_weight.md]
    python experiments/restoration_weight.py --restoration_field=colour_line_weight \
        --restoration_weight_output=experiments/results/colour_line_weight.md

Examples: `refiner_data.make_example` at indices 100000 on (neither training nor evaluation
data: the refiner trains on 0-1999), every anaglyph encoding, 160x320 scenes and scenes
twice as large and deep, 70 % window-aligned, 30 % clean and 70 % degraded like the
refiner's training mix; and, with --photo_dir, clean warps of photographs
(`photo_warps.warped_pair`, 192x384, seeds 10^9 on: the learned matching stage's source
with new warps, never an evaluation scene). Each example's classical disparities (cached
in the refiner's examples, the classical matcher's for the warps) are restored with every
candidate weight; the score of a weight is the mean RGB PSNR of both views, per encoding
and scale weighted 0.3 clean / 0.7 degraded. Reported: each weight's mean over encodings
and scales (the other fields at their defaults) and its largest and mean regret (the dB
it loses to the best weight of an encoding and scale). The default is the weight of the
smallest largest regret when its mean is within 0.05 dB of the best.
"""

import collections
import time
from typing import Dict, List, Sequence

from absl import app
from absl import flags

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.classical import anaglyph
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import photo_warps
from mixstereo_tf.data import texture_atlas
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.restoration import views
from mixstereo_tf.training import refiner_data

import numpy as np

from experiments import validation  # --photo_dir (empty here: procedural examples only).

flags.DEFINE_string('restoration_weight_output', 'experiments/results/restoration_weight.md',
                    'Markdown report.')
flags.DEFINE_integer('examples', 12, 'Examples per encoding at the small scale (half as many '
                     'at the large one).')
flags.DEFINE_enum('restoration_field', 'prior_weight', ['prior_weight', 'colour_line_weight'],
                  'The `RestoreConfig` field swept.')
FLAGS = flags.FLAGS

# Candidate values of each swept field.
CANDIDATES = {'prior_weight': (0.01, 0.03, 0.1, 0.2, 0.3, 0.5, 1.0),
              'colour_line_weight': (0.0, 0.3, 1.0, 2.0, 3.0, 5.0, 10.0)}
FIRST_INDEX = 100000
CLEAN_SHARE = 0.3
SCALES = (('160x320', 0.0, 1.0), ('320x640', 1.0, 0.5))  # (name, large_probability, share)


def _candidate_psnrs(image: np.ndarray, name: str, d_left: np.ndarray, d_right: np.ndarray,
                     truth, field: str) -> np.ndarray:
  """Per candidate of `field`, the mean RGB PSNR of both views of uint8 anaglyph `image`
  restored from these disparities against truth['left'], truth['right']."""
  mixture = image.astype(np.float32) / 255.0
  row = []
  for weight in CANDIDATES[field]:
    restored = views.restore_views(mixture, name, d_left, d_right,
                                   config=views.RestoreConfig(**{field: weight}))
    row.append(np.mean([metrics.psnr(restored[key] * 255.0, truth[key].astype(np.float64))
                        for key in ('left', 'right')]))
  return np.array(row)


def _scores(name: str, large: float, count: int, field: str
            ) -> Dict[bool, List[np.ndarray]]:
  """{clean: [per example, the mean view PSNR of every candidate of `field`]} for one
  encoding and scale."""
  config = refiner_data.ExampleConfig(mixtures=name, clean_probability=CLEAN_SHARE,
                                      large_probability=large)
  textures = texture_atlas.load_textures('train')  # As the refiner's examples (no texture_dir).
  out = collections.defaultdict(list)
  for index in range(FIRST_INDEX, FIRST_INDEX + count):
    example = refiner_data.make_example(index, config, textures)
    out[example['clean']].append(_candidate_psnrs(
        example['mixture'], name, example['classical_disparity_left'],
        example['classical_disparity_right'], example, field))
  return out


PHOTO_WARP = photo_warps.WarpConfig(height=192, width=384, max_disparity=64)


def _photo_scores(name: str, count: int, field: str, atlas) -> Dict[bool, List[np.ndarray]]:
  """{True: [per warped pair, the mean view PSNR of every candidate of `field`]}: clean
  anaglyphs of `count` photo warps, restored from the classical matcher's disparities."""
  rows = []
  for pair in validation.photo_pairs(PHOTO_WARP, count, atlas):
    image = realworld.make_anaglyph(pair, name, 'ours')
    matched = anaglyph.unmix_anaglyph(image, name)
    rows.append(_candidate_psnrs(image, name, matched['disparity_left'],
                                 matched['disparity_right'], pair, field))
  return {True: rows, False: []}


def _weighted(scores: Dict[bool, List[np.ndarray]]) -> np.ndarray:
  """The clean and degraded means mixed CLEAN_SHARE : 1 - CLEAN_SHARE (the share of a
  kind with no example goes to the other)."""
  shares = {True: CLEAN_SHARE, False: 1.0 - CLEAN_SHARE}
  present = [clean for clean in shares if scores[clean]]
  total = sum(shares[clean] for clean in present)
  return sum(shares[clean] / total * np.mean(scores[clean], axis=0) for clean in present)


def summarize(table: np.ndarray) -> Dict[str, np.ndarray]:
  """{'mean', 'max_regret', 'mean_regret'} per weight of a [cases, weights] PSNR table."""
  regret = table.max(axis=1, keepdims=True) - table
  return {'mean': table.mean(axis=0), 'max_regret': regret.max(axis=0),
          'mean_regret': regret.mean(axis=0)}


def _row(label: str, values: Sequence[float], digits: int = 2) -> str:
  return f'| {label} | ' + ' | '.join(f'{v:.{digits}f}' for v in values) + ' |'


def main(argv):
  del argv
  start, field = time.time(), FLAGS.restoration_field
  weights = CANDIDATES[field]
  header = '| encoding | ' + ' | '.join(f'w = {w}' for w in weights) + ' |'
  rule = '| --- ' * (len(weights) + 1) + '|'
  sections, cases, split = [], [], collections.defaultdict(list)
  for scale, large, share in SCALES:
    count = max(1, round(FLAGS.examples * share))
    lines = [f'## {scale} scenes, {count} examples per encoding', '', header, rule]
    for name in mixtures.parse_names('anaglyphs'):
      scores = _scores(name, large, count, field)
      for clean, rows in scores.items():
        split[clean].append(np.mean(rows, axis=0))
      weighted = _weighted(scores)
      cases.append(weighted)
      lines.append(_row(name, weighted))
    sections.append('\n'.join(lines))
  if FLAGS.photo_dir:
    atlas = texture_atlas.load_texture_dir(FLAGS.photo_dir)
    count = max(1, round(FLAGS.examples / 2))
    lines = [f'## 192x384 photo warps, {count} clean examples per encoding', '', header, rule]
    for name in mixtures.parse_names('anaglyphs'):
      scores = _photo_scores(name, count, field, atlas)
      split[True].append(np.mean(scores[True], axis=0))
      cases.append(_weighted(scores))
      lines.append(_row(name, cases[-1]))
    sections.append('\n'.join(lines))
  summary = summarize(np.array(cases))
  best, safest = int(np.argmax(summary['mean'])), int(np.argmin(summary['max_regret']))
  lines = [
      f'# The restoration\'s `{field}` on validation examples', '',
      f'Written by `python experiments/restoration_weight.py --restoration_field={field}'
      + (f' --photo_dir={FLAGS.photo_dir}' if FLAGS.photo_dir else '') +
      f'` in {time.time() - start:.0f} s. '
      'Mean RGB PSNR (dB) of both restored views, classical disparities, weighted 0.3 clean '
      '/ 0.7 degraded; regret: dB lost to the best weight of an encoding and scale.', '',
      '| over encodings and scales | ' + ' | '.join(f'w = {w}' for w in weights) + ' |', rule,
      _row('mean', summary['mean'], 3), _row('largest regret', summary['max_regret']),
      _row('mean regret', summary['mean_regret'], 3),
      _row('mean, clean examples only', np.mean(split[True], axis=0), 3),
      _row('mean, degraded examples only', np.mean(split[False], axis=0), 3), '',
      f'Best mean: w = {weights[best]}; smallest largest regret: w = {weights[safest]}; '
      f'shipped (`RestoreConfig.{field}`): w = {getattr(views.RestoreConfig(), field)}.',
      '', '\n\n'.join(sections), '']
  with open(FLAGS.restoration_weight_output, 'w') as handle:
    handle.write('\n'.join(lines))
  print('\n'.join(lines[:10]))


if __name__ == '__main__':
  app.run(main)
