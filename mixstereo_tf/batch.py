r"""Unmixes an archive of mixture images and videos on Apache Beam (`pip install '.[beam]'`).

  python -m mixstereo_tf.batch --input='scans/*.jpg' --output_dir=out --method=classical \
      --mixture=auto --direct_num_workers=2 --direct_running_mode=multi_processing

Inputs: `--input` (an image, folder, glob pattern or video, as for `mixstereo-unmix`) or
`--input_list` (a text file, one path per line, on any file system Beam reads). Every
input gets exactly `mixstereo-unmix`'s outputs with the same flags; the output folder also
gets `batch_summary.csv` (per input: status, encoding, range searched, seconds) and
`batch_dead_letters.csv` (inputs that failed, with the reason; the others still run).
Running the same command again skips the inputs whose outputs are complete. Arguments
that are not this tool's flags are Apache Beam pipeline options (`--runner=...`). The exit
status is non-zero if any input failed. Details: mixstereo_tf/cli/beam_batch.py.
"""

from mixstereo_tf.cli import startup  # pylint: disable=unused-import (first: quiet TF)

import logging as std_logging
import os
import sys

from absl import flags
from absl import logging

from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.cli import device
from mixstereo_tf.cli import flag_errors
from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.cli import input_failures
from mixstereo_tf.cli import input_listing
from mixstereo_tf.cli import worker_output
from mixstereo_tf.unmixing import predictors

try:
  from mixstereo_tf.cli import beam_batch  # pylint: disable=g-import-not-at-top
except ModuleNotFoundError as e:
  if not (e.name or '').startswith('apache_beam'):
    raise
  sys.exit("mixstereo-batch needs Apache Beam: pip install 'mixstereo_tf[beam]'")

FLAGS = flags.FLAGS

cli_flags.define_unmix_predictor()
cli_flags.define_input()
flags.DEFINE_string('input_list', None, 'A text file of input paths, one per line (instead '
                    'of --input; local or on any file system Apache Beam reads; relative '
                    'paths are read from the folder the command runs in, not the list\'s).')
cli_flags.define_output_dir()
cli_flags.require_unless_listing('output_dir')
cli_flags.define_output_options()
flags.register_multi_flags_validator(
    ['input', 'input_list', 'pretrained'],
    lambda values: ((values['input'] is None) != (values['input_list'] is None) or
                    values['pretrained'] == pretrained.LIST),
    message='Give exactly one of --input and --input_list.')


def main(argv):
  flag_errors.refuse_arguments(argv, 'input', passed_on=True)  # Others: Beam's options.
  cli_flags.exit_if_listing()
  device.log_line()
  try:
    config = cli_flags.unmix_predictor_config()
    predictors.build_unmixer(config)  # A bad predictor flag fails here, not on workers.
    items = beam_batch.list_inputs(FLAGS.input, FLAGS.input_list, FLAGS.output_dir)
    options = cli_flags.output_options(config)
    pipeline_options = beam_batch.pipeline_options(argv[1:])
    input_listing.prepare_output_dir(items, FLAGS.output_dir)
  except ValueError as e:
    raise flag_errors.usage_error(e) from None
  logging.info('%d input(s) to %s.', len(items), FLAGS.output_dir)
  std_logging.getLogger('apache_beam').setLevel(std_logging.WARNING)  # Runner chatter.
  # The local runner's workers in other processes write their log to this stderr, and its
  # job service relays each line again: relayed lines are dropped.
  std_logging.getLogger('apache_beam.runners.portability.local_job_service').setLevel(
      std_logging.CRITICAL)
  for name in ('apache_beam.runners.common', 'apache_beam.runners.worker.bundle_processor'):
    std_logging.getLogger(name).addFilter(beam_batch.DropInterrupts())  # Ctrl-C's traceback.
  try:
    with worker_output.filtered_stderr():  # Multi-processing workers' notes and Ctrl-C.
      counts = beam_batch.run(items, config, FLAGS.output_dir, options, pipeline_options)
  except (KeyboardInterrupt, RuntimeError) as e:  # Beam re-raises Ctrl-C as RuntimeError.
    if 'OutputFull' in str(e) or isinstance(e, input_failures.OutputFull):
      sys.exit(f'error: {str(e).split("OutputFull: ", 1)[-1]}')
    if not isinstance(e, KeyboardInterrupt) and 'KeyboardInterrupt' not in str(e):
      raise
    logging.error('Interrupted: the inputs finished so far are kept; run the same command '
                  'to continue (finished inputs are skipped).')
    sys.exit(130)
  logging.info('%(done)d input(s) done, %(skipped)d skipped (complete before this run), '
               '%(failed)d failed. Summary: %(summary)s', dict(
                   counts, summary=os.path.join(FLAGS.output_dir, beam_batch.SUMMARY)))
  if counts['failed']:
    sys.exit(f'error: {counts["failed"]} of {len(items)} input(s) failed: see '
             f'{os.path.join(FLAGS.output_dir, beam_batch.DEAD_LETTERS)}')


def _parse_known_flags(argv):
  """Parses this tool's flags; the rest of argv (after the program) is for Beam."""
  try:
    return FLAGS(argv, known_only=True)
  except flags.Error as e:
    sys.exit(f'FATAL Flags parsing error: {e}\nPass --helpshort or --helpfull to see help '
             'on flags.')


def run():
  """Console-script entry point (`mixstereo-batch`)."""
  cli_flags.run_binary(main, __doc__, flags_parser=_parse_known_flags)


if __name__ == '__main__':
  run()
