"""Quiet TensorFlow start-up for the command-line tools.

Importing this module (first, before anything that imports TensorFlow) imports TensorFlow
with its C++ start-up chatter filtered out (`core.quiet_import`). A run from a source
checkout that imports another copy of the package (a stale installed one) is warned about:
its results would not be the checkout's.
"""

import logging
import os
import sys

from mixstereo_tf.core import quiet_import


def shadowing_warning(directory: str) -> str:
  """A warning when `directory` holds a mixstereo_tf source tree that is not the imported
  package (e.g. a stale non-editable install shadows the checkout); '' otherwise."""
  local = os.path.join(directory, 'mixstereo_tf')
  imported = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
  if (not os.path.isfile(os.path.join(local, '__init__.py')) or
      os.path.realpath(local) == os.path.realpath(imported)):
    return ''
  return (f'WARNING: running the mixstereo_tf installed at {imported}, not the source tree '
          f'{local}; reinstall it (pip install -e .) or set PYTHONPATH={directory}.\n')


class _DropNotes(logging.Filter):
  """Drops third-party start-up notes logged on the root logger that are no problem:
  Apache Beam's 'apitools not found' (its Google Cloud clients, which a local run does not
  use), printed even for --help."""

  def filter(self, record: logging.LogRecord) -> bool:
    return not str(record.msg).startswith('apitools not found')


sys.stderr.write(shadowing_warning(os.getcwd()))
logging.getLogger().addFilter(_DropNotes())
quiet_import.import_tensorflow()
