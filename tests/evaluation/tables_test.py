"""Exact-output tests of the result tables."""

import math

import pytest

from mixstereo_tf.evaluation import tables

_COLUMNS = ['method', 'psnr_left', 'd1_all']
_ROWS = [{'method': 'ours', 'psnr_left': 26.3, 'd1_all': 5.961},
         ['paper', 26.304, None],
         {'method': 'empty', 'psnr_left': math.nan}]


def test_format_table_exact():
  text = tables.format_table('KITTI 2015', _COLUMNS, _ROWS, percent_columns={'d1_all'})
  assert text == ('KITTI 2015\n'
                  'method  psnr_left  d1_all\n'
                  '------  ---------  ------\n'
                  'ours        26.30   5.96%\n'
                  'paper       26.30       -\n'
                  'empty         nan       -\n')


def test_markdown_table_exact():
  text = tables.markdown_table(None, _COLUMNS, _ROWS[:2], percent_columns={'d1_all'},
                               digits=3)
  assert text == ('| method | psnr_left | d1_all |\n'
                  '| --- | ---: | ---: |\n'
                  '| ours | 26.300 | 5.961% |\n'
                  '| paper | 26.304 | - |\n')


def test_row_length_mismatch_raises():
  with pytest.raises(ValueError, match='2 values for 3 columns'):
    tables.format_table('t', _COLUMNS, [['a', 1.0]])
