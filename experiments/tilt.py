"""Tilted anaglyphs and double images: crooked scans, rolled cameras and misregistered inks,
turned level (`unmixing/tilt.py`).

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
4. Double images (I = a L + (1 - a) R), their echo's line (`classical/echo_tilt.py`): the
   real pairs at a = 1/2 turned by `ANGLES` (no ink offset: both copies share every
   channel), and false turns as in part 3 on level double images of the 16 warps and the
   KITTI frames at a = 0.3 / 0.5 / 0.7 (every other warp through a quality-85 JPEG).
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


def scores(mixture: np.ndarray, truth: dict, encoding: str, setting: str,
           weight: float = 0.5) -> tuple:
  """(turned?, bad-1 %, left PSNR, right PSNR) of the default method (a double image
  mixed at `weight` told so: `--mixing_weight`)."""
  out = mixstereo_tf.unmix(mixture, mixture=encoding, rectify=setting,
                           mixing_weight=None if weight == 0.5 else weight)
  known = truth['known']
  rows, columns = np.flatnonzero(known.any(1)), np.flatnonzero(known.any(0))
  box = (slice(rows[0], rows[-1] + 1), slice(columns[0], columns[-1] + 1))
  psnr = lambda key: metrics.psnr(getattr(out, key)[box].astype(float),
                                  truth[key][box].astype(float))
  error = np.abs(out.disparity - truth['disparity_left'])[known]
  return ('tilt' in out.info, 100 * float(np.mean(error > 1)), psnr('left'), psnr('right'))


def table(pairs: dict, encodings: tuple, offsets: tuple = (0.0, OFFSET)) -> list:
  """Rows per angle and offset: turned by auto, then bad-1 and views per setting."""
  lines = ['| tilt | turned by auto | ' + ' | '.join(SETTINGS) + ' |',
           '| --- | --- |' + ' --- |' * len(SETTINGS)]
  for offset in offsets:
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


def _level_images(atlas, encodings: tuple, weights: tuple = (0.5,)) -> dict:
  """Part 3's and 4's level images: {name: (mixture, encoding, truth or None, weight)}, an
  encoding 'diplopia' mixed at each of `weights` (a L + (1 - a) R)."""
  def mixed(pair, encoding, weight):
    if encoding != 'diplopia':
      return image_range.signed_to_u8(mixtures.mix(
          encoding, image_range.u8_to_signed(pair['left']),
          image_range.u8_to_signed(pair['right'])).numpy())
    return np.uint8(np.round(weight * np.float32(pair['left']) +
                             (1 - weight) * np.float32(pair['right'])))
  images = {}
  for index in range(16):
    height, width = SIZES[index % len(SIZES)]
    pair = photo_warps.warped_pair(validation.PHOTO_SEED + 500 + index, photo_warps.WarpConfig(
        height=height, width=width, max_disparity=96), atlas)
    truth = tilted(pair, 'anaglyph', 0.0, 0.0)[1]
    for encoding, weight in ((e, w) for e in encodings for w in weights):
      mixture = mixed(pair, encoding, weight)
      if index % 2:
        _, data = cv2.imencode('.jpg', mixture[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, 85])
        mixture = cv2.imdecode(data, cv2.IMREAD_COLOR)[..., ::-1].copy()
      named = encoding if len(weights) == 1 else f'{encoding} a = {weight:g}'
      images[f'warp {index} ({width} x {height}{", JPEG" if index % 2 else ""}), '
             f'{named}'] = (mixture, encoding, truth, weight)
  for folder in FLAGS.tilt_kitti_dirs:
    pair = _kitti(folder)
    for encoding, weight in ((e, w) for e in encodings[:3] for w in weights):
      named = encoding if len(weights) == 1 else f'{encoding} a = {weight:g}'
      images[f'{os.path.basename(folder)}, {named}'] = (mixed(pair, encoding, weight),
                                                         encoding, None, weight)
  return images


def false_turns(images: dict, title: str) -> list:
  """Part 3's (or 4's) lines on `_level_images`."""
  turned = []
  for name, (mixture, encoding, truth, weight) in images.items():
    found = tilt.choose(mixture, encoding)
    if found is not None:
      cost = '' if truth is None else ' (bad-1, views: off %.1f%%, %.2f / %.2f dB; auto ' \
          '%.1f%%, %.2f / %.2f dB)' % tuple(
              value for setting in SETTINGS
              for value in scores(mixture, truth, encoding, setting, weight)[1:])
      turned.append(f'{name} by {found.angle:.2f} degrees, {found.offset:.2f} px{cost}')
  kind = 'double images' if title.startswith('4') else 'anaglyphs'
  return [f'## {title}', '', f'Of {len(images)} level {kind} `--rectify=auto` would '
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
  body += false_turns(_level_images(atlas, FALSE_TURN_ENCODINGS), '3. False turns')
  for name, pair in printed.real_pairs().items():
    body += [f'## 4. {name}, double image (a = 1/2)', ''] + table(
        {name: pair}, ('diplopia',), offsets=(0.0,))
  body += false_turns(_level_images(atlas, ('diplopia',), (0.3, 0.5, 0.7)),
                      '4. False turns of double images')
  markdown.write(FLAGS.tilt_output, [
      '# Tilted anaglyphs and double images: turned level or not', '',
      f'Written by `python -m experiments.tilt {" ".join(sys.argv[1:])}` in '
      f'{time.perf_counter() - start:.0f} s on {os.cpu_count()} CPU cores (module '
      'docstring).', ''] + body)


if __name__ == '__main__':
  app.run(main)
