"""Choices of the classical de-diplopia judged on validation pairs, not evaluation scenes.

    python -m experiments.diplopia_validation --photo_dir=photos/warps \
        --diplopia_variants="r5=window_radius=5,P 12/120=p1=12@p2=120"

Validation pairs: the photographs of `--photo_dir` (experiments/get_photos.sh; those the
learned stages train on, never an evaluation scene) under drawn disparity fields
(`photo_warps.warped_pair`, seeds 10^9 on, which training never draws; 256 x 512, depth
range 96, positive disparities as double images are ordered), mixed as I = (L + R) / 2
and rounded to 8 bits. Each variant is the shipped `DiplopiaConfig` with some fields
replaced (`field=value`, joined by `@`; `p1` and `p2` are those of its SGM, the fields of
`diplopia_layers.LayerConfig` those of its layer solve, e.g. `cg_tolerance`, and
`cepstrum_` + a field of `diplopia_cepstrum.CepstrumConfig` its echo score's), run by
`diplopia.unmix_diplopia` over [1, true maximum + 3]. Scores: bad-1 over the visible
pixels with a true disparity of at least 1 px, both views' RGB PSNR, and the seconds of one
pair's `unmix_diplopia` (one run on the machine at hand).
"""

import dataclasses
import os
import sys
import time
from typing import Dict, List, Tuple

from absl import app
from absl import flags
import numpy as np

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import diplopia_cepstrum
from mixstereo_tf.classical import diplopia_layers
from mixstereo_tf.data import photo_warps

from experiments import markdown
from experiments import validation  # --photo_dir, the pairs, their scores.

flags.DEFINE_list('diplopia_variants', [], 'label=field=value[@field=value...]: fields of '
                  'DiplopiaConfig (p1, p2: its SGM penalties); the shipped config comes '
                  'first.')
flags.DEFINE_integer('diplopia_pairs', 16, 'Warped photo pairs.')
flags.DEFINE_string('diplopia_validation_output',
                    'experiments/results/diplopia_validation.md', 'Markdown report.')
FLAGS = flags.FLAGS

WARP = photo_warps.WarpConfig(height=256, width=512, max_disparity=96, window_probability=0.0)
MATCHING_FIELDS = ('p1', 'p2')
CEPSTRUM_PREFIX = 'cepstrum_'  # cepstrum_weight=1.5: CepstrumConfig(weight=1.5).


def parse_variant(item: str) -> Tuple[str, diplopia.DiplopiaConfig]:
  """(label, config) of 'label=field=value[@field=value...]'.

  Raises:
    ValueError: naming --diplopia_variants and the item at fault.
  """
  label, sep, rest = item.partition('=')
  if not sep or not label or not rest:
    raise ValueError(f'--diplopia_variants: {item!r} is not label=field=value[@...].')
  base = diplopia.DiplopiaConfig()
  layer_fields = validation.numeric_fields(diplopia_layers.LayerConfig)
  cepstrum_fields = {CEPSTRUM_PREFIX + field: kind for field, kind in
                     validation.numeric_fields(diplopia_cepstrum.CepstrumConfig).items()}
  types = dict(validation.numeric_fields(diplopia.DiplopiaConfig), **layer_fields,
               **cepstrum_fields, **{field: int for field in MATCHING_FIELDS})
  values = validation.field_values('--diplopia_variants', item, rest.split('@'), types)
  matching = {field: values.pop(field) for field in MATCHING_FIELDS if field in values}
  layers = {field: values.pop(field) for field in layer_fields if field in values}
  cepstrum = {field[len(CEPSTRUM_PREFIX):]: values.pop(field) for field in cepstrum_fields
              if field in values}
  return label, dataclasses.replace(
      base, matching=dataclasses.replace(base.matching, **matching),
      layers=dataclasses.replace(base.layers, **layers),
      cepstrum=dataclasses.replace(base.cepstrum, **cepstrum), **values)


def evaluate(variants, atlas, count: int) -> Dict[str, List[Dict[str, float]]]:
  """{label: per pair scores} of each (label, config)."""
  rows = {label: [] for label, _ in variants}
  for number, pair in enumerate(validation.photo_pairs(WARP, count, atlas)):
    truth = pair['disparity_left']
    scored = pair['nonocc_left'] & (truth >= 1)
    image = np.round((pair['left'].astype(np.float32) + pair['right']) / 2).astype(np.uint8)
    for label, config in variants:
      start = time.perf_counter()
      out = diplopia.unmix_diplopia(image, (1, int(np.ceil(truth.max())) + 3), config)
      seconds = time.perf_counter() - start
      rows[label].append(dict(validation.scores(out['disparity_left'], pair, scored,
                                                out['left'], out['right']), seconds=seconds))
    print(f'pair {number + 1}/{count}', file=sys.stderr, flush=True)
  return rows


def main(argv):
  del argv
  start = time.perf_counter()
  variants = [('shipped', diplopia.DiplopiaConfig())] + validation.parse_all(
      FLAGS.diplopia_variants, parse_variant)
  rows = evaluate(variants, validation.required_atlas(), FLAGS.diplopia_pairs)
  lines = ['| variant | bad-1 | views L / R (dB) | seconds a pair |', '| --- | --- | --- | --- |']
  for label, _ in variants:
    mean = lambda key: np.mean([r[key] for r in rows[label]])  # pylint: disable=cell-var-from-loop
    lines.append(f"| {label} | {100 * mean('bad1'):.1f}% | "
                 f"{mean('psnr_left'):.3f} / {mean('psnr_right'):.3f} | {mean('seconds'):.3f} |")
  text = ['# Classical de-diplopia: choices on validation pairs', '',
          f'Written by `python -m experiments.diplopia_validation` in '
          f'{time.perf_counter() - start:.0f} s on {os.cpu_count()} CPU cores, '
          f'{FLAGS.diplopia_pairs} photo-warp double images (seeds 10^9 on, 256 x 512, '
          'range 96; module docstring). Variants: '
          + ', '.join(f'`{v}`' for v in FLAGS.diplopia_variants) + '.', '', *lines, '']
  markdown.write(FLAGS.diplopia_validation_output, text)


if __name__ == '__main__':
  app.run(main)
