"""Encoding detection on validation anaglyphs stored as JPEG and video frames: the choice of
`DetectConfig`'s gray_blur, gray_relative, gray_detail and ghost_max_fraction
(docs/DESIGN.md, unmixing).

    python -m experiments.detection_validation --photo_dir=photos/warps

Pairs: the training photographs under drawn disparity fields (`photo_warps.warped_pair`,
1024 x 368, half of them window-aligned; never an evaluation scene), seeds 2.6e9 on (the
choice) and 2.7e9 on (drawn after it). Each pair is made by FFmpeg into every three-channel
encoding of `ffmpeg_encoder.FFMPEG_MODES` (`ENCODINGS`) and stored as png (as made), as a JPEG and as an H.264 video
frame, both with 4:2:0 chroma (`ffmpeg_encoder.round_trip`). Per configuration and storage:
how many images `detection.detect` names exactly, and the misreads of the shipped one.
"""

import collections
import dataclasses
import os
import sys
import time

from absl import app
from absl import flags

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import photo_warps
from mixstereo_tf.evaluation import ffmpeg_encoder
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.unmixing import detection

from experiments import markdown
from experiments import validation  # --photo_dir.

flags.DEFINE_integer('detection_pairs', 12, 'Warped photo pairs per seed set.')
flags.DEFINE_string('detection_validation_output',
                    'experiments/results/detection_validation.md', 'Markdown report.')
FLAGS = flags.FLAGS

SEED_SETS = {'choice': 2_600_000_000, 'after': 2_700_000_000}
CODECS = ('png', 'jpeg', 'h264')
WARPS = photo_warps.WarpConfig(height=368, width=1024, max_disparity=96,
                               window_probability=0.5)
SHIPPED = detection.DetectConfig()
SHIPPED_NAME = 'shipped (leak at 1/2 width)'
# The detection before this choice, the gray rule alone, and other copy widths for the leak.
CONFIGS = {
    'before': dataclasses.replace(SHIPPED, gray_blur=1, gray_relative=0.0,
                                  ghost_max_fraction=1.0),
    'gray rule, leak at full width': dataclasses.replace(SHIPPED, ghost_max_fraction=1.0),
    SHIPPED_NAME: SHIPPED,
    'leak at 0.4 width': dataclasses.replace(SHIPPED, ghost_max_fraction=0.4),
    'leak at 1/3 width': dataclasses.replace(SHIPPED, ghost_max_fraction=1 / 3),
}
AFTER_CONFIGS = ('before', SHIPPED_NAME)
# The three-channel encodings whose detection these parameters were chosen for (the
# two-channel red-blue and red-green ones are found by their empty channel first:
# `unmixing/two_channel.py`, `results/detection.md`).
ENCODINGS = tuple(name for name in ffmpeg_encoder.FFMPEG_MODES
                  if not mixtures.get_mixture(name).served_as)


def _detections(first_seed: int, count: int, names, atlas):
  """[(seed, encoding, codec, config name, detected name)] for `count` pairs."""
  found = []
  for seed in range(first_seed, first_seed + count):
    pair = photo_warps.warped_pair(seed, WARPS, atlas)
    for encoding in ENCODINGS:
      made = realworld.make_anaglyph(pair, encoding, 'ffmpeg')
      for codec in CODECS:
        image = ffmpeg_encoder.round_trip(made, codec)
        for name in names:
          found.append((seed, encoding, codec, name, detection.detect(image, CONFIGS[name]).name))
    print(seed, flush=True)
  return found


def _section(title, found, names):
  exact = collections.Counter((f[3], f[2]) for f in found if f[1] == f[4])
  total = collections.Counter((f[3], f[2]) for f in found)
  misreads = collections.Counter((f[2], f[1], f[4] or 'refused') for f in found
                                 if f[3] == SHIPPED_NAME and f[1] != f[4])
  return [f'## {title}', '', '| configuration | ' + ' | '.join(CODECS) + ' |',
          '| --- |' + ' --- |' * len(CODECS),
          *(f'| {name} | ' + ' | '.join(f'{exact[(name, c)]} / {total[(name, c)]}'
                                        for c in CODECS) + ' |' for name in names), '',
          'Misreads of the shipped configuration (stored, made as -> read as, count): ' +
          '; '.join(f'{c} {m} -> {r} x{n}' for (c, m, r), n in sorted(misreads.items())), '']


def main(argv):
  del argv
  start = time.perf_counter()
  atlas = validation.required_atlas()
  text = ['# Encoding detection on validation anaglyphs, as made and stored lossily', '',
          f'Written by `python -m experiments.detection_validation {" ".join(sys.argv[1:])}`; '
          'see the module docstring. '
          f'{FLAGS.detection_pairs} pairs a set, {len(ENCODINGS)} '
          'encodings each.', '']
  for title, names in (('choice', tuple(CONFIGS)), ('after', AFTER_CONFIGS)):
    found = _detections(SEED_SETS[title], FLAGS.detection_pairs, names, atlas)
    text += _section(f'Seeds {SEED_SETS[title]:.2g} on ({title})', found, names)
  text.append(f'{time.perf_counter() - start:.0f} s on {os.cpu_count()} CPU cores.')
  markdown.write(FLAGS.detection_validation_output, text)


if __name__ == '__main__':
  app.run(main)
