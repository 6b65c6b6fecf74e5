"""Tilted anaglyphs: crooked scans and misregistered inks, turned level (`unmixing/tilt.py`).

    python -m experiments.tilt --photo_dir=photos/warps

Each pair's colour anaglyph (and Dubois, on the warps) is turned by `ANGLES` degrees about
its centre (OpenCV, bilinear, edges reflected), and once more with its left eye's channel
moved down `OFFSET` px before the turn (inks printed out of register). The truth is turned
alike: the views, the left disparity (nearest; its magnitude, along the turned rows) and
its known pixels (turned as a mask; the reflected edges are unknown). The default method
unmixes each with `--rectify=off` and `--rectify=auto`, scored in the turned frame
(bad-1 over the known pixels, views' PSNR over the same box as the truth's).

1. Validation photo warps (`validation.photo_pairs`: 320 x 640, positive disparities up to
   51 px): what `auto` turned (how many level inputs it turned: false turns) and the mean
   scores; the decision rule (`LevelConfig.min_gain`) was set before this table
   (module docstring of `unmixing/tilt.py`).
2. The real pairs at hand, read after: Motorcycle, SceneFlow.
3. False turns: `tilt.choose` on level anaglyphs only: 16 more validation warps (`SIZES`,
   disparities up to 77 px, window-aligned by chance) in `FALSE_TURN_ENCODINGS`, every
   other one through a quality-85 JPEG, and the KITTI frames at hand
   (`--tilt_kitti_dirs`); each it would turn is listed.
"""

import os
import sys
import time

from absl import app
from absl import flags
import cv2
import numpy as np

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
import mixstereo_tf
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import photo_warps
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.unmixing import tilt

from experiments import halftone as printed  # The real pairs at hand, their flag.
from experiments import markdown
from experiments import validation  # --photo_dir, the pairs.

flags.DEFINE_integer('tilt_pairs', 6, 'Validation photo warps of part 1.')
flags.DEFINE_list('tilt_kitti_dirs', ['../shared/stereo_samples/kitti_object_velodyne',
                                       '../shared/stereo_samples/kitti2015_aanet_000151'],
                  'Folders of KITTI pairs (left.png / right.png or image_2.png / image_3.png) '
                  'of part 3.')
flags.DEFINE_string('tilt_output', 'experiments/results/tilt.md', 'Markdown report.')
FLAGS = flags.FLAGS

WARP = photo_warps.WarpConfig(height=320, width=640, max_disparity=64, window_probability=0.0)
ANGLES = (0.0, 0.5, 1.0, 2.0, 4.0)
OFFSET = 1.5  # Pixels the left eye's ink is printed below the right's.
SETTINGS = ('off', 'auto')
SIZES = ((256, 512), (320, 640), (480, 960), (540, 960))
FALSE_TURN_ENCODINGS = ('anaglyph', 'half_color', 'dubois_ffmpeg', 'green_magenta')


def tilted(pair: dict, encoding: str, angle: float, offset: float) -> tuple:
  """(the turned mixture, the turned truth dict)."""
  height, width = pair['left'].shape[:2]
  turn = cv2.getRotationMatrix2D((width / 2, height / 2), angle, 1.0)
  warp = lambda x, how, edge: cv2.warpAffine(x, turn, (width, height), flags=how,
                                             borderMode=edge)
  mixed = mixtures.mix(encoding, image_range.u8_to_signed(pair['left']),
                       image_range.u8_to_signed(pair['right']))
  mixture = image_range.signed_to_u8(mixed.numpy())
  if offset:
    left_eye = list(mixtures.get_mixture(encoding).eye_channels[0])
    lower = np.float64([[1, 0, 0], [0, 1, offset]])
    mixture[..., left_eye] = cv2.warpAffine(
        mixture[..., left_eye], lower, (width, height), flags=cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_REFLECT).reshape(height, width, -1)
  known = warp(pair['nonocc_left'].astype(np.uint8), cv2.INTER_NEAREST,
               cv2.BORDER_CONSTANT) > 0
  truth = {'left': warp(pair['left'], cv2.INTER_LINEAR, cv2.BORDER_REFLECT),
           'right': warp(pair['right'], cv2.INTER_LINEAR, cv2.BORDER_REFLECT),
           'disparity_left': warp(np.float32(pair['disparity_left']), cv2.INTER_NEAREST,
                                  cv2.BORDER_CONSTANT), 'known': known}
  return warp(mixture, cv2.INTER_LINEAR, cv2.BORDER_REFLECT), truth


def scores(mixture: np.ndarray, truth: dict, encoding: str, setting: str) -> tuple:
  """(turned?, bad-1 %, left PSNR, right PSNR) of the default method."""
  out = mixstereo_tf.unmix(mixture, mixture=encoding, rectify=setting)
  known = truth['known']
  rows, columns = np.flatnonzero(known.any(1)), np.flatnonzero(known.any(0))
  box = (slice(rows[0], rows[-1] + 1), slice(columns[0], columns[-1] + 1))
  psnr = lambda key: metrics.psnr(getattr(out, key)[box].astype(float),
                                  truth[key][box].astype(float))
  error = np.abs(out.disparity - truth['disparity_left'])[known]
  return ('tilt' in out.info, 100 * float(np.mean(error > 1)), psnr('left'), psnr('right'))


def table(pairs: dict, encodings: tuple) -> list:
  """Rows per angle and offset: turned by auto, then bad-1 and views per setting."""
  lines = ['| tilt | turned by auto | ' + ' | '.join(SETTINGS) + ' |',
           '| --- | --- |' + ' --- |' * len(SETTINGS)]
  for offset in (0.0, OFFSET):
    for angle in ANGLES:
      found = {setting: [] for setting in SETTINGS}
      for pair in pairs.values():
        for encoding in encodings:
          mixture, truth = tilted(pair, encoding, angle, offset)
          for setting in SETTINGS:
            found[setting].append(scores(mixture, truth, encoding, setting))
      cells = []
      for setting in SETTINGS:
        _, bad, left, right = np.mean(found[setting], axis=0)
        cells.append(f'{bad:.1f}%, {left:.2f} / {right:.2f} dB')
      turned = sum(row[0] for row in found['auto'])
      lines.append(f'| {angle:g} deg' + (f', inks {offset:g} px apart' if offset else '') +
                   f' | {turned} of {len(found["auto"])} | ' + ' | '.join(cells) + ' |')
  return lines + ['']


def _kitti(folder: str) -> dict:
  names = [('left.png', 'right.png'), ('image_2.png', 'image_3.png')]
  found = next(n for n in names if os.path.exists(os.path.join(folder, n[0])))
  left, right = (cv2.imread(os.path.join(folder, n))[..., ::-1].copy() for n in found)
  return {'left': left, 'right': right}


def false_turns(atlas) -> list:
  """Part 3's lines."""
  images = {}
  for index in range(16):
    height, width = SIZES[index % len(SIZES)]
    pair = photo_warps.warped_pair(validation.PHOTO_SEED + 500 + index, photo_warps.WarpConfig(
        height=height, width=width, max_disparity=96), atlas)
    for encoding in FALSE_TURN_ENCODINGS:
      mixture, truth = tilted(pair, encoding, 0.0, 0.0)
      if index % 2:
        _, data = cv2.imencode('.jpg', mixture[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, 85])
        mixture = cv2.imdecode(data, cv2.IMREAD_COLOR)[..., ::-1].copy()
      images[f'warp {index} ({width} x {height}{", JPEG" if index % 2 else ""}), '
             f'{encoding}'] = (mixture, encoding, truth)
  for folder in FLAGS.tilt_kitti_dirs:
    pair = _kitti(folder)
    for encoding in FALSE_TURN_ENCODINGS[:3]:
      mixed = mixtures.mix(encoding, image_range.u8_to_signed(pair['left']),
                           image_range.u8_to_signed(pair['right']))
      images[f'{os.path.basename(folder)}, {encoding}'] = (
          image_range.signed_to_u8(mixed.numpy()), encoding, None)
  turned = []
  for name, (mixture, encoding, truth) in images.items():
    found = tilt.choose(mixture, encoding)
    if found is not None:
      cost = '' if truth is None else ' (bad-1, views: off %.1f%%, %.2f / %.2f dB; auto ' \
          '%.1f%%, %.2f / %.2f dB)' % tuple(value for setting in SETTINGS for value in
                                             scores(mixture, truth, encoding, setting)[1:])
      turned.append(f'{name} by {found.angle:.2f} degrees, {found.offset:.2f} px{cost}')
  return ['## 3. False turns', '', f'Of {len(images)} level anaglyphs `--rectify=auto` would '
          f'turn {len(turned)}' + (': ' + '; '.join(turned) + '.' if turned else '.'), '']


def main(argv):
  del argv
  start = time.perf_counter()
  atlas = validation.required_atlas()
  warps = dict(enumerate(validation.photo_pairs(WARP, FLAGS.tilt_pairs, atlas)))
  body = ['## 1. Validation photo warps', '',
          f'{len(warps)} warps, colour and Dubois anaglyphs; mean bad-1, left / right PSNR.',
          ''] + table(warps, ('anaglyph', 'dubois_ffmpeg'))
  for name, pair in printed.real_pairs().items():
    body += [f'## 2. {name}, colour anaglyph', ''] + table({name: pair}, ('anaglyph',))
  body += false_turns(atlas)
  markdown.write(FLAGS.tilt_output, [
      '# Tilted anaglyphs: turned level or not', '',
      f'Written by `python -m experiments.tilt {" ".join(sys.argv[1:])}` in '
      f'{time.perf_counter() - start:.0f} s on {os.cpu_count()} CPU cores (module '
      'docstring).', ''] + body)


if __name__ == '__main__':
  app.run(main)
