"""Tests for mixstereo_tf.cli.flags: flags declared once, parsing and error translation."""

import ast
import contextlib
import copy
import importlib
import importlib.util
import os
import subprocess
import sys

from absl import app
from absl import flags
import pytest

from mixstereo_tf.cli import flag_errors
from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.unmixing import predictors


def test_groups_declare_each_flag_once():
  cli_flags.define_predictor()
  cli_flags.define_predictor()  # A second call (another tool in the process) is a no-op.
  cli_flags.define_mixture()
  assert flags.FLAGS['method'].default == predictors.PredictorConfig().method
  assert flags.FLAGS['restore_colors'].help.startswith('Alias for --restore_colour')


def test_defaults_come_from_the_config_dataclass():
  assert cli_flags.defaults(predictors.PredictorConfig) == {
      'method': 'model', 'checkpoint': None, 'saved_model': None, 'mixture': None,
      'restore_colour': None, 'disparity_range': None, 'max_network_pixels': 2_000_000,
      'pretrained': None, 'swap_eyes': False, 'mixing_weight': None, 'descreen': 'off',
      'rectify': 'off'}


@contextlib.contextmanager
def _parsing(name):
  """FLAGS marked parsed (the other flags keep their defaults) while the test sets --name;
  afterwards --name and, if they were not parsed before, all flags are unparsed."""
  was_parsed = flags.FLAGS.is_parsed()
  flags.FLAGS.mark_as_parsed()
  try:
    yield flags.FLAGS[name]
  finally:
    flags.FLAGS[name].unparse()
    if not was_parsed:
      flags.FLAGS.unparse_flags()


def test_output_format_is_repeatable_and_reaches_output_options():
  cli_flags.define_output_options()
  with _parsing('output_format') as output_format:
    assert cli_flags.output_options().formats == ()  # The default: none.
    output_format.parse('mpo')
    output_format.parse('anaglyph_dubois')
    assert cli_flags.output_options().formats == ('mpo', 'anaglyph_dubois')
    output_format.parse(' jps,wiggle')  # Comma-separated, as users type lists.
    assert cli_flags.output_options().formats == ('mpo', 'anaglyph_dubois', 'jps', 'wiggle')
    assert cli_flags.output_options().settings is None
    settings = cli_flags.output_options(predictors.PredictorConfig(pretrained='anaglyph')).settings
    assert settings['pretrained'] == 'anaglyph'  # The config's fields and its weights'.
    assert settings['weights'].startswith('weights.npz sha256:')
    default = cli_flags.output_options(predictors.PredictorConfig(mixture='auto')).settings
    spelt = predictors.PredictorConfig(mixture='auto', pretrained='anaglyph_matching')
    assert default == cli_flags.output_options(spelt).settings  # A rerun asks the same.
    classical = predictors.PredictorConfig('classical', mixture='auto')
    assert cli_flags.output_options(classical).settings['pretrained'] is None
    with pytest.raises(flags.IllegalFlagValueError, match="'gif' is not one of.*wiggle"):
      output_format.parse('mpo,gif')
    error = flag_errors.usage_error(ValueError("OutputOptions.formats: 'jps' twice"))
    assert str(error) == "--output_format: 'jps' twice"


def test_swap_eyes_is_a_boolean_flag_that_also_takes_auto():
  cli_flags.define_predictor()
  values = flags.FlagValues()
  flags.DEFINE_flag(copy.deepcopy(flags.FLAGS['swap_eyes']), flag_values=values)
  for argv, want in (([], False), (['--swap_eyes'], True), (['--noswap_eyes'], False),
                     (['--swap_eyes=auto'], 'auto'), (['--swap_eyes=AUTO'], 'auto'),
                     (['--swap_eyes=false'], False)):
    values.unparse_flags()
    values(['prog', *argv])
    assert values.swap_eyes == want, argv
  values.unparse_flags()
  with pytest.raises(flags.IllegalFlagValueError, match="true, false or 'auto'"):
    values(['prog', '--swap_eyes=maybe'])
  with _parsing('swap_eyes') as swap_eyes:
    swap_eyes.parse('auto')
    assert cli_flags.predictor_config().swap_eyes == 'auto'


def test_unmix_predictor_config_refuses_the_oracle():
  cli_flags.define_unmix_predictor()
  with _parsing('method') as method:
    assert cli_flags.unmix_predictor_config().method == flags.FLAGS.method
    method.parse('oracle')
    with pytest.raises(ValueError, match='--method=oracle needs the clean stereo pair'):
      cli_flags.unmix_predictor_config()


@pytest.mark.parametrize('binary', ['unmix', 'train', 'evaluate', 'export', 'batch'])
def test_help_under_a_console_script_wrapper_shows_the_binarys_docstring(binary):
  """A console script's `__main__` (the pip wrapper) has no docstring: absl printed a bare
  usage line for `mixstereo-unmix --help`. The docstring is read from the source: importing
  `mixstereo_tf.unmix` here would shadow the package's `unmix` function for later tests."""
  with open(importlib.util.find_spec(f'mixstereo_tf.{binary}').origin, encoding='utf-8') as f:
    docstring = ast.get_docstring(ast.parse(f.read()))
  script = ('import importlib, sys\n'
            f"sys.argv = ['mixstereo-{binary}', '--help']\n"
            f"importlib.import_module('mixstereo_tf.{binary}').run()\n")
  result = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          timeout=120, check=False,
                          env=dict(os.environ, TF_CPP_MIN_LOG_LEVEL='2'))
  first_line = docstring.strip().splitlines()[0]
  assert first_line in result.stdout + result.stderr


def test_the_tools_that_unmix_files_descreen_prints_and_evaluate_does_not():
  """--descreen and --rectify belong to mixstereo-unmix and mixstereo-batch (default
  'auto'); the paper's evaluation keeps PredictorConfig's 'off'."""
  cli_flags.define_unmix_predictor()
  assert flags.FLAGS['descreen'].default == 'auto' == flags.FLAGS['rectify'].default
  with _parsing('descreen') as descreen:
    assert cli_flags.unmix_predictor_config().descreen == 'auto'
    assert cli_flags.unmix_predictor_config().rectify == 'auto'
    assert cli_flags.predictor_config().descreen == 'off' == cli_flags.predictor_config().rectify
    descreen.parse('4.5')
    assert cli_flags.unmix_predictor_config().descreen == 4.5
    descreen.parse('none')
    with pytest.raises(app.UsageError, match="--descreen: expected 'auto', 'off'"):
      cli_flags.unmix_predictor_config()
  for binary, declared in (('unmix', True), ('batch', True), ('evaluate', False)):
    with open(importlib.util.find_spec(f'mixstereo_tf.{binary}').origin,
              encoding='utf-8') as f:
      assert ('define_unmix_predictor()' in f.read()) == declared, binary


def test_max_network_pixels_given_for_a_method_without_a_network_is_refused():
  cli_flags.define_predictor()
  with _parsing('max_network_pixels') as pixels:
    pixels.parse('1000')
    flags.FLAGS['method'].parse('classical')
    try:
      with pytest.raises(app.UsageError, match='--max_network_pixels applies to --method=model'):
        cli_flags.predictor_config()
    finally:
      flags.FLAGS['method'].unparse()


def test_temporal_prior_reaches_the_videos_temporal_config():
  cli_flags.define_output_options()
  with _parsing('temporal_prior') as temporal_prior:
    assert cli_flags.output_options().temporal_config.use_prior  # The default: the prior.
    temporal_prior.parse(False)
    config = cli_flags.output_options().temporal_config
    assert config.enabled and not config.use_prior


def test_keep_video_bits_reaches_the_video_config():
  cli_flags.define_output_options()
  with _parsing('keep_video_bits') as keep:
    assert cli_flags.output_options().video_config.keep_bits  # The default: kept.
    keep.parse(False)
    assert not cli_flags.output_options().video_config.keep_bits
