"""Encoding detection on anaglyphs made by FFmpeg's stereo3d (issue 13's must-show).

    python experiments/detection.py [--shared_dir=../shared/stereo_samples] \
        [--detection_output=experiments/results/detection.md] [--detection_codecs=png,jpeg,h264]

Pairs: Middlebury 2014 Motorcycle (scikit-image) and the real frames of --shared_dir
(KITTI 2015 #151, a KITTI object frame, a SceneFlow frame), each as captured and
window-aligned as anaglyph makers publish them (30 % of the disparities behind the
screen, `realworld.window_align`, placed by `realworld.estimated_disparities`: no ground
truth needed; scene names ending ' @30%'). Each pair is encoded by FFmpeg
in every mode of `ffmpeg_encoder.FFMPEG_MODES` and given to `detection.detect`; the left
view alone (an ordinary colour photo) and the diplopia average must be refused. Each image
is detected as FFmpeg made it (png) and stored as published anaglyphs are: a JPEG and an
H.264 video frame, both with 4:2:0 chroma (`ffmpeg_encoder.round_trip`; images cropped to
even sizes). Detection is only measured here; its parameters were chosen on training
scenes (`detection_validation.py`). For each miss, the views the classical method restores
from that image told the true and the detected encoding (RGB PSNR).
"""

import collections
import functools
import os
import sys
import time

from absl import app
from absl import flags

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import image_io
from mixstereo_tf.evaluation import ffmpeg_encoder
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.unmixing import detection
from mixstereo_tf.unmixing import predictors

import numpy as np
import skimage.data

cli_flags.define_shared_dir()
flags.DEFINE_string('detection_output', 'experiments/results/detection.md', 'Markdown report.')
flags.DEFINE_list('detection_codecs', ['png', 'jpeg', 'h264'],
                  'How each image is stored before detection: png (as made), '
                  f'{", ".join(ffmpeg_encoder.CODECS)}.')
FLAGS = flags.FLAGS

WINDOW = 0.3  # Share of the disparities behind the screen in the aligned copies.
SHARED = (('kitti2015_000151', 'kitti2015_aanet_000151', 'image_2.png', 'image_3.png'),
          ('kitti_object', 'kitti_object_velodyne', 'left.png', 'right.png'),
          ('sceneflow_A-0032-0006', 'sceneflow_A-0032-0006', 'left.png', 'right.png'))


def _captured(shared_dir):
  left, right, _ = skimage.data.stereo_motorcycle()
  yield 'motorcycle', left, right
  for name, folder, a, b in SHARED if shared_dir else ():
    yield name, *(image_io.read_image(os.path.join(shared_dir, folder, f)) for f in (a, b))


def _pairs(shared_dir):
  """(scene, left, right): each pair as captured, then window-aligned (module docstring)."""
  for name, left, right in _captured(shared_dir):
    yield name, left, right
    aligned = realworld.window_align(realworld.estimated_disparities(left, right), WINDOW)
    yield f'{name} @{WINDOW:.0%}', aligned['left'], aligned['right']


def _cases(left, right):
  for name in ffmpeg_encoder.FFMPEG_MODES:
    yield name, ffmpeg_encoder.encode(left, right, name)
  yield None, left
  diplopia = (left.astype(np.uint16) + right) // 2
  yield None, diplopia.astype(np.uint8)


def _family(name):
  return mixtures.get_mixture(name).family if name else None


@functools.cache
def _classical(name):
  return predictors.build_unmixer(predictors.PredictorConfig('classical', mixture=name))


def _miss_cost(image, truth, found, left, right):
  """A table row: RGB PSNR L / R of the classical method told `truth`, then `found`."""
  cells = []
  for name in (truth, found):
    out = _classical(name)(image)
    cells.append(f"{metrics.psnr(out['left'], left):.2f} / "
                 f"{metrics.psnr(out['right'], right):.2f}")
  return cells


def main(argv):
  del argv
  start = time.perf_counter()
  rows, costs = [], []
  exact, family, total = (collections.Counter() for _ in range(3))
  for scene, left, right in _pairs(FLAGS.shared_dir):
    height, width = left.shape[0] // 2 * 2, left.shape[1] // 2 * 2
    left, right = left[:height, :width], right[:height, :width]
    for index, (truth, made) in enumerate(_cases(left, right)):
      label = truth or ('photo (left view)' if index == len(ffmpeg_encoder.FFMPEG_MODES)
                        else 'diplopia')
      for codec in FLAGS.detection_codecs:
        image = ffmpeg_encoder.round_trip(made, codec)
        found = detection.detect(image)
        ok = found.name == truth
        same_family = _family(found.name) == _family(truth)
        for key in ('all', codec):
          exact[key] += ok
          family[key] += same_family
          total[key] += 1
        rows.append(f'| {scene} | {label} | {codec} | {found.name or "refused"} | '
                    f'{found.confidence:.2f} | {"yes" if ok else "no"} |')
        print(rows[-1], flush=True)
        if not ok and truth and found.name:
          told, detected = _miss_cost(image, truth, found.name, left, right)
          costs.append(f'| {scene} | {truth} | {codec} | {found.name} | {told} | {detected} |')
  seconds = time.perf_counter() - start
  text = '\n'.join([
      '# Encoding detection on FFmpeg anaglyphs', '',
      f'Written by `python {" ".join(sys.argv)}` in {seconds:.0f} s. FFmpeg stereo3d (the '
      'binary of imageio-ffmpeg) made each anaglyph; "refused" = not an anaglyph.', '',
      *(f'- **{key}: {exact[key]} of {total[key]} exact; {family[key]} of {total[key]} with '
        'the right glasses** (family, or refused when no anaglyph).'
        for key in ('all', *FLAGS.detection_codecs)), '',
      '| scene | made as | stored | detected | confidence | exact |',
      '| --- | --- | --- | --- | --- | --- |',
      *rows, '', '## What a miss costs', '',
      'RGB PSNR (dB) of the views the classical method restores when told the encoding '
      'that made the image, and when told the detected one (as `--mixture=auto` does).', '',
      '| scene | made as | stored | detected | PSNR L / R, told | PSNR L / R, detected |',
      '| --- | --- | --- | --- | --- | --- |', *costs, ''])
  with open(FLAGS.detection_output, 'w') as f:
    f.write(text)
  print(f"{exact['all']}/{total['all']} exact, {family['all']}/{total['all']} family; wrote "
        f'{FLAGS.detection_output}')


if __name__ == '__main__':
  app.run(main)
