"""Quiet TensorFlow start-up for the command-line tools.

Importing this module (first, before anything that imports TensorFlow) imports TensorFlow
with its C++ start-up chatter filtered out: the pre-initialisation INFO lines (oneDNN
notice, "Could not find cuda drivers", CPU feature notes) are dropped, and every other line
printed during the import is passed on unchanged. On a machine without a CUDA driver,
TensorFlow's C++ log level is also raised to errors-off, so no "failed call to cuInit"
error is printed when the first op runs; with a driver present only INFO and WARNING lines
are hidden (level 2). An explicit TF_CPP_MIN_LOG_LEVEL in the environment always wins.
This package's own messages go through absl logging and are never filtered. A run from a
source checkout that imports another copy of the package (a stale installed one) is warned
about: its results would not be the checkout's.
"""

import ctypes
import logging
import os
import sys
import tempfile

# Start-up lines of TensorFlow's C++ runtime that are information, not problems.
_NOISE = ('WARNING: All log messages before absl::InitializeLog() is called',
          'To enable the following instructions:')


def _has_cuda_driver() -> bool:
  try:
    ctypes.CDLL('libcuda.so.1')
  except OSError:
    return False
  return True


# Pre-initialisation warnings and errors of a CUDA build that are no problem: duplicate
# factory registrations (cuDNN, cuFFT, cuBLAS), no TensorRT, no driver (the device line,
# `cli/device.py`, says what runs instead).
_CUDA_NOISE = ('Unable to register cu', 'computation placer already registered',
               'Could not find TensorRT', 'Could not find cuda drivers')


def _is_noise(line: str) -> bool:
  # Pre-initialisation lines look like 'I0000 00:00:... file.cc:123] text' (W0000, E0000).
  if line.startswith(('W0000 ', 'E0000 ')):
    return any(text in line for text in _CUDA_NOISE)
  return line.startswith('I0000 ') or line.startswith(_NOISE)


def _import_tensorflow_quietly() -> None:
  os.environ.setdefault('TF_CPP_MIN_LOG_LEVEL', '2' if _has_cuda_driver() else '3')
  sys.stderr.flush()
  saved = os.dup(2)
  with tempfile.TemporaryFile(mode='w+b') as captured:
    os.dup2(captured.fileno(), 2)
    try:
      import tensorflow  # pylint: disable=g-import-not-at-top,unused-import
    finally:
      sys.stderr.flush()
      os.dup2(saved, 2)
      os.close(saved)
      captured.seek(0)
      text = captured.read().decode('utf-8', 'replace')
      sys.stderr.write(''.join(line for line in text.splitlines(keepends=True)
                               if not _is_noise(line)))
      sys.stderr.flush()


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
_import_tensorflow_quietly()
