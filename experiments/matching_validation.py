"""Choices of the learned matching stage judged on validation pairs, not evaluation scenes.

    python -m experiments.matching_validation --photo_dir=photos/warps \
        --variants="shipped=shipped,dilated=runs/abl_dil,census 0.3=shipped@census_weight=0.3"

The runs of experiments/results/matching_validation.md (800 steps each, as the ablations
of experiments/matching_ablations.py):
    common="--flagfile=experiments/pretrained_features.flags --num_steps=800"
    python -m mixstereo_tf.train $common --model_dir=runs/abl_w32
    python -m mixstereo_tf.train $common --feature_layers=6 \
        --feature_dilations=1,1,2,4,1,1 --model_dir=runs/abl_dil

Validation pairs: the training photographs (`--photo_dir`, experiments/get_photos.sh) under
new drawn disparity fields (`photo_warps.warped_pair`, seeds 10^9 on, which training never
draws; 256 x 512, depth range 96, both signs), FFmpeg's colour, half-colour and Dubois
anaglyphs of each. Each variant is a features model (`shipped`: the package's
`anaglyph_matching`; or a training run folder, its newest checkpoint) with optional
`LearnedMatchConfig` fields (`@field=value`), run by `learned_matching.match`, or
`census`: the classical census matcher (`matcher.match`) with optional `MatcherConfig`
fields; all over the true range +- 3 px. The census matcher as shipped is the first row. Scores: bad-1 over the visible left pixels and the views' RGB PSNR after the
restoration (`Family.restore`, as the tools run it).
"""

import os
import sys
import tempfile
import time
from typing import Dict, List, Tuple

from absl import app
from absl import flags
import numpy as np

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.classical import anaglyph
from mixstereo_tf.classical import matcher
from mixstereo_tf.data import photo_warps
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.unmixing import families
from mixstereo_tf.unmixing import learned_matching

from experiments import markdown
from experiments import validation  # --photo_dir, the pairs, their scores.

flags.DEFINE_list('variants', ['shipped=shipped'], 'label=MODEL[@field=value...]: MODEL '
                  "'shipped' or a features run folder, fields of LearnedMatchConfig; or "
                  "'census', fields of MatcherConfig.")
flags.DEFINE_integer('validation_pairs', 12, 'Warped photo pairs (each in every encoding).')
flags.DEFINE_string('validation_output', 'experiments/results/matching_validation.md',
                    'Markdown report.')
FLAGS = flags.FLAGS

ENCODINGS = ('anaglyph', 'half_color', 'dubois_ffmpeg')
WARP = photo_warps.WarpConfig(height=256, width=512, max_disparity=96)
MARGIN = 3
CENSUS = 'census'


def parse_variant(item: str) -> Tuple[str, str, object]:
  """(label, model, config) of 'label=MODEL[@field=value...]': a LearnedMatchConfig, or
  for MODEL 'census' a MatcherConfig (int and float fields).

  Raises:
    ValueError: naming --variants and the item at fault.
  """
  label, sep, rest = item.partition('=')
  parts = rest.split('@')
  if not sep or not label or not parts[0]:
    raise ValueError(f'--variants: {item!r} is not label=MODEL[@field=value...].')
  kind = (matcher.MatcherConfig if parts[0] == CENSUS else
          learned_matching.LearnedMatchConfig)
  values = validation.field_values('--variants', item, parts[1:],
                                   validation.numeric_fields(kind))
  return label, parts[0], kind(**values)


def _descriptors(model: str, folder: str):
  if model == 'shipped':
    entry = pretrained.get('anaglyph_matching')
  elif os.path.isdir(model):
    entry = validation.model_entry(model, folder)
  else:
    raise ValueError(f"--variants: model {model!r} is neither 'shipped' nor a folder.")
  return learned_matching.descriptor_function(pretrained.load_model(entry))


def _score(pair, image, name, disparities) -> Dict[str, float]:
  """`validation.scores` of the disparities and the views restored from them."""
  restored = families.of(name).restore(image.astype(np.float32) / 255.0, name,
                                       disparities['disparity_left'],
                                       disparities['disparity_right'])
  return validation.scores(disparities['disparity_left'], pair, pair['nonocc_left'],
                           restored['left'] * 255.0, restored['right'] * 255.0)


def evaluate(variants, atlas, count: int) -> Dict[Tuple[str, str], List[Dict[str, float]]]:
  """{(label, encoding): per pair scores}, classical first."""
  rows = {}
  with tempfile.TemporaryDirectory() as folder:
    models = {}
    for label, model, config in variants:
      if model not in models and model != CENSUS:
        models[model] = _descriptors(model, os.path.join(folder, f'model{len(models)}'))
    for number, pair in enumerate(validation.photo_pairs(WARP, count, atlas)):
      low = int(np.floor(pair['disparity_left'].min())) - MARGIN
      high = int(np.ceil(pair['disparity_left'].max())) + MARGIN
      for name in ENCODINGS:
        image = realworld.make_anaglyph(pair, name, 'ffmpeg')
        mixture = image.astype(np.float32) / 255.0
        out = matcher.match(*anaglyph.eye_images(mixture, name), low, high)
        rows.setdefault(('classical', name), []).append(_score(pair, image, name, out))
        for label, model, config in variants:
          if model == CENSUS:
            out = matcher.match(*anaglyph.eye_images(mixture, name), low, high, config)
          else:
            out = learned_matching.match(models[model], mixture, name, low, high, config)
          rows.setdefault((label, name), []).append(_score(pair, image, name, out))
      print(f'pair {number + 1}/{count}', file=sys.stderr, flush=True)
  return rows


def table(rows, labels) -> List[str]:
  """Markdown: per variant, bad-1 and views per encoding (means over the pairs)."""
  lines = ['| variant | ' + ' | '.join(f'{n} bad-1 | {n} views L / R (dB)'
                                       for n in ENCODINGS) + ' |',
           '| --- ' * (1 + 2 * len(ENCODINGS)) + '|']
  for label in labels:
    cells = []
    for name in ENCODINGS:
      mean = {k: np.mean([r[k] for r in rows[(label, name)]]) for k in rows[(label, name)][0]}
      cells += [f"{100 * mean['bad1']:.1f}%",
                f"{mean['psnr_left']:.2f} / {mean['psnr_right']:.2f}"]
    lines.append(f'| {label} | ' + ' | '.join(cells) + ' |')
  return lines


def main(argv):
  del argv
  start = time.perf_counter()
  variants = validation.parse_all(FLAGS.variants, parse_variant)
  rows = evaluate(variants, validation.required_atlas(), FLAGS.validation_pairs)
  text = ['# Learned matching stage: choices on validation pairs', '',
          f'Written by `python -m experiments.matching_validation` in '
          f'{time.perf_counter() - start:.0f} s on {os.cpu_count()} CPU cores, '
          f'{FLAGS.validation_pairs} photo-warp pairs (seeds 10^9 on, 256 x 512, range 96, '
          'FFmpeg anaglyphs; module docstring). Variants: '
          + ', '.join(f'`{v}`' for v in FLAGS.variants) + '.', '',
          *table(rows, ['classical'] + [v[0] for v in variants]), '']
  markdown.write(FLAGS.validation_output, text)


if __name__ == '__main__':
  app.run(main)
