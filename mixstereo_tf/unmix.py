r"""Separates mixture images or videos into two views and a disparity map.

  python -m mixstereo_tf.unmix --saved_model=exports/demo --input=photos/ \
      --output_dir=out --layout=sbs

Inputs: an image, a video (.mp4 .m4v .avi .mov .mkv .webm), a folder of them or a glob pattern.
An input that cannot be read, unmixed or written is reported with the reason and skipped;
the others still run, and the exit status is non-zero if any failed. A progress bar with
the measured frames per second is drawn on stderr when it is a terminal (logged otherwise).
Videos keep their container, frame rate, timestamps, audio and subtitles (copied;
portrait videos are turned upright, other rotations kept), are
unmixed shot by shot with the previous frame's disparity as a prior (--notemporal: frame by
frame), and are written resumably: after Ctrl-C or a crash, the same command continues
from the last finished segment. Outputs are described in mixstereo_tf/cli/unmix_files.py.
"""

from mixstereo_tf.cli import startup  # pylint: disable=unused-import (first: quiet TF)

import sys

from absl import flags
from absl import logging

from mixstereo_tf.cli import device
from mixstereo_tf.cli import flag_errors
from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.cli import input_failures
from mixstereo_tf.cli import unmix_files
from mixstereo_tf.unmixing import predictors

FLAGS = flags.FLAGS

cli_flags.define_unmix_predictor()
cli_flags.define_input()
cli_flags.define_output_dir()
cli_flags.require_unless_listing('input', 'output_dir')
cli_flags.define_output_options()


def main(argv):
  flag_errors.refuse_arguments(argv, 'input')
  cli_flags.exit_if_listing()
  device.log_line()
  try:
    config = cli_flags.unmix_predictor_config()
    unmixer = predictors.build_unmixer(config)
    report = unmix_files.unmix_inputs(
        unmixer, FLAGS.input, FLAGS.output_dir,
        cli_flags.output_options(config),
        progress_stream=sys.stderr)
  except ValueError as e:
    raise flag_errors.usage_error(e) from None
  except input_failures.OutputFull as e:
    sys.exit(f'error: {e}')
  except KeyboardInterrupt:
    logging.error('Interrupted: finished inputs are kept, and a video continues from its '
                  'last finished segment when the same command is run again.')
    sys.exit(130)
  logging.info('%d input(s) done, %d failed; %d frame(s) in %.2f s: %.2f frames/s '
               '(unmixing alone %.2f frames/s).', report.processed, len(report.failures),
               report.frames, report.seconds, report.frames_per_second,
               report.frames / report.unmix_seconds if report.unmix_seconds else 0.0)
  for path, reason in report.failures:
    logging.warning('failed: %s (%s)', path, reason)
  message = input_failures.failure_message(report)
  if message:
    sys.exit(message)


def run():
  """Console-script entry point (`mixstereo-unmix`)."""
  cli_flags.run_binary(main, __doc__)


if __name__ == '__main__':
  run()
