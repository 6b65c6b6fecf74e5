"""Tests for mixstereo_tf.cli.flag_errors: config fields in errors become the flags typed."""

from absl import app
from absl import flags
import pytest

from mixstereo_tf.cli import flag_errors
from mixstereo_tf.cli import flags as cli_flags


def test_usage_error_names_flags_instead_of_config_fields():
  cli_flags.define_data()
  cli_flags.define_predictor()
  error = ValueError("PredictorConfig.method='classical' needs PredictorConfig.mixture; "
                     'DataConfig.middlebury_scales: bad; EvalConfig.split_list missing; '
                     'OtherConfig.nothing stays.')
  text = str(flag_errors.usage_error(error, {'EvalConfig.split_list': 'data_dir'}))
  assert text == ("--method='classical' needs --mixture; --middlebury_scale: bad; "
                  '--data_dir missing; OtherConfig.nothing stays.')


def test_flag_names_translates_only_known_flags():
  message = "PredictorConfig.mixture=x; PredictorConfig.method='model'; VideoConfig.enabled."
  assert flag_errors.flag_names(message, known=cli_flags.PREDICTOR_FLAGS) == (
      "--mixture=x; --method='model'; VideoConfig.enabled.")
  cli_flags.define_unmix_predictor()
  assert all(name in flags.FLAGS for name in cli_flags.PREDICTOR_FLAGS)


def test_arguments_no_flag_took_are_refused_naming_them():
  flag_errors.refuse_arguments(['mixstereo-unmix'])
  flag_errors.refuse_arguments(['mixstereo-batch', '--runner', 'DirectRunner'], 'input',
                               passed_on=True)  # A Beam option's value.
  with pytest.raises(app.UsageError, match=r"taken by no flag: g/b.png g/c.png; quote a "
                                           r"pattern .*--input='dir/\*.png'"):
    flag_errors.refuse_arguments(['mixstereo-unmix', 'g/b.png', 'g/c.png'], 'input')
  with pytest.raises(app.UsageError, match=r'taken by no flag: g/b.png\.$'):
    flag_errors.refuse_arguments(['mixstereo-batch', '--runner=DirectRunner', 'g/b.png'],
                                 passed_on=True)
  with pytest.raises(app.UsageError, match=r'a1 a2 a3 a4 a5 \.\.\.\.'):
    flag_errors.refuse_arguments(['train'] + [f'a{i}' for i in range(1, 8)])


def test_typed_flags_are_those_on_the_command_line_not_in_a_flagfile():
  names = ('num_steps', 'num_epochs', 'temporal')
  assert flag_errors.typed_flags(['p', '--flagfile=f', '--num_steps=5'], names) == ['num_steps']
  assert flag_errors.typed_flags(['p', '-num_epochs', '2', '--notemporal'], names) == [
      'num_epochs', 'temporal']
  assert flag_errors.typed_flags(['p', '--', '--num_steps=5'], names) == []
