"""Refiners compared on validation examples, neither training nor evaluation data.

    python -m experiments.refiner_validation --refiner_runs=runs/diplopia_r7,OLD \
        [--refiner_mixture=diplopia]
    python -m experiments.refiner_validation --refiner_mixture=anaglyph \
        --refiner_runs=mixstereo_tf/artifacts/pretrained/anaglyph_refined,\
mixstereo_tf/artifacts/pretrained/anaglyph \
        --refiner_validation_output=experiments/results/refiner_validation_anaglyph.md

(OLD: a pretrained folder, e.g. an earlier commit's, `git show REV:mixstereo_tf/artifacts/
pretrained/diplopia/weights.npz` and its info.json in one folder.)

Validation examples: `refiner_data.make_example` at indices 100000 on (training uses
0-1499 of the same generator: realistic `sample` scenes with scikit-image's training
photographs, 30% clean, the rest degraded), 24 at 160 x 320 (disparities up to 64 px) and
16 cut from scenes twice as large and deep; for double images the same again with
a L + (1 - a) R, a from [0.3, 0.7] (`ExampleConfig.weighted_probability` = 1), every
method estimating a (`--mixing_weight=auto`). Rows: the classical method, the shipped model
of the encoding (`pretrained.choose`) and each item of --refiner_runs (a training run,
its newest checkpoint, or a pretrained folder holding info.json), all as the tools run
them (range estimated per image; a refiner trained on a shipped stage runs on it,
`Pretrained.base`). Scores: left bad-1 over every pixel and both views'
RGB PSNR against the scenes' truth.
"""

import os
import sys
import tempfile
import time

from absl import app
from absl import flags
import numpy as np

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.data import texture_atlas
from mixstereo_tf.training import refiner_data
from mixstereo_tf.unmixing import families
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.unmixing import shipped

from experiments import markdown
from experiments import validation

flags.DEFINE_list('refiner_runs', [], 'Refiner training runs or pretrained folders to '
                  'compare.')
flags.DEFINE_string('refiner_mixture', 'diplopia', 'The encoding of the examples.')
flags.DEFINE_string('refiner_validation_output',
                    'experiments/results/refiner_validation.md', 'Markdown report.')
FLAGS = flags.FLAGS

FIRST_INDEX = 100000
# (label, large_probability, weighted, count).
SCALES = (('160x320, up to 64 px', 0.0, False, 24), ('320x640, up to 128 px', 1.0, False, 16),
          ('160x320, a in [0.3, 0.7]', 0.0, True, 24),
          ('320x640, a in [0.3, 0.7]', 1.0, True, 16))


def _unmixers(name, runs, folder, weight):
  """{label: Unmixer}: classical, the shipped model, then each run; `weight`: their
  mixing weight (`PredictorConfig.mixing_weight`)."""
  config = predictors.PredictorConfig(mixture=name, method='model', mixing_weight=weight)
  out = {'classical': predictors.build_unmixer(
      predictors.PredictorConfig(mixture=name, method='classical', mixing_weight=weight)),
         'shipped': shipped.pretrained_unmixer(pretrained.choose(None, name), config)}
  for index, run in enumerate(runs):
    if not os.path.isdir(run):
      raise app.UsageError(f'--refiner_runs: {run!r} is not a folder.')
    entry = validation.model_entry(run, os.path.join(folder, f'run{index}'))
    out[run] = shipped.pretrained_unmixer(entry, config)
  return out


def main(argv):
  del argv
  start = time.perf_counter()
  textures = texture_atlas.load_textures('train')
  lines = ['| scenes | model | bad-1 | views L / R (dB) |', '| --- | --- | --- | --- |']
  with tempfile.TemporaryDirectory() as folder:
    weights = (False, True) if families.of(FLAGS.refiner_mixture).weighted else (False,)
    built = {weighted: _unmixers(FLAGS.refiner_mixture, FLAGS.refiner_runs,
                                 os.path.join(folder, str(weighted)),
                                 'auto' if weighted else None) for weighted in weights}
    for label, large, weighted, count in SCALES:
      if weighted not in built:
        continue
      unmixers = built[weighted]
      config = refiner_data.ExampleConfig(mixtures=FLAGS.refiner_mixture,
                                          clean_probability=0.3, large_probability=large,
                                          weighted_probability=float(weighted))
      rows = {key: [] for key in unmixers}
      for index in range(FIRST_INDEX, FIRST_INDEX + count):
        example = refiner_data.make_example(index, config, textures)
        scored = np.ones(example['disparity_left'].shape, bool)
        for key, unmix in unmixers.items():
          out = unmix(example['mixture'])
          rows[key].append(validation.scores(out['disparity_left'], example, scored,
                                             out['left'], out['right']))
        print(f'{label}: example {index - FIRST_INDEX + 1}/{count}', file=sys.stderr,
              flush=True)
      for key, values in rows.items():
        mean = lambda k: np.mean([v[k] for v in values])  # pylint: disable=cell-var-from-loop
        lines.append(f"| {label} ({count}) | {key} | {100 * mean('bad1'):.2f}% | "
                     f"{mean('psnr_left'):.2f} / {mean('psnr_right'):.2f} |")
  text = ['# Refiners on validation examples', '',
          f'Written by `python -m experiments.refiner_validation '
          f'--refiner_mixture={FLAGS.refiner_mixture} --refiner_runs='
          f'{",".join(FLAGS.refiner_runs)}` in {time.perf_counter() - start:.0f} s on '
          f'{os.cpu_count()} CPU cores (module docstring).', '', *lines, '']
  markdown.write(FLAGS.refiner_validation_output, text)


if __name__ == '__main__':
  app.run(main)
