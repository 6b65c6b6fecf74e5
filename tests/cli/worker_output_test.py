"""Tests of cli/worker_output.py: Beam workers' console output, filtered."""

import signal
import subprocess
import sys

import pytest

from mixstereo_tf.cli import worker_output

# What two multi-processing workers wrote (shortened), a real error among it.
STARTING = """\
INFO:__main__:Logging handler created.
WARNING:root:apitools not found, and bigquery client libraries are not available.
WARNING:__main__:No semi_persistent_directory found:  User registered objects ...
INFO:apache_beam.runners.worker.sdk_worker:Control channel established.
WARNING:absl:scans/a.png: Detected half_color, the smallest encoding ...
ERROR:apache_beam.runners.common:disk on fire [while running 'Unmix/ParDo(_UnmixFn)']
Traceback (most recent call last):
  File "apache_beam/runners/common.py", line 1512, in process
OSError: disk on fire
"""
INTERRUPTED = """\
CRITICAL:__main__:Python sdk harness failed: 
Traceback (most recent call last):
  File "sdk_worker_main.py", line 250, in main
    sdk_harness.run()
            ^^^^^^^^^^
KeyboardInterrupt

During handling of the above exception, another exception occurred:

Traceback (most recent call last):
  File "grpc/_channel.py", line 547, in __next__
KeyboardInterrupt
E1128 14:59:58.594453 1399 local_job_service.py:367] CRITICAL - Worker: ... KeyboardInterrupt
"""


def _filtered(text, lines=None):
  lines = lines or worker_output.StderrFilter()
  out = [kept for line in text.splitlines(keepends=True) for kept in lines.feed(line)]
  return ''.join(out + lines.close())


def test_worker_notes_and_interrupt_tracebacks_are_dropped_and_errors_kept():
  assert _filtered(STARTING + INTERRUPTED) == STARTING[STARTING.index('WARNING:absl'):]


def test_after_ctrl_c_only_log_lines_are_kept():
  """Threads' echoes of the interrupt interleave mid-line (a line 'self.run()' without its
  indent reached the console)."""
  lines = worker_output.StderrFilter()
  lines.interrupted = True
  echo = ('Exception in thread run_worker:\nself.run()\n'
          'RuntimeError: Worker subprocess exited with return code -2\n')
  ours = 'E1128 15:00:00.945756 1399 batch.py:82] Interrupted: the inputs ... kept\n'
  assert _filtered(echo + STARTING + ours, lines) == (
      'WARNING:absl:scans/a.png: Detected half_color, the smallest encoding ...\n' + ours)


def test_a_childs_output_passes_the_filter(capfd):
  script = ("import sys; sys.stderr.write('INFO:apache_beam.x:note\\n"
            "WARNING:absl:a.png: clipped\\nno newline at the end')")
  with worker_output.filtered_stderr():
    subprocess.run([sys.executable, '-c', script], check=True)
  assert capfd.readouterr().err == 'WARNING:absl:a.png: clipped\nno newline at the end'


def test_ctrl_c_marks_the_filter_interrupted_and_still_interrupts():
  before = signal.getsignal(signal.SIGINT)
  with worker_output.filtered_stderr() as lines:
    with pytest.raises(KeyboardInterrupt):
      signal.getsignal(signal.SIGINT)(signal.SIGINT, None)
  assert lines.interrupted and signal.getsignal(signal.SIGINT) is before
