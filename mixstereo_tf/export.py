r"""Exports a trained run as a SavedModel that unmixes uint8 images of any size.

  python -m mixstereo_tf.export --checkpoint=runs/demo --export_dir=exports/demo

Signatures: `serving_default` (image -> left, right, disparity, disparity_right) and
`metadata` (mixture, training crop, architecture); see mixstereo_tf/serving.py.
"""

from mixstereo_tf.cli import startup  # pylint: disable=unused-import (first: quiet TF)

from absl import app  # pylint: disable=g-bad-import-order
from absl import flags
from absl import logging

from mixstereo_tf import inference
from mixstereo_tf import runs
from mixstereo_tf import serving
from mixstereo_tf.cli import flags as cli_flags

FLAGS = flags.FLAGS

cli_flags.define_checkpoint()
flags.DEFINE_string('export_dir', None, 'Where to write the SavedModel (must be new).',
                    required=True)
flags.mark_flag_as_required('checkpoint')


def main(argv):
  del argv
  try:
    model, run_info = runs.load_run(FLAGS.checkpoint)
    serving.export_saved_model(inference.serving_function(model), model.variables, run_info,
                               FLAGS.export_dir)
  except ValueError as e:
    raise cli_flags.usage_error(e) from None
  logging.info('Exported the %s model to %s.', run_info.mixture, FLAGS.export_dir)


def run():
  """Console-script entry point (`mixstereo-export`)."""
  app.run(main)


if __name__ == '__main__':
  run()
