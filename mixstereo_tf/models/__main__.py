"""Prints the parameter table of the default (paper) configuration.

Usage: python -m mixstereo_tf.models
"""

import sys

from mixstereo_tf.models import summary


def main() -> int:
  print(summary.parameter_table())
  return 0


if __name__ == '__main__':
  sys.exit(main())
