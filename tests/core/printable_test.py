"""Tests of core/printable.py: file names that are no UTF-8 in logs."""

import io
import logging as std_logging
import os

from absl import logging

import mixstereo_tf  # pylint: disable=unused-import  (installs the filter)
from mixstereo_tf.core import printable

LATIN = os.fsdecode(b'/scans/caf\xe9.png')


def test_printable_escapes_the_bytes_of_a_name_that_is_no_utf8():
  assert printable.printable(LATIN) == '/scans/caf\\xe9.png'
  text = 'déjà vu.png'
  assert printable.printable(text) is text
  assert printable.printable('a\ud800b') == 'a\\ud800b'  # Not from a byte: kept visible.


def test_a_strict_utf8_log_sink_takes_a_line_naming_such_a_file():
  """Such a line raised UnicodeEncodeError in the handler: logging printed 'Logging error'
  with a traceback, and an absl log file (--log_dir) or pytest-xdist lost the line."""
  raw = io.BytesIO()
  stream = io.TextIOWrapper(raw, encoding='utf-8', errors='strict', write_through=True)
  handler = std_logging.StreamHandler(stream)
  errors = []
  handler.handleError = errors.append
  logging.get_absl_logger().addHandler(handler)
  try:
    logging.warning('skipped %s: %s', LATIN, 'unreadable')
  finally:
    logging.get_absl_logger().removeHandler(handler)
  assert not errors
  assert raw.getvalue().decode('utf-8') == 'skipped /scans/caf\\xe9.png: unreadable\n'


def test_install_adds_the_filter_once():
  printable.install()
  printable.install()
  kinds = [f for f in logging.get_absl_logger().filters
           if isinstance(f, printable.PrintableMessages)]
  assert len(kinds) == 1
