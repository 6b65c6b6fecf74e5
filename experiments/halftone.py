"""Printed anaglyphs: halftone screens found and smoothed (`classical/halftone.py`).

    python -m experiments.halftone --photo_dir=photos/warps

Prints are simulated two ways: this project's operator (`data/halftone_print`: cyan,
magenta and yellow round dots at 15 / 75 / 0 degrees) and, where ImageMagick's `convert`
is installed, its ordered dither (CMYK separations, each ink's channel turned to its screen
angle, 15 / 75 / 0 / 45 degrees for C / M / Y / K, dithered with the `h4x4o`, `h6x6o` or
`h8x8o` halftone map and turned back): an independent encoder, with black ink.

1. **Choice** (validation photo warps, `validation.photo_pairs`: 320 x 640, positive
   disparities up to 51 px), each a colour and a Dubois anaglyph, printed: the default
   method (the encoding named) with the screen's true period smoothed at blur = `BLURS` x
   period, without smoothing, and with `--descreen=auto`; bad-1 and the views' PSNR
   against the clean views; how many prints `find_screen` finds, and how many
   `--mixture=auto` reads as their encoding with and without descreening.
2. **What is not a print**: `find_screen` on the photographs of --photo_dir at 640, 1600
   and 4000 px wide (where larger), scikit-image's images, and colour anaglyphs of the
   validation warps and of the real pairs at hand (none may be read as printed).
3. **Read after** on the real pairs at hand (Motorcycle, SceneFlow; never chosen on):
   printed, unmixed by the default method with --descreen off and auto, and not printed.
"""

import glob
import os
import shutil
import subprocess
import sys
import tempfile
import time

from absl import app
from absl import flags
import cv2
import numpy as np
from PIL import Image
import skimage.data

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
import mixstereo_tf
from mixstereo_tf.classical import halftone
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import disparity_io
from mixstereo_tf.data import halftone_print
from mixstereo_tf.data import photo_warps
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.unmixing import detection

from experiments import markdown
from experiments import validation  # --photo_dir, the pairs.

flags.DEFINE_integer('halftone_pairs', 6, 'Validation photo warps of part 1.')
flags.DEFINE_string('halftone_sceneflow_dir', '../shared/stereo_samples/sceneflow_A-0032-0006',
                    "The SceneFlow pair of part 3 ('' leaves it out).")
flags.DEFINE_string('halftone_output', 'experiments/results/halftone.md', 'Markdown report.')
FLAGS = flags.FLAGS

WARP = photo_warps.WarpConfig(height=320, width=640, max_disparity=64, window_probability=0.0)
BLURS = (0.35, 0.5, 0.65)
ENCODINGS = ('anaglyph', 'dubois_ffmpeg')
OURS = (3.0, 5.0)  # Periods of this project's operator, pixels.
MAGICK = {'h4x4o': 4.0, 'h8x8o': 8.0}  # ImageMagick's maps and their periods, pixels.
MAGICK_ANGLES = (15, 75, 0, 45)


def magick_print(image: np.ndarray, halftone_map: str) -> np.ndarray:
  """ImageMagick's CMYK ordered-dither print of uint8 RGB `image` (module docstring)."""
  with tempfile.TemporaryDirectory() as folder:
    Image.fromarray(image).save(os.path.join(folder, 'in.png'))
    run = lambda *args: subprocess.run(['convert', *args], check=True, capture_output=True)
    run(os.path.join(folder, 'in.png'), '-colorspace', 'CMYK', '-separate',
        os.path.join(folder, 'ink_%d.png'))
    for index, angle in enumerate(MAGICK_ANGLES):
      ink = os.path.join(folder, f'ink_{index}.png')
      run(ink, '-virtual-pixel', 'edge', '-distort', 'SRT', str(angle), '-ordered-dither',
          halftone_map, '-distort', 'SRT', str(-angle), ink)
    run(*[os.path.join(folder, f'ink_{i}.png') for i in range(4)], '-set', 'colorspace',
        'CMYK', '-combine', '-colorspace', 'sRGB', os.path.join(folder, 'out.png'))
    return np.asarray(Image.open(os.path.join(folder, 'out.png')).convert('RGB'))


def printers() -> dict:
  """{name: (print function of a uint8 RGB image, true period)}."""
  found = {f'ours, {p:g} px': (lambda x, p=p: halftone_print.halftone_print(x, p), p)
           for p in OURS}
  if shutil.which('convert'):
    found.update({f'ImageMagick {m}': (lambda x, m=m: magick_print(x, m), p)
                  for m, p in MAGICK.items()})
  return found


def mixed(pair: dict, name: str) -> np.ndarray:
  out = mixtures.mix(name, image_range.u8_to_signed(pair['left']),
                     image_range.u8_to_signed(pair['right']))
  return image_range.signed_to_u8(out.numpy())


def scores(pair: dict, image: np.ndarray, descreen, encoding: str = 'anaglyph') -> tuple:
  """(bad-1 %, left PSNR, right PSNR) of the default method on `image`, its encoding named
  (detection refuses some prints: a table below)."""
  out = mixstereo_tf.unmix(image, mixture=encoding, descreen=descreen)
  error = np.abs(out.disparity - pair['disparity_left'])[pair['nonocc_left']]
  psnr = lambda key: metrics.psnr(getattr(out, key).astype(float), pair[key].astype(float))
  return 100 * float(np.mean(error > 1)), psnr('left'), psnr('right')


def _detected(image: np.ndarray):
  """The encoding `detection.detect` names (None: none, or too small)."""
  try:
    return detection.detect(image).name
  except ValueError:
    return None


def settings(period: float) -> dict:
  """{row name: --descreen value} of part 1."""
  rows = {'none': halftone.OFF}
  rows.update({f'blur {b} x period': (b, period) for b in BLURS})
  rows['auto (shipped)'] = halftone.AUTO
  return rows


def _smoothed(image: np.ndarray, setting):
  """The image and --descreen value of a setting: (blur, period) smooths it here."""
  if isinstance(setting, tuple):
    blur, period = setting
    return cv2.GaussianBlur(image, (0, 0), blur * period), halftone.OFF
  return image, setting


def choice(pairs: list) -> list:
  """Part 1's table."""
  prints = printers()
  rows = {}
  found, read = 0, {halftone.OFF: 0, halftone.AUTO: 0}
  for pair in pairs:
    for encoding in ENCODINGS:
      clean = mixed(pair, encoding)
      for name, (make, period) in prints.items():
        image = make(clean)
        screen = halftone.find_screen(image)
        found += screen is not None
        for setting in read:
          smooth = halftone.descreen(image, screen.period) if (
              screen and setting == halftone.AUTO) else image
          read[setting] += _detected(smooth) == encoding
        for row, setting in settings(period).items():
          rows.setdefault((name, row), []).append(
              scores(pair, *_smoothed(image, setting), encoding))
  lines = ['## 1. Choice: validation photo warps', '',
           f'{len(pairs)} warps x {len(ENCODINGS)} encodings ({", ".join(ENCODINGS)}) per '
           f'print; `find_screen` found {found} of {len(pairs) * len(ENCODINGS) * len(prints)} '
           f'prints; detection read {read[halftone.OFF]} as their encoding without '
           f'descreening, {read[halftone.AUTO]} with. Mean bad-1, left / right PSNR.', '',
           '| print | ' + ' | '.join(settings(1.0)) + ' |',
           '| --- |' + ' --- |' * len(settings(1.0))]
  for name in prints:
    cells = []
    for row in settings(1.0):
      bad, left, right = np.mean(rows[(name, row)], axis=0)
      cells.append(f'{bad:.1f}%, {left:.2f} / {right:.2f} dB')
    lines.append(f'| {name} | ' + ' | '.join(cells) + ' |')
  return lines + ['']


def not_prints(pairs: list, real: dict) -> list:
  """Part 2's lines: every image `find_screen` reads as printed."""
  images = {}
  for path in sorted(glob.glob(os.path.join(FLAGS.photo_dir, '*'))):
    photo = cv2.imread(path)
    for width in (640, 1600, 4000):
      if photo is not None and photo.shape[1] >= width:
        size = (width, round(photo.shape[0] * width / photo.shape[1]))
        images[f'{os.path.basename(path)} at {width} px'] = cv2.resize(
            photo, size, interpolation=cv2.INTER_AREA)[..., ::-1]
  for name in ('astronaut', 'brick', 'camera', 'chelsea', 'coffee', 'grass', 'gravel',
               'rocket', 'text'):
    image = getattr(skimage.data, name)()
    images[f'scikit-image {name}'] = image if image.ndim == 3 else np.dstack([image] * 3)
  for index, pair in enumerate(pairs):
    images[f'validation warp {index}, colour anaglyph'] = mixed(pair, 'anaglyph')
  for name, pair in real.items():
    images[f'{name}, colour anaglyph'] = mixed(pair, 'anaglyph')
  read = [name for name, image in images.items() if halftone.find_screen(image)]
  return ['## 2. What is not a print', '',
          f'`find_screen` on {len(images)} images that are no prints: {len(read)} read as '
          'printed' + (f' ({", ".join(read)}).' if read else '.'), '']


def real_pairs() -> dict:
  """{name: pair} of the real pairs at hand (truth cut as given; unknown pixels left out)."""
  left, right, truth = skimage.data.stereo_motorcycle()
  pairs = {'Motorcycle': {'left': left, 'right': right, 'nonocc_left': np.isfinite(truth),
                          'disparity_left': np.nan_to_num(truth)}}
  folder = FLAGS.halftone_sceneflow_dir
  if folder:
    truth, valid = disparity_io.read_disparity(os.path.join(folder, 'disp_left.pfm'))
    occluded = np.asarray(Image.open(os.path.join(folder, 'occ_left.png'))) > 0
    rgb = lambda name: np.asarray(Image.open(os.path.join(folder, name)).convert('RGB'))
    pairs['SceneFlow'] = {'left': rgb('left.png'), 'right': rgb('right.png'),
                          'disparity_left': truth, 'nonocc_left': valid & ~occluded}
  return pairs


def read_after(real: dict) -> list:
  """Part 3's table."""
  lines = ['## 3. Read after: the real pairs at hand', '', 'The default method, colour '
           'anaglyph: bad-1, left / right PSNR.', '',
           '| pair | print | not printed | --descreen=off | --descreen=auto (shipped) |',
           '| --- | --- | --- | --- | --- |']
  for pair_name, pair in real.items():
    clean = mixed(pair, 'anaglyph')
    plain = '%.1f%%, %.2f / %.2f dB' % scores(pair, clean, halftone.AUTO)
    for name, (make, _) in printers().items():
      image = make(clean)
      cells = ['%.1f%%, %.2f / %.2f dB' % scores(pair, image, setting)
               for setting in (halftone.OFF, halftone.AUTO)]
      lines.append(f'| {pair_name} | {name} | {plain} | ' + ' | '.join(cells) + ' |')
  return lines + ['']


def main(argv):
  del argv
  start = time.perf_counter()
  atlas = validation.required_atlas()
  pairs = list(validation.photo_pairs(WARP, FLAGS.halftone_pairs, atlas))
  real = real_pairs()
  body = choice(pairs) + not_prints(pairs, real) + read_after(real)
  magick = 'ImageMagick found' if shutil.which('convert') else 'no ImageMagick: ours only'
  markdown.write(FLAGS.halftone_output, [
      '# Printed anaglyphs: halftone screens', '',
      f'Written by `python -m experiments.halftone {" ".join(sys.argv[1:])}` in '
      f'{time.perf_counter() - start:.0f} s on {os.cpu_count()} CPU cores ({magick}; module '
      'docstring).', ''] + body)


if __name__ == '__main__':
  app.run(main)
