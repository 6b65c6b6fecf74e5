r"""Evaluates a trained model (or the classical baseline) on a benchmark.

  python -m mixstereo_tf.evaluate --protocol=middlebury --data_dir=data/middlebury \
      --checkpoint=runs/middlebury_anaglyph --output_csv=results/mb.csv

Protocols: kitti2015 / kitti2012 (stereo training sets), middlebury (scene folders), eigen
(KITTI raw root + the Eigen test list; depth from the left disparity) and sample (the
embedded held-out set, nothing to download). The mixture of each pair is synthesised from
its true views; the tables print the paper's numbers beside ours
(mixstereo_tf/evaluation/report.py).
"""

from absl import app
from absl import flags
from absl import logging

from mixstereo_tf import mixtures
from mixstereo_tf import unmixing
from mixstereo_tf.data import sources
from mixstereo_tf.evaluation import report
from mixstereo_tf.evaluation import runner

FLAGS = flags.FLAGS

flags.DEFINE_enum('protocol', None, runner.PROTOCOLS, 'Benchmark to evaluate on.',
                  required=True)
flags.DEFINE_string('data_dir', None, 'Dataset root: KITTI stereo (holding training/), '
                    'Middlebury scenes, or the KITTI raw root for eigen; unused by sample.')
flags.DEFINE_enum('mixture', None, mixtures.MIXTURE_NAMES,
                  "Mixture operator (default: the model's; must match it); required for "
                  '--method=classical.')
flags.DEFINE_string('checkpoint', None, 'Training run directory or checkpoint prefix.')
flags.DEFINE_string('saved_model', None, 'SavedModel from mixstereo_tf.export.')
flags.DEFINE_enum('method', 'model', runner.METHODS,
                  'model: a trained network; classical: the training-free baseline; oracle: '
                  'the stereo module of --checkpoint (a stereo_only run) on the clean pairs.')
flags.DEFINE_boolean('restore_colour', None, "Rebuild the views' exact channels from the "
                     'mixture and disparities (paper 4.2); default: on for channel anaglyphs.')
flags.DEFINE_alias('restore_colors', 'restore_colour')
flags.DEFINE_string('output_csv', None, 'Write the per-image rows here.')
flags.DEFINE_string('output_markdown', None, 'Write the tables as Markdown here.')
flags.DEFINE_boolean('allow_partial', False, 'Allow a kitti2015 average over fewer than its '
                     '200 images (the table is marked partial).')
flags.DEFINE_integer('max_images', None, 'Evaluate only the first N pairs.', lower_bound=1)
flags.DEFINE_string('eigen_list', runner.DEFAULT_EIGEN_LIST, 'Eigen test split list.')
flags.DEFINE_list('middlebury_scale', [], 'Ground-truth disparity scale per Middlebury scene '
                  '(--protocol=middlebury) as scene:scale items, e.g. tsukuba:16,venus:8.')
flags.DEFINE_integer('sample_scenes', None, 'Procedural held-out scenes for --protocol=sample '
                     '(default: all of them).', lower_bound=1)


def _make_predictor() -> unmixing.Unmixing:
  """The flags' predictor; for 'oracle' a pair predictor (mixture: the flag or the run's)."""
  if FLAGS.method != 'oracle':
    return unmixing.make_unmixing(FLAGS.method, FLAGS.saved_model, FLAGS.checkpoint,
                                  FLAGS.mixture, FLAGS.restore_colour)
  if not FLAGS.checkpoint or FLAGS.saved_model or FLAGS.restore_colour is not None:
    raise ValueError('--method=oracle needs --checkpoint (a stereo_only training run) and '
                     'takes neither --saved_model nor --restore_colour.')
  from mixstereo_tf import inference  # pylint: disable=g-import-not-at-top (TF start-up)
  model, run_info = inference.load_run(FLAGS.checkpoint)
  config = run_info.model_config
  return unmixing.Unmixing(runner.stereo_pair_predictor(model, config.size_multiple),
                           FLAGS.mixture or run_info.mixture, config.max_disparity)


def main(argv):
  if len(argv) > 1:
    raise app.UsageError(f'Unexpected arguments: {argv[1:]}')
  try:
    if FLAGS.method == 'classical' and FLAGS.restore_colour is not None:
      raise ValueError('--restore_colour applies to --method=model only.')
    if FLAGS.protocol != 'sample' and not FLAGS.data_dir:
      raise ValueError(f'--protocol={FLAGS.protocol} needs --data_dir.')
    setup = _make_predictor()
    config = runner.EvalConfig(
        protocol=FLAGS.protocol, mixture=setup.mixture, data_dir=FLAGS.data_dir,
        method=FLAGS.method, allow_partial=FLAGS.allow_partial, max_images=FLAGS.max_images,
        eigen_list=FLAGS.eigen_list, restore_colour=FLAGS.restore_colour,
        max_disparity=int(setup.default_max_disparity), sample_scenes=FLAGS.sample_scenes,
        middlebury_scales=sources.parse_scene_scales(FLAGS.middlebury_scale))

    def progress(index, total, row):
      logging.info('[%d/%d] %s: %.3f s', index + 1, total, row['name'], row['seconds'])

    result = runner.evaluate(config, setup.fn, progress)
    text = report.format_report(result)
  except ValueError as e:
    raise app.UsageError(str(e)) from None
  print(text, end='')
  if FLAGS.output_csv:
    report.write_csv(FLAGS.output_csv, result.rows)
  if FLAGS.output_markdown:
    report.write_markdown(FLAGS.output_markdown, result)


def run():
  """Console-script entry point (`mixstereo-eval`)."""
  app.run(main)


if __name__ == '__main__':
  run()
