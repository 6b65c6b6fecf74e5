"""Progress lines for long runs: a bar with frames per second and an ETA.

`ProgressBar` redraws one line in place on a terminal and logs lines otherwise, so logs of
batch jobs stay short.
"""

import time
from typing import Callable, Optional, TextIO

from absl import logging


def _duration(seconds: float) -> str:
  minutes, seconds = divmod(int(round(seconds)), 60)
  return f'{minutes} min {seconds:02d} s' if minutes else f'{seconds} s'


def format_progress(done: int, total: Optional[int], seconds: float,
                    frames: Optional[int] = None, label: str = '', bar_width: int = 10,
                    resumed: int = 0) -> str:
  """One progress line, e.g. '[###.......] 3/10  1.2 frames/s  ETA 6 s'.

  Args:
    done: items (inputs or video frames) finished.
    total: items in all; None when unknown (a video without a frame count): the line then
      has neither bar nor ETA ('37 done  1.2 frames/s').
    seconds: wall time since the start.
    frames: frames produced so far (default `done`); frames/s is frames / seconds.
    label: optional prefix, e.g. the video's file name.
    bar_width: characters between the brackets.
    resumed: of `done`, those finished before `seconds` began (a resumed video): the ETA
      extrapolates the time of the others.
  """
  frames = done if frames is None else frames
  parts = [label] if label else []
  if total:
    filled = bar_width * min(done, total) // total
    parts.append(f'[{"#" * filled}{"." * (bar_width - filled)}] {done}/{total}')
  else:
    parts.append(f'{done} done')
  parts.append(f'{frames / seconds if seconds > 0 else 0.0:.1f} frames/s')
  if total:
    # The ETA extrapolates the time per item finished since; unknown before the first one.
    left = max(total - done, 0) * seconds / (done - resumed) if done > resumed else None
    parts.append('ETA ' + ('?' if left is None else _duration(left)))
  return '  '.join(parts)


class ProgressBar:
  """Shows `format_progress` lines: redrawn in place on a terminal, logged otherwise.

  On a `stream` that is a TTY the line is rewritten after a carriage return at most every
  `redraw_seconds`; otherwise (a pipe, a file, no stream) it goes to the INFO log at most
  every `log_seconds`, so logs stay short. The first update and the last one (done >=
  total, or `force`) are always shown; a count already shown is not repeated.
  """

  def __init__(self, total: Optional[int], label: str = '', stream: Optional[TextIO] = None,
               clock: Callable[[], float] = time.perf_counter, redraw_seconds: float = 0.2,
               log_seconds: float = 10.0, resumed: int = 0):
    self.total, self.label, self._resumed = total, label, resumed
    self._stream = stream if stream is not None and stream.isatty() else None
    self._clock = clock
    self._start = clock()
    self._interval = redraw_seconds if self._stream else log_seconds
    self._shown_at = self._shown_done = None
    self._drawn = 0  # Characters of the line currently on the terminal.

  def update(self, done: int, frames: Optional[int] = None, force: bool = False) -> None:
    """Shows the progress after `done` items (and `frames` frames) unless shown recently."""
    now = self._clock()
    last = force or (self.total is not None and done >= self.total)
    if done == self._shown_done or (
        self._shown_at is not None and not last and now - self._shown_at < self._interval):
      return
    self._shown_at, self._shown_done = now, done
    line = format_progress(done, self.total, now - self._start, frames, self.label,
                           resumed=self._resumed)
    if self._stream is None:
      logging.info('%s', line)
      return
    # Spaces overwrite the end of a longer previous line.
    self._stream.write('\r' + line.ljust(self._drawn))
    self._stream.flush()
    self._drawn = len(line)

  def clear(self) -> None:
    """Erases the terminal line before other output; the next update redraws it."""
    if self._drawn:
      self._stream.write('\r' + ' ' * self._drawn + '\r')
      self._stream.flush()
      self._drawn, self._shown_at, self._shown_done = 0, None, None

  def close(self) -> None:
    """Ends the terminal line, leaving the last progress on screen."""
    if self._drawn:
      self._stream.write('\n')
      self._stream.flush()
      self._drawn = 0
