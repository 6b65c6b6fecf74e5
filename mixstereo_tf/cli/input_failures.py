"""What an input's failure means for a run of the tools (`mixstereo-unmix`, the batch
pipeline): its one-line reason, which errors are the input's own (`INPUT_ERRORS`: the run
goes on without it) and which end the run (`OutputFull`: no later input could be written
either), and the run's closing error (`failure_message`)."""

import errno
import os
import shutil
from typing import Optional

import cv2
from PIL import Image
import tensorflow as tf

from mixstereo_tf.cli import flag_errors
from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.video import streams


def failure_message(report) -> Optional[str]:
  """The error that ends the run with a non-zero status: any input of `report`
  (`unmix_files.UnmixReport`) failed."""
  if not report.failures:
    return None
  paths = ', '.join(path for path, _ in report.failures[:5])
  more = ', ...' if len(report.failures) > 5 else ''
  return (f'error: {len(report.failures)} of {report.processed + len(report.failures)} '
          f'input(s) failed: {paths}{more}')


def reason(error: Exception) -> str:
  """A one-line reason for a failed input (TensorFlow messages can span many lines),
  naming the predictor flags (`--mixture`) instead of PredictorConfig fields, and the
  package's own error classes by their built-in base (`ValueError`)."""
  message = error.message if isinstance(error, tf.errors.OpError) else str(error)
  lines = message.strip().splitlines()
  line = flag_errors.flag_names(lines[0], known=cli_flags.PREDICTOR_FLAGS) if lines else ''
  kind = type(error)
  while kind.__module__.startswith('mixstereo_tf.'):  # The package's own: by their base.
    kind = kind.__base__
  return f'{kind.__name__}: {line}'


# What one input may raise without stopping the others: unreadable or malformed files (ValueError,
# cv2.error, FFmpeg's errors), failures inside TensorFlow (e.g. an image too large for memory),
# NumPy / numba allocations too large (MemoryError) and file-system errors while reading or writing.
INPUT_ERRORS = (ValueError, cv2.error, streams.FFmpegError, tf.errors.OpError, OSError,
                MemoryError, Image.DecompressionBombError)  # The last: a huge or forged size.


class OutputFull(RuntimeError):
  """The output folder's disk is full or takes no more files: no later input could be
  written either."""


# Free bytes under which a failed input is taken for a full output disk, not its own fault.
OUTPUT_RESERVE = 1 << 20

# Write errors that every later input would meet too: a full disk, an exhausted quota, a
# file system (re)mounted read-only.
_STOPPING_ERRNOS = (errno.ENOSPC, errno.EDQUOT, errno.EROFS)


def _stopping_error(error: Optional[BaseException]) -> str:
  """The reason ('Disk quota exceeded', ...) when `error` or one it was raised from is one
  of `_STOPPING_ERRNOS`, by its errno or, from FFmpeg or OpenCV, by its text; else ''."""
  seen = set()
  while error is not None and id(error) not in seen:
    seen.add(id(error))
    if isinstance(error, OSError) and error.errno in _STOPPING_ERRNOS:
      return os.strerror(error.errno)
    for code in _STOPPING_ERRNOS:
      if os.strerror(code) in str(error):
        return os.strerror(code)
    error = error.__cause__ or error.__context__
  return ''


def check_output_room(output_dir: str, error: Optional[BaseException] = None) -> None:
  """Raises OutputFull, naming `output_dir`, when its file system has under OUTPUT_RESERVE
  bytes free, or when `error` (the input's) is a write error every later input would meet
  (`_STOPPING_ERRNOS`); called when an input failed (a full disk made every later input fail
  as a bad one, and the batch's summary was then not written)."""
  keep = 'the finished inputs are kept: {} and run the same command to continue'
  stopping = _stopping_error(error)
  if stopping:
    raise OutputFull(f'writing the results failed with "{stopping}" (the output folder '
                     f'{output_dir} or its disk), as it would for every later input; '
                     + keep.format('fix it'))
  try:
    free = shutil.disk_usage(output_dir).free
  except OSError:
    return
  if free < OUTPUT_RESERVE:
    raise OutputFull(f'the output folder {output_dir} is on a full disk ({free} bytes free); '
                     + keep.format('free some space'))
