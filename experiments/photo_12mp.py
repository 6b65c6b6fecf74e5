"""A 12-megapixel (4000x3000) anaglyph through `unmix --mixture=auto`, the classical method
or the shipped model: seconds and the process' peak resident memory (issues 13 and 15);
with --photo_encoding=diplopia a double image (L + R) / 2 through `--mixture=diplopia`.

    python experiments/photo_12mp.py [--photo_encoding=anaglyph] [--photo_method=model]
        [--photo_pretrained=anaglyph_matching] [--photo_size=1242x375]

The pair is scikit-image's Motorcycle (Middlebury 2014, 2964x2000) resized to 4000x3000,
so its disparities reach ~360 px; an anaglyph is FFmpeg's when imageio-ffmpeg is there
and FFmpeg makes that encoding (`ffmpeg_encoder.FFMPEG_MODES`), else ours.
"""

import os
import resource
import time

from absl import app
from absl import flags
import cv2
import numpy as np
import skimage.data

import mixstereo_tf
from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.core import mixtures
from mixstereo_tf.evaluation import ffmpeg_encoder
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.unmixing import predictors

flags.DEFINE_string('photo_encoding', 'anaglyph', 'The encoding to make and unmix: an anaglyph '
                    "(unmixed with --mixture=auto) or 'diplopia' (with --mixture=diplopia).")
flags.DEFINE_enum('photo_method', 'classical', ('classical', 'model'),
                  'classical, or model: the shipped model (no model flag).')
flags.DEFINE_string('photo_size', '4000x3000', 'WIDTHxHEIGHT of the photo.')
flags.DEFINE_string('photo_pretrained', None, 'With --photo_method=model: the shipped model '
                    '(e.g. anaglyph_matching, the learned matching stage; default: the '
                    "tools' default).")
FLAGS = flags.FLAGS


def _peak_gib() -> float:
  return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # KiB on Linux.


def main(argv):
  del argv
  left, right, _ = skimage.data.stereo_motorcycle()
  size = tuple(int(v) for v in FLAGS.photo_size.split('x'))
  left, right = (cv2.resize(v, size, interpolation=cv2.INTER_CUBIC) for v in (left, right))
  pair = {'left': left, 'right': right}
  encoder = 'ffmpeg' if FLAGS.photo_encoding in ffmpeg_encoder.FFMPEG_MODES else 'ours'
  try:
    image = realworld.make_anaglyph(pair, FLAGS.photo_encoding, encoder)
  except ImportError:  # No imageio-ffmpeg.
    image = realworld.make_anaglyph(pair, FLAGS.photo_encoding, 'ours')
  del left, right, pair
  before = _peak_gib()
  double = not mixtures.get_mixture(FLAGS.photo_encoding).is_anaglyph
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      FLAGS.photo_method, mixture=FLAGS.photo_encoding if double else 'auto',
      pretrained=FLAGS.photo_pretrained))
  start, cpu = time.perf_counter(), time.process_time()
  out = unmixer(image)
  wall, cpu = time.perf_counter() - start, time.process_time() - cpu
  info = out['info']
  print(f'{FLAGS.photo_size} {FLAGS.photo_encoding}, {FLAGS.photo_method} '
        f'{FLAGS.photo_pretrained or ""}: detected {info["detected"]} '
        f'({info["confidence"]:.2f}), range {info["disparity_range"]}, '
        f'{wall:.1f} s wall, {cpu:.1f} CPU-s, peak RSS {_peak_gib():.2f} GiB '
        f'({before:.2f} GiB before the unmix: input images and TensorFlow); package '
        f'{os.path.dirname(mixstereo_tf.__file__)}')
  assert np.isfinite(out['disparity_left']).all()


if __name__ == '__main__':
  app.run(main)
