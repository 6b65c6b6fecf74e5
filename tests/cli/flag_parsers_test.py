"""Tests for mixstereo_tf.cli.flag_parsers: values parsed, or refused naming the flag."""

import re

from absl import app
import pytest

from mixstereo_tf.cli import flag_parsers


def test_scale_items_are_parsed_or_named():
  assert flag_parsers.parse_scene_scales(['tsukuba:16', ' Venus : 8.5']) == (('tsukuba', 16.0),
                                                                         ('Venus', 8.5))
  assert flag_parsers.parse_scene_scales([]) == ()
  for item in ('tsukuba', 'tsukuba:abc', 'venus:'):
    with pytest.raises(app.UsageError, match=rf"--middlebury_scale: .*{re.escape(repr(item))}"):
      flag_parsers.parse_scene_scales(['cones:4', item])


def test_mixing_weight_is_auto_a_number_in_the_open_unit_interval_or_unset():
  assert flag_parsers.parse_mixing_weight(None) is None
  assert flag_parsers.parse_mixing_weight(' AUTO ') == 'auto'
  assert flag_parsers.parse_mixing_weight('0.3') == 0.3
  for text in ('1', '0', 'half'):
    with pytest.raises(app.UsageError, match=rf"--mixing_weight: .*{re.escape(repr(text))}"):
      flag_parsers.parse_mixing_weight(text)


def test_descreen_is_auto_off_or_a_period_above_one_pixel():
  assert flag_parsers.parse_descreen(' Auto') == 'auto'
  assert flag_parsers.parse_descreen('off') == 'off'
  assert flag_parsers.parse_descreen('5.5') == 5.5
  for text in ('1', '-3', 'dots', 'nan'):
    with pytest.raises(app.UsageError, match='--descreen: .*period'):
      flag_parsers.parse_descreen(text)
