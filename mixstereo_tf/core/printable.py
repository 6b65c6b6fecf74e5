"""File names as UTF-8 text for logs and CSV files.

A file name whose bytes are not UTF-8 (a Latin-1 name from an old share) reaches Python as
a str holding lone surrogates (PEP 383). Printed to a terminal they show as escapes, but a
strict UTF-8 sink refuses them: an absl log file (`--log_dir`), a CSV, pytest-xdist's
reports. `printable` writes such bytes as `\\xNN`; `install` makes every message logged on
absl's logger printable, so no log line naming such a file fails.
"""

import logging as std_logging

from absl import logging


def printable(text: str) -> str:
  """`text` unchanged when it encodes as UTF-8; else each byte a surrogate stands for as
  `\\xNN` (other lone surrogates as `\\udXXX`)."""
  try:
    text.encode('utf-8')
    return text
  except UnicodeEncodeError:
    pass
  try:
    return text.encode('utf-8', 'surrogateescape').decode('utf-8', 'backslashreplace')
  except UnicodeEncodeError:
    return text.encode('utf-8', 'backslashreplace').decode('utf-8')


class PrintableMessages(std_logging.Filter):
  """Rewrites a record whose formatted message is no UTF-8 text by `printable`."""

  def filter(self, record: std_logging.LogRecord) -> bool:
    message = record.getMessage()
    shown = printable(message)
    if shown is not message:
      record.msg, record.args = shown, ()
    return True


_FILTER = PrintableMessages()


def install() -> None:
  """Adds the filter to absl's logger (once; later calls do nothing). Filters run in the
  order added, so one added after it (`cli.unmix_files.naming_input`) prints its own
  text by `printable`."""
  logger = logging.get_absl_logger()
  if _FILTER not in logger.filters:
    logger.addFilter(_FILTER)
