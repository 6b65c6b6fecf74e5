"""TensorFlow imported without its C++ start-up chatter, for the tools and `unmix()`.

The pre-initialisation INFO lines (oneDNN notice, "Could not find cuda drivers", CPU
feature notes) printed while TensorFlow is imported are dropped, and every other line
printed then is passed on unchanged. On a machine without a CUDA driver, TensorFlow's C++
log level is also raised to errors-off, so no "failed call to cuInit" error is printed when
the first op runs; with a driver present only INFO and WARNING lines are hidden (level 2).
An explicit TF_CPP_MIN_LOG_LEVEL in the environment always wins, and a TensorFlow already
imported (by the caller) is left as it is. This package's own messages go through absl
logging and are never filtered.
"""

import ctypes
import os
import sys
import tempfile

# Start-up lines of TensorFlow's C++ runtime that are information, not problems.
_NOISE = ('WARNING: All log messages before absl::InitializeLog() is called',
          'To enable the following instructions:')

# Pre-initialisation warnings and errors of a CUDA build that are no problem: duplicate
# factory registrations (cuDNN, cuFFT, cuBLAS), no TensorRT, no driver (the device line,
# `cli/device.py`, says what runs instead).
_CUDA_NOISE = ('Unable to register cu', 'computation placer already registered',
               'Could not find TensorRT', 'Could not find cuda drivers')


def _has_cuda_driver() -> bool:
  try:
    ctypes.CDLL('libcuda.so.1')
  except OSError:
    return False
  return True


def is_noise(line: str) -> bool:
  """Whether a line printed while TensorFlow is imported is start-up chatter."""
  # Pre-initialisation lines look like 'I0000 00:00:... file.cc:123] text' (W0000, E0000).
  if line.startswith(('W0000 ', 'E0000 ')):
    return any(text in line for text in _CUDA_NOISE)
  return line.startswith('I0000 ') or line.startswith(_NOISE)


def import_tensorflow() -> None:
  """Imports TensorFlow with its start-up chatter filtered out of standard error (module
  docstring); nothing where it is already imported."""
  if 'tensorflow' in sys.modules:
    return
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
                               if not is_noise(line)))
      sys.stderr.flush()
