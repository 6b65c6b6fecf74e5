"""Tests for mixstereo_tf.cli.input_failures: an input's failure reason, and the errors
that end a run."""

import errno
import os

import pytest
import tensorflow as tf

from mixstereo_tf.cli import input_failures
from mixstereo_tf.cli import unmix_files
from mixstereo_tf.unmixing import mixture_choice


def test_failure_message_names_at_most_five_inputs():
  assert input_failures.failure_message(unmix_files.UnmixReport(processed=3)) is None
  report = unmix_files.UnmixReport(processed=1, failures=[(f'{i}.png', 'bad') for i in range(7)])
  assert input_failures.failure_message(report) == (
      'error: 7 of 8 input(s) failed: 0.png, 1.png, 2.png, 3.png, 4.png, ...')


def test_reason_is_one_line_naming_flags_and_built_in_error_classes():
  error = tf.errors.ResourceExhaustedError(None, None, 'OOM when allocating\n  at node x')
  assert input_failures.reason(error) == 'ResourceExhaustedError: OOM when allocating'
  package_error = mixture_choice.NoAnaglyphError('no anaglyph (PredictorConfig.mixture=x)')
  assert input_failures.reason(package_error) == 'ValueError: no anaglyph (--mixture=x)'
  assert input_failures.reason(ValueError('')) == 'ValueError: '


def test_output_room_ends_the_run_on_a_full_disk_or_a_stopping_write_error(tmp_path,
                                                                             monkeypatch):
  input_failures.check_output_room(str(tmp_path))  # Room, no error: nothing.
  input_failures.check_output_room(str(tmp_path), ValueError('bad pixels'))
  for code in (errno.ENOSPC, errno.EDQUOT, errno.EROFS):
    cause = OSError(code, os.strerror(code))
    wrapped = RuntimeError('writing failed')
    wrapped.__cause__ = cause  # Found through the chain of causes.
    with pytest.raises(input_failures.OutputFull, match=os.strerror(code)):
      input_failures.check_output_room(str(tmp_path), wrapped)
  usage = input_failures.shutil.disk_usage(tmp_path)
  monkeypatch.setattr(input_failures.shutil, 'disk_usage',
                      lambda path: usage._replace(free=input_failures.OUTPUT_RESERVE - 1))
  with pytest.raises(input_failures.OutputFull, match='full disk'):
    input_failures.check_output_room(str(tmp_path))
