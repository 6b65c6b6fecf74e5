"""Real-world anaglyph conditions (issue 13): window alignment, every encoding, detection.

    python experiments/realworld.py [--shared_dir=../shared/stereo_samples] \
        [--checkpoint=RUN] [--realworld_output=experiments/results/realworld.md]

Scenes with ground truth: the `sample` held-out scenes (8 procedural + Motorcycle at the
source's factor) and the SceneFlow frame of --shared_dir when given. For each: (1) the colour anaglyph made by FFmpeg with no, 30 % and 70 % window
alignment (`realworld.window_align`): classical bad-1; (2) at 30 % alignment every
encoding FFmpeg makes of the red-cyan family plus one green-magenta and one amber-blue:
classical told the encoding, classical on the encoding `detection` reports, the shipped
models told the encoding (`SHIPPED`: the default, the learned matching stage; the refiner
trained on it; the refiner on the classical result) (and --checkpoint's model) against the
trivial baseline (the mixture as each view), RGB and luma PSNR, bad-1 / bad-3, and how
often `detection` named the encoding.
"""

import csv
import functools
import os
import sys
import time

from absl import app
from absl import flags

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.unmixing import detection
from mixstereo_tf.unmixing import predictors

import numpy as np

cli_flags.define_shared_dir()
cli_flags.define_checkpoint()  # A model run to score beside classical.
flags.DEFINE_string('realworld_output', 'experiments/results/realworld.md', 'Markdown report.')
FLAGS = flags.FLAGS

FRACTIONS = (None, 0.3, 0.7)
# Row label -> the shipped model (`--pretrained`; None: the default of the encoding).
SHIPPED = {'shipped default': None, 'learned + its refiner': 'anaglyph_refined',
           'refiner': 'anaglyph'}
DETECTED = 'classical, detected encoding'
ENCODINGS = ('anaglyph', 'gray', 'half_color', 'dubois_ffmpeg', 'green_magenta_half',
             'amber_blue_dubois')


def _group(name):
  return 'procedural (mean)' if name.startswith('synthetic') else name


@functools.cache
def _classical(name):
  return predictors.build_unmixer(predictors.PredictorConfig('classical', mixture=name))


@functools.cache
def _shipped(label, name):
  """The Unmixer of a `SHIPPED` row for encoding `name`."""
  return predictors.build_unmixer(predictors.PredictorConfig(
      'model', mixture=name, pretrained=SHIPPED[label]))


def _unmixed(common, method, unmixer, pair, image):
  """A result row: `unmixer` on `image`, scored against `pair`'s views and disparities."""
  start = time.perf_counter()
  out = unmixer(image)
  return dict(common, method=method, seconds=round(time.perf_counter() - start, 2),
              **realworld.score(pair, out['left'], out['right'], out['disparity_left']))


def _evaluate(shared_dir):
  rows = []
  # A model unmixes the encodings it was trained on (its own mixture), window-aligned.
  model = predictors.build_unmixer(predictors.PredictorConfig(
      checkpoint=FLAGS.checkpoint)) if FLAGS.checkpoint else None
  for scene, data in realworld.scenes(shared_dir):
    base = {'scene': scene, 'group': _group(scene)}
    for fraction in FRACTIONS:
      pair = realworld.window_align(data, fraction) if fraction is not None else dict(
          data, shift=0)
      for name in ENCODINGS if fraction == 0.3 else ('anaglyph',):
        image = realworld.make_anaglyph(pair, name, 'ffmpeg')
        found = detection.detect(image)
        common = dict(base, fraction=fraction, shift=pair['shift'], encoding=name,
                      detected=found.name, confidence=round(found.confidence, 3))
        rows.append(dict(common, method='trivial',
                         **realworld.score(pair, image, image)))
        told = _unmixed(common, 'classical', _classical(name), pair, image)
        rows.append(told)
        if fraction == 0.3:
          rows.extend(_unmixed(common, label, _shipped(label, name), pair, image)
                      for label in SHIPPED)
        if model is not None and model.mixture == name:
          rows.append(_unmixed(common, 'model', model, pair, image))
        if fraction == 0.3 and found.name:  # As `--mixture=auto` would unmix it.
          rows.append(dict(told, method=DETECTED) if found.name == name else
                      _unmixed(common, DETECTED, _classical(found.name), pair, image))
        print(scene, fraction, name, found.name, file=sys.stderr, flush=True)
  return rows


def _mean(rows, key):
  values = [r[key] for r in rows if r.get(key) is not None and np.isfinite(r[key])]
  return float(np.mean(values)) if values else float('nan')


def _groups(rows):
  return list(dict.fromkeys(r['group'] for r in rows))


def _window_table(rows):
  lines = ['| scenes | bad-1 aligned as given | 30 % in front | 70 % in front | ratios |',
           '| --- | --- | --- | --- | --- |']
  for group in _groups(rows):
    picked = [r for r in rows if r['group'] == group and r['method'] == 'classical'
              and r['encoding'] == 'anaglyph']
    bad = [_mean([r for r in picked if r['fraction'] == f], 'bad1') for f in FRACTIONS]
    lines.append(f'| {group} | {100 * bad[0]:.1f}% | {100 * bad[1]:.1f}% | '
                 f'{100 * bad[2]:.1f}% | {bad[1] / bad[0]:.2f}x, {bad[2] / bad[0]:.2f}x |')
  return lines


def _encoding_table(rows):
  lines = ['| scenes | encoding | method | Y-PSNR L / R | RGB PSNR L / R | bad-1 | bad-3 | '
           'bad-1 / colour | detected |', '| --- ' * 9 + '|']
  for group in _groups(rows):
    for name in ENCODINGS:
      picked = [r for r in rows if r['group'] == group and r['fraction'] == 0.3
                and r['encoding'] == name]
      colour = _mean([r for r in rows if r['group'] == group and r['fraction'] == 0.3
                      and r['encoding'] == 'anaglyph' and r['method'] == 'classical'], 'bad1')
      right = sum(r['detected'] == name for r in picked if r['method'] == 'trivial')
      total = sum(r['method'] == 'trivial' for r in picked)
      for method in ('classical', DETECTED, *SHIPPED, 'model', 'trivial'):
        these = [r for r in picked if r['method'] == method]
        if not these:
          continue
        bad1 = _mean(these, 'bad1')
        cells = (f"{_mean(these, 'ypsnr_left'):.2f} / {_mean(these, 'ypsnr_right'):.2f}",
                 f"{_mean(these, 'psnr_left'):.2f} / {_mean(these, 'psnr_right'):.2f}",
                 f'{100 * bad1:.1f}%' if np.isfinite(bad1) else '-',
                 f"{100 * _mean(these, 'bad3'):.1f}%" if np.isfinite(bad1) else '-',
                 f'{bad1 / colour:.2f}x' if np.isfinite(bad1) else '-',
                 f'{right}/{total}' if method == 'trivial' else '')
        lines.append(f'| {group} | {name} | {method} | ' + ' | '.join(cells) + ' |')
  return lines


def main(argv):
  del argv
  start = time.perf_counter()
  rows = _evaluate(FLAGS.shared_dir)
  with open(os.path.splitext(FLAGS.realworld_output)[0] + '.csv', 'w', newline='') as handle:
    keys = list(dict.fromkeys(k for r in rows for k in r))
    writer = csv.DictWriter(handle, keys)
    writer.writeheader()
    writer.writerows(rows)
  text = ['# Real-world anaglyph conditions', '',
          'Written by `python experiments/realworld.py' +
          (f' --shared_dir={FLAGS.shared_dir}' if FLAGS.shared_dir else '') +
          (f' --checkpoint={FLAGS.checkpoint}' if FLAGS.checkpoint else '') + '`; anaglyphs '
          "made by FFmpeg's stereo3d (imageio-ffmpeg); classical = `--method=classical` "
          'with the disparity range estimated from each image; '
          + ('model = the --checkpoint run on the encoding it was trained on, range '
             'estimated likewise and fitted around its levels; ' if FLAGS.checkpoint else '')
          + f'shipped default = `--method=model` (the default `--pretrained` of the encoding: '
          f'{pretrained.choose(None, "anaglyph").name}); learned + its refiner = '
          '`--pretrained=anaglyph_refined` (on the learned stage); refiner = '
          '`--pretrained=anaglyph` (on the classical result); '
          + f'{DETECTED} = classical on the encoding `detection` reports (as '
          '`--mixture=auto`; refused images are left out); trivial = the mixture as each '
          'view. '
          f'{time.perf_counter() - start:.0f} s on this machine.', '',
          '## Window alignment (colour anaglyph, classical bad-1)', '', *_window_table(rows),
          '', '## Every encoding at 30 % window alignment', '', *_encoding_table(rows), '']
  with open(FLAGS.realworld_output, 'w') as handle:
    handle.write('\n'.join(text))
  print('\n'.join(text))


if __name__ == '__main__':
  app.run(main)
