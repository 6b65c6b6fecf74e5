r"""Exports a trained run as a SavedModel that unmixes uint8 images of any size.

  python -m mixstereo_tf.export --model_dir=runs/demo --export_dir=exports/demo

Signatures: `serving_default` (image -> left, right, disparity, disparity_right) and
`metadata` (mixture, training crop, architecture); see mixstereo_tf/serving.py.
"""

from absl import app
from absl import flags
from absl import logging

from mixstereo_tf import inference
from mixstereo_tf import serving

FLAGS = flags.FLAGS

flags.DEFINE_string('model_dir', None, 'Training run directory (config.json + checkpoints).',
                    required=True)
flags.DEFINE_string('export_dir', None, 'Where to write the SavedModel (must be new).',
                    required=True)
flags.DEFINE_string('checkpoint', None, 'Checkpoint prefix to export (default: the newest '
                    'in --model_dir).')


def main(argv):
  del argv
  try:
    model, run_info = inference.load_run(FLAGS.model_dir, FLAGS.checkpoint)
    serving.export_saved_model(model, run_info, FLAGS.export_dir)
  except ValueError as e:
    raise app.UsageError(str(e)) from None
  logging.info('Exported the %s model to %s.', run_info.mixture, FLAGS.export_dir)


def run():
  """Console-script entry point (`mixstereo-export`)."""
  app.run(main)


if __name__ == '__main__':
  run()
