"""Tests for mixstereo_tf.cli.progress: progress lines, terminal redraws and logged lines."""

import io
import logging

import pytest

from mixstereo_tf.cli import progress


class _Terminal(io.StringIO):
  """A stream that says it is a terminal, so progress is drawn on it."""

  def isatty(self):
    return True


@pytest.mark.parametrize('args, line', [
    ((3, 10, 2.5), '[###.......] 3/10  1.2 frames/s  ETA 6 s'),
    ((0, 10, 0.0), '[..........] 0/10  0.0 frames/s  ETA ?'),
    ((10, 10, 4.0), '[##########] 10/10  2.5 frames/s  ETA 0 s'),
    ((12, 10, 6.0), '[##########] 12/10  2.0 frames/s  ETA 0 s'),  # A wrong frame count.
    ((1, 100, 2.0), '[..........] 1/100  0.5 frames/s  ETA 3 min 18 s'),
    ((2, 4, 10.0, 50, 'clip.mp4'), 'clip.mp4  [#####.....] 2/4  5.0 frames/s  ETA 10 s'),
    ((37, None, 10.0), '37 done  3.7 frames/s'),
    # A resumed video: 60 frames were done before; this run's 1 frame took 2 s.
    ((61, 120, 2.0, 1, '', 10, 60), '[#####.....] 61/120  0.5 frames/s  ETA 1 min 58 s'),
])
def test_format_progress(args, line):
  assert progress.format_progress(*args) == line


def _clock(*times):
  return iter(times).__next__


def test_progress_bar_redraws_a_terminal_line():
  terminal = _Terminal()
  bar = progress.ProgressBar(3, stream=terminal, clock=_clock(0.0, 30.0, 30.1, 31.0))
  bar.update(1)  # t = 30: shown.
  bar.update(2)  # t = 30.1: within the redraw interval, skipped.
  bar.update(3)  # t = 31: the last one is always shown.
  bar.close()
  first = '[###.......] 1/3  0.0 frames/s  ETA 1 min 00 s'
  last = '[##########] 3/3  0.1 frames/s  ETA 0 s'
  # The shorter last line is padded so nothing of the first one remains.
  assert terminal.getvalue() == '\r' + first + '\r' + last.ljust(len(first)) + '\n'
  terminal = _Terminal()
  bar = progress.ProgressBar(None, 'v.mp4', terminal, clock=_clock(0.0, 1.0, 2.0))
  bar.update(4)
  bar.clear()  # Before a log message: the line is blanked and the next update redraws.
  bar.update(4)
  line = 'v.mp4  4 done  4.0 frames/s'
  assert terminal.getvalue() == (f'\r{line}\r{" " * len(line)}\r'
                                 f'\rv.mp4  4 done  2.0 frames/s')


def test_progress_bar_logs_lines_when_not_a_terminal(caplog):
  stream = io.StringIO()
  bar = progress.ProgressBar(3, stream=stream, clock=_clock(0.0, 1.0, 5.0, 12.0),
                             log_seconds=10.0)
  with caplog.at_level(logging.INFO, logger='absl'):
    for done in (1, 2, 3):
      bar.update(done)
    bar.close()
  assert stream.getvalue() == ''
  assert [r.getMessage() for r in caplog.records] == [
      '[###.......] 1/3  1.0 frames/s  ETA 2 s', '[##########] 3/3  0.2 frames/s  ETA 0 s']
