"""Ghosting of the input colour anaglyph vs the recovered pair re-encoded (issue 30).

    python experiments/reencode_ghosting.py \
        [--ghosting_output=experiments/results/reencode_ghosting.md]

The pair: Middlebury 2014 Motorcycle (scikit-image), downscaled by --ghosting_scale, encoded
as a red-cyan colour anaglyph (`anaglyph`: R from the left view, G and B from the right),
unmixed by the classical method, and the recovered pair re-encoded by
`stereo_formats.reencode` (`--output_format=anaglyph_*`).

Filter model (linear, on the displayed [0, 1] values): the eye behind the red filter sees
R + k (G + B) / 2, the eye behind the cyan filter sees the two channels G + k R and
B + k R. k = 0 is ideal glasses (red passes R, cyan passes G and B); k = 0.1 stands for
cheap glasses leaking 10% of the other primaries (an assumption, not a measured filter).

Crosstalk of an eye: its signal S is fitted by least squares over every pixel as
S = a . L + b . R + c (L, R the TRUE views' RGB, 7 unknowns per channel seen); the leak is
the energy of the other view's term, var(b . R_other), over that of its own view's term,
var(a . L_own), summed over the channels the eye sees. 0% = no trace of the other view.
"""

import os
import sys
import time

from absl import app
from absl import flags

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.cli import stereo_formats
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.unmixing import predictors

import cv2
import numpy as np
import skimage.data

flags.DEFINE_string('ghosting_output', 'experiments/results/reencode_ghosting.md',
                    'Markdown report.')
flags.DEFINE_float('ghosting_scale', 0.5, 'Scale of the Motorcycle pair (741x500 px).')
FLAGS = flags.FLAGS

LEAKS = (0.0, 0.1)
ENCODINGS = (('dubois', 'anaglyph_dubois'), ('optimized', 'anaglyph_optimized'),
             ('gray', 'anaglyph_gray'), ('anaglyph', 'anaglyph_colour'))


def eye_signals(image: np.ndarray, leak: float):
  """(red-filter eye [N, 1], cyan-filter eye [N, 2]) of a uint8 RGB image, [0, 1]."""
  rgb = image.reshape(-1, 3).astype(np.float64) / 255.0
  red = rgb[:, :1] + leak * (rgb[:, 1:2] + rgb[:, 2:3]) / 2
  cyan = rgb[:, 1:] + leak * rgb[:, :1]
  return red, cyan


def crosstalk(signal: np.ndarray, own: np.ndarray, other: np.ndarray) -> float:
  """Energy of `other`'s least-squares term over `own`'s, in % (module docstring)."""
  own = own.reshape(-1, 3).astype(np.float64) / 255.0
  other = other.reshape(-1, 3).astype(np.float64) / 255.0
  design = np.concatenate([own, other, np.ones((own.shape[0], 1))], axis=1)
  coefficients, *_ = np.linalg.lstsq(design, signal, rcond=None)
  own_term, other_term = own @ coefficients[:3], other @ coefficients[3:6]
  return 100.0 * float(other_term.var(axis=0).sum() / own_term.var(axis=0).sum())


def leaks(image, left, right, leak):
  """(left-eye %, right-eye %) crosstalk of an anaglyph image against the true views."""
  red, cyan = eye_signals(image, leak)
  return crosstalk(red, left, right), crosstalk(cyan, right, left)


def _pair(scale):
  left, right, _ = skimage.data.stereo_motorcycle()
  size = (round(left.shape[1] * scale), round(left.shape[0] * scale))
  return tuple(cv2.resize(v, size, interpolation=cv2.INTER_AREA) for v in (left, right))


def main(argv):
  del argv
  start = time.perf_counter()
  left, right = _pair(FLAGS.ghosting_scale)
  colour = stereo_formats.reencode('anaglyph', left, right)
  unmixer = predictors.build_unmixer(predictors.PredictorConfig('classical',
                                                                mixture='anaglyph'))
  out = unmixer(colour)
  images = [('input: colour anaglyph of the true pair', colour)] + [
      (f're-encoded `{flag}` of the recovered pair',
       stereo_formats.reencode(name, out['left'], out['right'])) for name, flag in ENCODINGS]
  lines = [
      '# Ghosting: the input colour anaglyph vs the recovered pair re-encoded', '',
      f'`python {" ".join(sys.argv)}` ({time.perf_counter() - start:.0f} s). Motorcycle '
      f'(scikit-image) at {left.shape[1]}x{left.shape[0]} px, red-cyan colour anaglyph, '
      'classical unmix; recovered views '
      f"{metrics.psnr(out['left'], left):.2f} / {metrics.psnr(out['right'], right):.2f} dB "
      'PSNR (left / right). Filter model and crosstalk: the docstring of '
      '`experiments/reencode_ghosting.py` (k = leak of each filter; k = 0 ideal glasses, '
      'k = 0.1 an assumed leaky pair). Crosstalk: energy of the other view in what an eye '
      'sees over its own view, %.', '',
      '| anaglyph | k | left eye (red) | right eye (cyan) |', '| --- | ---: | ---: | ---: |']
  for leak in LEAKS:
    for label, image in images:
      left_leak, right_leak = leaks(image, left, right, leak)
      lines.append(f'| {label} | {leak:g} | {left_leak:.2f} | {right_leak:.2f} |')
  os.makedirs(os.path.dirname(FLAGS.ghosting_output) or '.', exist_ok=True)
  with open(FLAGS.ghosting_output, 'w', encoding='utf-8') as f:
    f.write('\n'.join(lines) + '\n')
  print('\n'.join(lines))


if __name__ == '__main__':
  app.run(main)
