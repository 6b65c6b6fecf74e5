r"""Evaluates a trained model (or the classical baseline) on a benchmark.

  python -m mixstereo_tf.evaluate --protocol=middlebury --data_dir=data/middlebury \
      --checkpoint=runs/middlebury_anaglyph --output_csv=results/mb.csv

Protocols (mixstereo_tf/evaluation/protocols/): kitti2015 / kitti2012 (stereo training
sets), middlebury (scene folders), eigen (KITTI raw root + the Eigen test list; depth from
the left disparity) and sample (the embedded held-out set, nothing to download). The
mixture of each pair is synthesised from its true views; the tables print the paper's
numbers beside ours. Each method searches its own fixed range (--disparity_range=network:
a model sees the image as it is, as in the paper) unless --disparity_range is given.
"""

import dataclasses
import sys

from mixstereo_tf.cli import startup  # pylint: disable=unused-import (first: quiet TF)

from absl import flags
from absl import logging

from mixstereo_tf.cli import device
from mixstereo_tf.cli import flag_errors
from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.core import mixtures
from mixstereo_tf.evaluation import protocols
from mixstereo_tf.evaluation import report
from mixstereo_tf.evaluation import results
from mixstereo_tf.evaluation import runner
from mixstereo_tf.unmixing import disparity_range
from mixstereo_tf.unmixing import predictors

FLAGS = flags.FLAGS

cli_flags.define_predictor()
cli_flags.define_data()
flags.DEFINE_enum('protocol', None, protocols.names(), 'Benchmark to evaluate on.')
cli_flags.require_unless_listing('protocol')
flags.DEFINE_enum('encoding', None, mixtures.MIXTURE_NAMES,
                  'The mixture the pairs are mixed with (default: --mixture, or with '
                  "--mixture=auto the model's); the predictor sees only the mixed image.")
flags.DEFINE_string('output_csv', None, 'Write the per-image rows here.')
flags.DEFINE_string('output_markdown', None, 'Write the tables as Markdown here.')
flags.DEFINE_boolean('allow_partial', False, 'Allow an average over fewer images than the '
                     "protocol's full count (kitti2015: 200); the table is marked partial.")
flags.DEFINE_integer('max_images', None, 'Evaluate only the first N pairs.', lower_bound=1)
flags.DEFINE_string('eigen_list', None, 'Eigen test split list (default: the list shipped '
                    'with the package, data_lists/kitti/eigen_test_files.txt).')
flags.DEFINE_integer('heldout_scenes', None, 'Procedural held-out scenes for '
                     '--protocol=sample (default: all of them).', lower_bound=1)
flags.DEFINE_list('depth_caps', [f'{c:g}' for c in cli_flags.defaults(results.EvalConfig)[
    'depth_caps']], 'Depth caps in metres of --protocol=eigen, one table each (the paper\'s '
                  'comparison rows are at 50 m and 80 m; experiments/README.md).')

_RENAMED = {'EvalConfig.split_list': 'eigen_list', 'DataConfig.split_list': 'eigen_list'}


def _depth_caps():
  try:
    return tuple(float(cap) for cap in FLAGS.depth_caps)
  except ValueError:
    raise ValueError(f'--depth_caps must be numbers, got {FLAGS.depth_caps}.') from None


def main(argv):
  flag_errors.refuse_arguments(argv)
  cli_flags.exit_if_listing()
  device.log_line()
  try:
    predictor = cli_flags.predictor_config()
    if not FLAGS['disparity_range'].present:
      # The paper's protocols: a network sees the image as it is, the classical method
      # searches its own fixed range.
      predictor = dataclasses.replace(predictor, disparity_range=disparity_range.NETWORK)
    unmixer = predictors.build_unmixer(predictor)
    encoding = FLAGS.encoding or unmixer.mixture
    if encoding == 'auto':
      raise ValueError('--mixture=auto needs --encoding: the mixture the pairs are mixed '
                       'with.')
    config = results.EvalConfig(
        protocol=FLAGS.protocol, mixture=encoding, data_dir=FLAGS.data_dir,
        allow_partial=FLAGS.allow_partial, max_images=FLAGS.max_images,
        split_list=FLAGS.eigen_list, max_disparity=int(unmixer.max_disparity),
        heldout_scenes=FLAGS.heldout_scenes,
        middlebury_scales=cli_flags.middlebury_scales(),
        depth_caps=_depth_caps())

    def progress(index, total, row):
      logging.info('[%d/%d] %s: %.3f s', index + 1, total, row['name'], row['seconds'])

    for name in ('output_csv', 'output_markdown'):  # Before hours of evaluation.
      if FLAGS[name].value:
        report.prepare_path(FLAGS[name].value, f'--{name}')
    result = runner.evaluate(config, unmixer, progress)
    text = report.format_report(result)
  except ValueError as e:
    raise flag_errors.usage_error(e, _RENAMED) from None
  print(text, end='')
  if FLAGS.output_csv:
    report.write_csv(FLAGS.output_csv, result.rows)
  if FLAGS.output_markdown:
    report.write_markdown(FLAGS.output_markdown, result, report.provenance(
        sys.argv, predictors.weights_identity(predictor)))


def run():
  """Console-script entry point (`mixstereo-eval`)."""
  cli_flags.run_binary(main, __doc__)


if __name__ == '__main__':
  run()
