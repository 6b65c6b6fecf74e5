"""The console output of Apache Beam's local workers, filtered for `mixstereo-batch`.

In Beam's multi-processing mode (`--direct_running_mode=multi_processing`) each worker is a
Python process of its own that writes its log to the tool's standard error in Python's
plain format, before and outside anything the tool configures: about 15 lines of start-up
and shut-down notes per worker ('INFO:apache_beam.runners.worker...'), and on Ctrl-C a
KeyboardInterrupt traceback from every worker and every thread that waited on one,
burying the run's one-line message 'Interrupted: ...'.

`filtered_stderr` passes file descriptor 2 of this process, which the workers inherit,
through a pipe and a thread that writes on to the real standard error every line but
those (`StderrFilter`). The workers' warnings and errors, which name their input, are
kept, and so is any traceback that does not end in KeyboardInterrupt. Once Ctrl-C has
reached this process only log lines pass: the echoes of the interrupt from many threads
interleave, even within a line. Measured (`--direct_num_workers=2`, 2000 inputs, Ctrl-C
after 25 s): 30 lines of notes before the first input and 222 after Ctrl-C, now none and
the one 'Interrupted' line.
"""

import contextlib
import logging as std_logging
import os
import re
import signal
import sys
import threading
from typing import Iterator, List

from absl import logging

# Worker lines that are notes, not problems (Python's 'LEVEL:logger:message' format).
NOISE = ('INFO:apache_beam.', 'INFO:__main__:', 'WARNING:root:apitools not found',
         'WARNING:__main__:No semi_persistent_directory found')
# Lines that open a traceback block: it is kept or dropped whole, when its last line
# (the exception) has been read.
BLOCK_STARTS = ('Traceback (most recent call last):', 'Exception in thread ',
                'CRITICAL:__main__:Python sdk harness failed', 'ERROR:apache_beam.')


# A log line of absl's format ('E1128 16:46:30.58 123 batch.py:87] ...') or of a worker's
# own records of this package ('WARNING:absl:...').
_LOG_LINE = re.compile(r'[IWEF]\d{4} \d\d:\d\d:\d\d|(WARNING|ERROR|CRITICAL):absl:')
# Lines between the tracebacks of chained exceptions.
_CHAINED = ('During handling of the above exception', 'The above exception was')


class StderrFilter:
  """Line by line: `feed` a line (with its newline), get back the lines to write."""

  def __init__(self):
    self.interrupted = False  # Set on Ctrl-C: every traceback after it is its echo.
    self._block: List[str] = []
    self._dropped = False  # The last block was dropped: so is a blank line after it.

  def feed(self, line: str) -> List[str]:
    """The lines to write now, `line` and those held before it included or not."""
    if self.interrupted:  # Only log lines: the threads' echoes interleave mid-line.
      self._block = []
      return [line] if _LOG_LINE.match(line) else []
    if self._block:
      self._block.append(line)
      if line[:1] in (' ', '\t', '\n') or line.startswith(BLOCK_STARTS + _CHAINED):
        return []
      block, self._block = self._block, []  # `line` is the exception: the block ends.
      self._dropped = 'KeyboardInterrupt' in line
      return [] if self._dropped else block
    dropped, self._dropped = self._dropped, False
    if line.startswith(BLOCK_STARTS + _CHAINED):
      self._block = [line]
      return []
    if line.startswith(NOISE) or (dropped and line == '\n') or 'KeyboardInterrupt' in line:
      return []
    return [line]

  def close(self) -> List[str]:
    """The lines still held (a block cut short) when the output ends."""
    block, self._block = self._block, []
    return [] if self.interrupted else block


class _BeamAfterInterrupt(std_logging.Filter):
  """Drops the records of Beam's loggers once `lines` is interrupted (a worker's closing
  errors: 'Failed to read inputs in the data plane', 'Error closing worker_handler')."""

  def __init__(self, lines: StderrFilter):
    super().__init__()
    self.lines = lines

  def filter(self, record: std_logging.LogRecord) -> bool:
    return not (self.lines.interrupted and record.name.startswith('apache_beam'))


def _write(fd: int, lines: List[str]) -> None:
  """Writes `lines` on `fd`; a closed reader (`| head`) only loses them: the pipe must be
  drained on, or the writers would block."""
  if lines:
    try:
      os.write(fd, ''.join(lines).encode('utf-8'))
    except OSError:
      pass


def _pump(read_fd: int, write_fd: int, lines: StderrFilter) -> None:
  """Copies `read_fd` to `write_fd` through `lines` until the pipe's end, then closes
  both."""
  pending = b''
  with os.fdopen(read_fd, 'rb', buffering=0) as source:
    while True:
      chunk = source.read(65536)
      if not chunk:
        break
      *whole, pending = (pending + chunk).split(b'\n')
      _write(write_fd, [out for line in whole
                        for out in lines.feed(line.decode('utf-8', 'replace') + '\n')])
  _write(write_fd, (lines.feed(pending.decode('utf-8', 'replace')) if pending else []) +
         lines.close())
  os.close(write_fd)


@contextlib.contextmanager
def filtered_stderr() -> Iterator[StderrFilter]:
  """While inside, standard error (this process's and its children's) passes through a
  `StderrFilter`; Ctrl-C in the main thread marks it interrupted, then raises
  KeyboardInterrupt as before."""
  lines = StderrFilter()
  sys.stderr.flush()
  read_fd, write_fd = os.pipe()
  real = os.dup(2)
  pump = threading.Thread(target=_pump, args=(read_fd, os.dup(real), lines), daemon=True,
                          name='stderr-filter')
  pump.start()
  os.dup2(write_fd, 2)
  os.close(write_fd)

  def interrupted(signum, frame):
    lines.interrupted = True
    signal.default_int_handler(signum, frame)
  main = threading.current_thread() is threading.main_thread()  # Signals: main only.
  previous = signal.signal(signal.SIGINT, interrupted) if main else None
  # This process's Beam records (logged through absl's handler) after Ctrl-C: its echo.
  beam_echo = _BeamAfterInterrupt(lines)
  logging.get_absl_handler().addFilter(beam_echo)
  try:
    yield lines
  finally:
    logging.get_absl_handler().removeFilter(beam_echo)
    if main:
      signal.signal(signal.SIGINT, previous)
    sys.stderr.flush()
    os.dup2(real, 2)  # The pipe ends when the workers, which hold it too, have ended.
    os.close(real)
    pump.join(timeout=5.0)
