"""The shipped models against the classical method (issue 15): experiments/results/pretrained.md.

    python experiments/pretrained.py --shared_dir=../shared/stereo_samples

For each model of `mixstereo_tf/artifacts/pretrained/` (or --pretrained=NAME|FOLDER) and its
default mixture (colour anaglyph / diplopia, made by `core/mixtures.py` as in the paper):
  1. the `sample` held-out scenes (8 procedural + Motorcycle), never trained on;
  2. the SceneFlow frame of --shared_dir;
  3. for anaglyph models, the real-world conditions of `evaluation/realworld.py`: every
     scene above, 30 % window-aligned, in each encoding FFmpeg's stereo3d makes
     (`experiments/realworld.py`'s list), the model unmixing each encoding it is named.
Both methods run as `mixstereo-unmix` runs them (disparity range estimated per image); the
table gives mean PSNR of both views and mean bad-1 per method and says, per set, whether
the model beats the classical method in all three.
"""

import sys
import time

from absl import app
from absl import flags
import numpy as np

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.core import mixtures
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.unmixing import predictors

cli_flags.define_shared_dir()
cli_flags.define_pretrained()
flags.DEFINE_string('pretrained_output', 'experiments/results/pretrained.md', 'Markdown report.')
FLAGS = flags.FLAGS

ENCODINGS = ('anaglyph', 'gray', 'half_color', 'dubois_ffmpeg', 'green_magenta_half',
             'amber_blue_dubois')
METHODS = ('model', 'classical')


def _unmixers(entry, name):
  return {'model': predictors.build_unmixer(predictors.PredictorConfig(
              method='model', pretrained=entry.folder, mixture=name)),
          'classical': predictors.build_unmixer(predictors.PredictorConfig(
              method='classical', mixture=name))}


def _score(unmixers, pair, image):
  scores = {}
  for method, unmixer in unmixers.items():
    start = time.perf_counter()
    out = unmixer(image)
    scores[method] = dict(realworld.score(pair, out['left'], out['right'],
                                          out['disparity_left']),
                          seconds=time.perf_counter() - start)
  return scores


def _evaluate(entry, scenes):
  """{set name: [per-image {method: scores}]}."""
  name = entry.mixtures[0]
  sets = {'held-out + Motorcycle': [], realworld.SCENEFLOW_FRAME: []}
  own = _unmixers(entry, name)
  for scene, data in scenes:
    pair = dict(data, shift=0)
    mixed = realworld.make_anaglyph(pair, name, 'ours')
    key = realworld.SCENEFLOW_FRAME if scene == realworld.SCENEFLOW_FRAME else (
        'held-out + Motorcycle')
    sets[key].append(_score(own, pair, mixed))
    print(entry.name, scene, name, file=sys.stderr, flush=True)
  if mixtures.get_mixture(name).is_anaglyph:
    title = 'real-world: 30 % window-aligned, FFmpeg encodings'
    sets[title] = []
    for encoding in ENCODINGS:
      if encoding not in entry.mixtures:
        continue
      unmixers = _unmixers(entry, encoding)
      for scene, data in scenes:
        pair = realworld.window_align(data, 0.3)
        sets[title].append(_score(unmixers, pair, realworld.make_anaglyph(
            pair, encoding, 'ffmpeg')))
        print(entry.name, scene, encoding, file=sys.stderr, flush=True)
  return sets


def _mean(rows, method, key):
  return float(np.mean([r[method][key] for r in rows]))


def _table(entry, sets):
  lines = [f'## {entry.name} ({entry.kind}; {", ".join(entry.mixtures)})', '',
           f'Recipe: `{entry.recipe}`', '',
           '| set | images | method | PSNR L | PSNR R | bad-1 | s / image | model beats '
           'classical |', '| --- ' * 8 + '|']
  for title, rows in sets.items():
    if not rows:
      continue
    means = {m: [_mean(rows, m, k) for k in ('psnr_left', 'psnr_right', 'bad1', 'seconds')]
             for m in METHODS}
    model, classical = means['model'], means['classical']
    wins = [model[0] > classical[0], model[1] > classical[1], model[2] < classical[2]]
    verdict = 'yes' if all(wins) else 'NO: ' + ', '.join(
        what for what, won in zip(('PSNR L', 'PSNR R', 'bad-1'), wins) if not won)
    for method in METHODS:
      psnr_l, psnr_r, bad1, seconds = means[method]
      lines.append(f'| {title} | {len(rows)} | {method} | {psnr_l:.2f} | {psnr_r:.2f} | '
                   f'{100 * bad1:.1f}% | {seconds:.2f} | '
                   f'{verdict if method == "model" else ""} |')
  return lines + ['']


def main(argv):
  del argv
  start = time.perf_counter()
  entries = [pretrained.get(FLAGS.pretrained)] if FLAGS.pretrained else pretrained.available()
  scenes = list(realworld.scenes(FLAGS.shared_dir))
  text = ['# Shipped models against the classical method', '',
          'Written by `python experiments/pretrained.py' +
          (f' --shared_dir={FLAGS.shared_dir}' if FLAGS.shared_dir else '') + '`. Both '
          'methods as `mixstereo-unmix` runs them (each image\'s disparity range estimated; '
          'the model unmixes the encoding it is given). PSNR: RGB, dB; bad-1: left '
          'disparity error > 1 px over valid ground truth. None of these scenes is a '
          'training scene.', '']
  for entry in entries:
    text += _table(entry, _evaluate(entry, scenes))
  text.append(f'{time.perf_counter() - start:.0f} s on this machine (2 cores).')
  with open(FLAGS.pretrained_output, 'w') as handle:
    handle.write('\n'.join(text) + '\n')
  print('\n'.join(text))


if __name__ == '__main__':
  app.run(main)
