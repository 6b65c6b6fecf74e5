r"""Writes a few pairs of the embedded `sample` source as PNGs, to see what training sees.

  python -m mixstereo_tf.cli.preview --output_dir=/tmp/sample_preview \
      --mixture=anaglyph --num=4 [--split=heldout] [--height=128 --width=256]

For each pair: <name>_left.png, _right.png, _mixture.png (RGB) and _disparity_left.png,
_disparity_right.png (grey, 255 = --max_disparity, black = unknown).
"""

from mixstereo_tf.cli import startup  # pylint: disable=unused-import (first: quiet TF)

import os  # pylint: disable=g-bad-import-order

from absl import app
from absl import flags
import cv2

from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.data import sample

cli_flags.define_output_dir()
flags.mark_flag_as_required('output_dir')
cli_flags.define_mixture()
cli_flags.define_max_disparity()
FLAGS = flags.FLAGS
_NUM = flags.DEFINE_integer('num', 4, 'Number of pairs to write.', lower_bound=1)
_SPLIT = flags.DEFINE_enum('split', 'train', sample.SPLITS,
                           'heldout also includes the Motorcycle pair (last).')
_HEIGHT = flags.DEFINE_integer('height', None, 'Scene height (default: the source default).')
_WIDTH = flags.DEFINE_integer('width', None, 'Scene width (default: the source default).')


def main(argv):
  del argv
  samples = sample.sample_records(_SPLIT.value, max_disparity=FLAGS.max_disparity,
                                  height=_HEIGHT.value, width=_WIDTH.value)
  if _SPLIT.value == 'heldout':  # Show the real pair even when --num is small.
    samples = samples[:max(_NUM.value - 1, 0)] + samples[-1:]
  os.makedirs(FLAGS.output_dir, exist_ok=True)
  for record in samples[:_NUM.value]:
    images = sample.preview_images(record, (FLAGS.mixture or 'anaglyph'), FLAGS.max_disparity)
    for key, image in images.items():
      path = os.path.join(FLAGS.output_dir, f'{record.name}_{key}.png')
      if image.ndim == 3:
        image = cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
      if not cv2.imwrite(path, image):
        raise ValueError(f'Could not write {path} (--output_dir).')
    print(f'Wrote {record.name} to {FLAGS.output_dir}')


if __name__ == '__main__':
  app.run(main)
