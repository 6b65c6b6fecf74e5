r"""Exports a trained model: a SavedModel that unmixes uint8 images of any size, or a
folder in the package's pretrained format.

  python -m mixstereo_tf.export --checkpoint=runs/demo --export_dir=exports/demo
  python -m mixstereo_tf.export --pretrained=models/demo --export_dir=exports/demo
  python -m mixstereo_tf.export --checkpoint=runs/pretrained_anaglyph --as_pretrained \
      --export_dir=mixstereo_tf/artifacts/pretrained/anaglyph --recipe='...' --results='...'

Signatures: `serving_default` (image -> left, right, disparity, disparity_right) and
`metadata` (mixture, training crop, architecture); see mixstereo_tf/artifacts/serving.py.
Without --checkpoint, `--pretrained=FOLDER` exports a joint network in the pretrained
format (written by --as_pretrained). The shipped models have no SavedModel: each runs a
classical stage (census or ZNCC costs, SGM, restoration) that is not a TensorFlow graph.
"""

from mixstereo_tf.cli import startup  # pylint: disable=unused-import (first: quiet TF)

from absl import flags
from absl import logging

from mixstereo_tf.artifacts import graphs
from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.artifacts import runs
from mixstereo_tf.artifacts import serving
from mixstereo_tf.cli import device
from mixstereo_tf.cli import flag_errors
from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.unmixing import unmixer

FLAGS = flags.FLAGS

cli_flags.define_checkpoint()
cli_flags.define_mixture()
cli_flags.define_pretrained()
flags.DEFINE_string('export_dir', None, 'Where to write the SavedModel (must be new).')
cli_flags.require_unless_listing('export_dir')
flags.DEFINE_boolean('as_pretrained', False, 'Write --checkpoint in the pretrained format '
                     '(mixstereo_tf/artifacts/pretrained/NAME: float16 weights and '
                     'info.json) instead of a SavedModel.')
flags.DEFINE_string('recipe', '', 'With --as_pretrained: the command that retrains it.')
flags.DEFINE_string('results', '', 'With --as_pretrained: its held-out numbers.')


# Why a kind of the pretrained format is no TensorFlow graph alone.
_NOT_A_GRAPH = {
    'refiner': "a network refining the classical method's result",
    'features': 'learned descriptors whose costs a classical SGM aggregates',
    'echo_features': 'learned echo descriptors whose costs a classical SGM aggregates'}


def _model_and_info():
  """(model, RunInfo) of --checkpoint, else of the shipped model."""
  if FLAGS.checkpoint:
    if FLAGS.pretrained:
      raise ValueError('Give --checkpoint or --pretrained, not both.')
    return runs.load_run(FLAGS.checkpoint)
  if not FLAGS.pretrained:
    raise ValueError('Give --checkpoint (a training run) or --pretrained (a joint network '
                     'in the pretrained format): the shipped models have no SavedModel.')
  entry = pretrained.choose(FLAGS.pretrained, FLAGS.mixture)
  if entry.kind != 'joint':
    raise ValueError(f'--pretrained={FLAGS.pretrained}: {entry.name!r} is a {entry.kind!r} '
                     f'model, {_NOT_A_GRAPH.get(entry.kind, "not a joint network")}, which a '
                     'SavedModel cannot hold; use it through mixstereo-unmix / mixstereo-eval '
                     '(or mixstereo_tf.unmix).')
  model = pretrained.load_model(entry)
  return model, runs.RunInfo(entry.mixture, entry.crop[0], entry.crop[1], model.model_config)


def main(argv):
  flag_errors.refuse_arguments(argv)
  cli_flags.exit_if_listing()
  device.log_line()
  try:
    if FLAGS.as_pretrained:
      if not FLAGS.checkpoint:
        raise ValueError('--as_pretrained needs --checkpoint (the run to package).')
      entry = pretrained.from_run(FLAGS.checkpoint, FLAGS.export_dir, FLAGS.recipe,
                                  FLAGS.results)
      logging.info('Wrote the %s %s model to %s.', entry.kind, entry.mixture, entry.folder)
      return
    model, run_info = _model_and_info()
    unmixer.warn_if_untrained(run_info, FLAGS.checkpoint or FLAGS.pretrained)
    serving.export_saved_model(graphs.serving_function(model), model.variables, run_info,
                               FLAGS.export_dir)
  except ValueError as e:
    raise flag_errors.usage_error(e) from None
  logging.info('Exported the %s model to %s.', run_info.mixture, FLAGS.export_dir)


def run():
  """Console-script entry point (`mixstereo-export`)."""
  cli_flags.run_binary(main, __doc__)


if __name__ == '__main__':
  run()
