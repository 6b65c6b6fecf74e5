"""Ablation of the colour-line pass (issue "Learned cross-channel matching", item 3): the
views of each evaluation set restored with and without it from the same disparities.

    python -m experiments.colour_line [--shared_dir=../shared/stereo_samples] \
        [--colour_line_output=experiments/results/colour_line.md]

Scenes, window alignment and FFmpeg's encodings as experiments/same_channel.py; for the
colour, half-colour and Dubois anaglyphs, the classical method and the learned matching
stage (the default) each match once, then `views.restore_views` restores both views from
their disparities with `RestoreConfig.colour_line_weight` 0 (the restoration before the
pass) and its default. Reported: RGB PSNR L / R per scene group, and the gain.
"""

import dataclasses
import os
import time

from absl import app
from absl import flags
import numpy as np

from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.restoration import views
from experiments import markdown
from experiments import same_channel  # Also defines --shared_dir.

flags.DEFINE_string('colour_line_output', 'experiments/results/colour_line.md',
                    'Markdown report.')
FLAGS = flags.FLAGS

ENCODINGS = ('anaglyph', 'half_color', 'dubois_ffmpeg')
METHODS = ('classical', 'learned')
PASSES = {'without': dataclasses.replace(views.RestoreConfig(), colour_line_weight=0.0),
          'with': views.RestoreConfig()}


def _rows(shared_dir):
  """(group, encoding, method, pass, psnr_left, psnr_right) of every run."""
  for scene, data in same_channel.scenes(shared_dir):
    pair = realworld.window_align(data, same_channel.FRACTION)
    for name in ENCODINGS:
      image = realworld.make_anaglyph(pair, name, 'ffmpeg')
      for method in METHODS:
        out = same_channel.unmixer(name, method)(image)
        for label, config in PASSES.items():
          restored = views.restore_views(image.astype(np.float32) / 255.0, name,
                                         out['disparity_left'], out['disparity_right'],
                                         config=config)
          yield (same_channel.group(scene), name, method, label,
                 *(metrics.psnr(np.rint(restored[k] * 255.0), pair[k].astype(np.float64))
                   for k in ('left', 'right')))


def _table(rows):
  lines = ['| scenes | encoding | method | without the pass L / R (dB) | with it | gain |',
           '| --- ' * 6 + '|']
  keys = dict.fromkeys(r[:3] for r in rows)
  for group, name, method in keys:
    mean = {label: np.mean([r[4:] for r in rows if r[:4] == (group, name, method, label)],
                           axis=0) for label in PASSES}
    gain = mean['with'] - mean['without']
    lines.append(f"| {group} | {name} | {method} | {mean['without'][0]:.2f} / "
                 f"{mean['without'][1]:.2f} | {mean['with'][0]:.2f} / {mean['with'][1]:.2f} "
                 f'| {gain[0]:+.2f} / {gain[1]:+.2f} |')
  return lines


def main(argv):
  del argv
  start = time.perf_counter()
  rows = list(_rows(FLAGS.shared_dir))
  command = 'python -m experiments.colour_line' + (
      f' --shared_dir={FLAGS.shared_dir}' if FLAGS.shared_dir else '')
  text = ['# The colour-line pass, ablated', '',
          f'Written by `{command}` in {time.perf_counter() - start:.0f} s on '
          f'{os.cpu_count()} CPU cores. Scenes, window alignment (30%) and FFmpeg '
          'encodings as `same_channel.md`; each method matches once and its disparities '
          'are restored without (`RestoreConfig(colour_line_weight=0)`, the restoration '
          'before the pass) and with the pass (the default). RGB PSNR of the uint8 views.',
          '', *_table(rows), '']
  markdown.write(FLAGS.colour_line_output, text)


if __name__ == '__main__':
  app.run(main)
