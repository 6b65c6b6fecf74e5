"""Encoding detection on plain photographs: what `--mixture=auto` accepts that is no
anaglyph, and the doubt it then reports (`DetectConfig.doubtful_family_score`).

    python -m experiments.detection_photos --photo_dir=photos/warps

Photographs: those of --photo_dir (the training photographs, `experiments/get_photos.sh`)
and scikit-image's colour images, each at most 1600 px wide, stored as png, JPEG and an
H.264 frame (`ffmpeg_encoder.round_trip`). Beside them the validation anaglyphs of
`detection_validation` (the same pairs, encodings and storage): how many of those accepted
carry a doubt. A photograph is no mixture, so every one `detect` names is a false accept.
"""

import collections
import os
import sys
import time

from absl import app
from absl import flags
import cv2
import skimage.data

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.cli import input_images
from mixstereo_tf.data import photo_warps
from mixstereo_tf.evaluation import ffmpeg_encoder
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.unmixing import detection

from experiments import detection_validation
from experiments import markdown
from experiments import validation  # --photo_dir.

flags.DEFINE_string('detection_photos_output', 'experiments/results/detection_photos.md',
                    'Markdown report.')
FLAGS = flags.FLAGS

SKIMAGE = ('astronaut', 'coffee', 'chelsea', 'rocket', 'hubble_deep_field',
           'immunohistochemistry', 'retina', 'colorwheel', 'cat')  # Bundled (no pooch).
MAX_WIDTH = 1600


def _photographs():
  """[(name, uint8 RGB)]: --photo_dir's files and scikit-image's colour images."""
  folder = FLAGS.photo_dir
  found = [(name, input_images.read_image(os.path.join(folder, name)))
           for name in sorted(os.listdir(folder))]
  found += [(name, getattr(skimage.data, name)()[..., :3]) for name in SKIMAGE]
  shrunk = []
  for name, image in found:
    height, width = image.shape[:2]
    if width > MAX_WIDTH:
      image = cv2.resize(image, (MAX_WIDTH, height * MAX_WIDTH // width),
                         interpolation=cv2.INTER_AREA)
    shrunk.append((name, image[:image.shape[0] // 2 * 2, :image.shape[1] // 2 * 2]))
  return shrunk


def _stored(image, codec):
  return image if codec == 'png' else ffmpeg_encoder.round_trip(image, codec)


def _photo_rows():
  """Per storage: photographs, accepted (name, encoding, family score, doubt)."""
  rows, accepted = collections.Counter(), []
  for name, image in _photographs():
    for codec in detection_validation.CODECS:
      found = detection.detect(_stored(image, codec))
      rows[codec] += 1
      if found.name:
        family = max((k for k in found.scores if k.startswith('family:')),
                     key=found.scores.get)
        accepted.append((codec, name, found.name, found.scores[family], bool(found.doubt)))
  return rows, accepted


def _anaglyph_rows(atlas):
  """Per storage: validation anaglyphs accepted, and those of them with a doubt."""
  counts = collections.Counter()
  for first in detection_validation.SEED_SETS.values():
    for seed in range(first, first + detection_validation.FLAGS.detection_pairs):
      pair = photo_warps.warped_pair(seed, detection_validation.WARPS, atlas)
      for encoding in ffmpeg_encoder.FFMPEG_MODES:
        made = realworld.make_anaglyph(pair, encoding, 'ffmpeg')
        for codec in detection_validation.CODECS:
          found = detection.detect(ffmpeg_encoder.round_trip(made, codec))
          counts[codec, 'all'] += 1
          counts[codec, 'accepted'] += found.name is not None
          counts[codec, 'doubt'] += found.doubt is not None
  return counts


def main(argv):
  del argv
  start = time.perf_counter()
  atlas = validation.required_atlas()
  rows, accepted = _photo_rows()
  counts = _anaglyph_rows(atlas)
  codecs = detection_validation.CODECS
  text = ['# Encoding detection on plain photographs', '',
          f'Written by `python -m experiments.detection_photos {" ".join(sys.argv[1:])}`; '
          'see the module docstring. Doubt: a family score under '
          f'{detection.DetectConfig().doubtful_family_score} (`Detection.doubt`, logged as a '
          'warning and recorded as `detection_doubt`).', '',
          '| stored as | ' + ' | '.join(codecs) + ' |', '| --- |' + ' --- |' * len(codecs),
          '| photographs accepted (with a doubt) / all | ' + ' | '.join(
              f'{sum(a[0] == c for a in accepted)} ({sum(a[0] == c and a[4] for a in accepted)})'
              f' / {rows[c]}' for c in codecs) + ' |',
          '| validation anaglyphs with a doubt / accepted / all | ' + ' | '.join(
              f'{counts[c, "doubt"]} / {counts[c, "accepted"]} / {counts[c, "all"]}'
              for c in codecs) + ' |', '',
          'Photographs accepted (stored as, photograph, read as, family score, doubt): ' +
          '; '.join(f'{c} {n} {e} {s:.3f} {"yes" if d else "no"}'
                    for c, n, e, s, d in accepted) + '.', '',
          f'{time.perf_counter() - start:.0f} s on {os.cpu_count()} CPU cores.']
  markdown.write(FLAGS.detection_photos_output, text)


if __name__ == '__main__':
  app.run(main)
