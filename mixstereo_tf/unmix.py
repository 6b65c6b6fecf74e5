r"""Separates mixture images or videos into two views and a disparity map.

  python -m mixstereo_tf.unmix --saved_model=exports/demo --input=photos/ \
      --output_dir=out --layout=sbs

Inputs: an image, a folder of images, a glob pattern or a video (.mp4 .avi .mov .mkv).
An input that cannot be read, unmixed or written is reported with the reason and skipped;
the others still run, and the exit status is non-zero if any failed. A progress bar with
the measured frames per second is drawn on stderr when it is a terminal (logged otherwise).
Outputs are described in mixstereo_tf/unmixing.py.
"""

import sys

from absl import app
from absl import flags
from absl import logging

from mixstereo_tf import media
from mixstereo_tf import mixtures
from mixstereo_tf import unmixing

FLAGS = flags.FLAGS

flags.DEFINE_string('saved_model', None, 'SavedModel from mixstereo_tf.export.')
flags.DEFINE_string('checkpoint', None, 'Training run directory or checkpoint prefix.')
flags.DEFINE_enum('method', 'model', unmixing.METHODS,
                  'model: the trained network; classical: the training-free baseline.')
flags.DEFINE_enum('mixture', None, mixtures.MIXTURE_NAMES,
                  "The inputs' mixture operator; must match the model's (default: the "
                  "model's); required for --method=classical.")
flags.DEFINE_string('input', None, 'Image, folder, glob pattern or video.', required=True)
flags.DEFINE_string('output_dir', None, 'Where to write the results.', required=True)
flags.DEFINE_enum('layout', 'separate', media.LAYOUTS,
                  'Views as two files (separate), side by side (sbs), side by side at '
                  'half width (sbs_half) or top-bottom (tb).')
flags.DEFINE_boolean('restore_colour', None, 'Rebuild the views\' exact channels from the '
                     'mixture and disparities (paper 4.2); default: on for channel anaglyphs.')
flags.DEFINE_alias('restore_colors', 'restore_colour')
flags.DEFINE_float('max_display_disparity', None, 'Disparity (pixels) shown brightest in '
                   'the colour maps, fixed for the run (default: the model\'s max_disparity).')


def main(argv):
  del argv
  try:
    if FLAGS.method == 'classical' and FLAGS.restore_colour is not None:
      raise ValueError('--restore_colour applies to --method=model only.')
    setup = unmixing.make_unmixing(FLAGS.method, FLAGS.saved_model, FLAGS.checkpoint,
                                   FLAGS.mixture, FLAGS.restore_colour)
    report = unmixing.unmix_inputs(setup, FLAGS.input, FLAGS.output_dir, FLAGS.layout,
                                   FLAGS.max_display_disparity, progress_stream=sys.stderr)
  except ValueError as e:
    raise app.UsageError(str(e)) from None
  logging.info('%d input(s) done, %d failed; %d frame(s) in %.2f s: %.2f frames/s '
               '(unmixing alone %.2f frames/s).', report.processed, len(report.failures),
               report.frames, report.seconds, report.frames_per_second,
               report.frames / report.unmix_seconds if report.unmix_seconds else 0.0)
  for path, reason in report.failures:
    logging.warning('failed: %s (%s)', path, reason)
  message = unmixing.failure_message(report)
  if message:
    sys.exit(message)


def run():
  """Console-script entry point (`mixstereo-unmix`)."""
  app.run(main)


if __name__ == '__main__':
  run()
