"""Tests for mixstereo_tf.artifacts.runs: the run directory, RunInfo and checkpoint lookup."""

import dataclasses
import json
import os
import shutil

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.artifacts import runs
from tests.unmixing import predictors_test

TINY = predictors_test.TINY


@pytest.fixture(scope='module')
def run(tmp_path_factory):
  path = str(tmp_path_factory.mktemp('run'))
  model, prefix = predictors_test.make_run_dir(path)
  return path, model, prefix


def test_load_run_restores_the_weights(run):
  path, model, prefix = run
  for source in (path, prefix):
    loaded, info = runs.load_run(source)
    assert info == runs.RunInfo('anaglyph', 64, 128, TINY)
    for saved, restored in zip(model.variables, loaded.variables):
      np.testing.assert_array_equal(saved.numpy(), restored.numpy())


def test_load_run_errors(tmp_path, run):
  path, model, prefix = run
  with pytest.raises(ValueError, match='No checkpoint'):
    runs.load_run(str(tmp_path))
  with pytest.raises(ValueError, match='neither a run directory nor a checkpoint prefix'):
    runs.load_run(prefix + '-nope')
  no_config = tmp_path / 'no_config'
  shutil.copytree(path, no_config)
  os.remove(no_config / 'config.json')
  with pytest.raises(ValueError, match='config.json'):
    runs.load_run(str(no_config))
  broken = tmp_path / 'broken'
  shutil.copytree(path, broken)
  (broken / 'config.json').write_text(json.dumps({'model': TINY.to_dict()}))
  with pytest.raises(ValueError, match='pipeline'):
    runs.load_run(str(broken))
  # A checkpoint with only the separation network's weights cannot restore the model.
  partial = tmp_path / 'partial'
  partial.mkdir()
  shutil.copy(os.path.join(path, 'config.json'), partial)
  part = tf.train.Checkpoint(model=tf.train.Checkpoint(separation=model.separation))
  with pytest.raises(ValueError, match='weights'):
    runs.load_run(part.write(str(partial / 'ckpt-1')))


def test_resolve_checkpoint_takes_a_directory_or_a_prefix(run, tmp_path):
  path, _, prefix = run
  assert runs.resolve_checkpoint(path) == (path, prefix)
  assert runs.resolve_checkpoint(prefix) == (path, prefix)
  (tmp_path / 'empty').mkdir()
  with pytest.raises(ValueError, match='No checkpoint in'):
    runs.resolve_checkpoint(str(tmp_path / 'empty'))


def test_write_run_files_and_read_run_info_round_trip(tmp_path):
  info = runs.RunInfo('diplopia', 32, 64, TINY)
  runs.write_run_files(str(tmp_path / 'r'), '--x=1\n', model=TINY,
                       pipeline={'mixture': 'diplopia', 'crop_height': 32, 'crop_width': 64})
  assert runs.read_run_info(str(tmp_path / 'r')) == info
  assert (tmp_path / 'r' / runs.FLAGS_FILE).read_text() == '--x=1\n'
  assert json.loads((tmp_path / 'r' / runs.CONFIG_FILE).read_text())['model'] == TINY.to_dict()


def test_resuming_refuses_another_configuration(tmp_path):
  run_dir = str(tmp_path / 'r')
  train = {'num_steps': 30, 'learning_rate': 1e-4, 'log_every': 5, 'model_dir': run_dir}
  pipeline = {'mixture': 'anaglyph', 'crop_height': 32, 'crop_width': 64}
  runs.write_run_files(run_dir, None, train=train, model=TINY, pipeline=pipeline)
  # No checkpoint yet: nothing trained under the old label, any change is written.
  runs.write_run_files(run_dir, None, train=train, model=TINY,
                       pipeline=dict(pipeline, crop_width=128))
  runs.write_run_files(run_dir, None, train=train, model=TINY, pipeline=pipeline)
  tf.train.Checkpoint(step=tf.Variable(1)).save(os.path.join(run_dir, 'ckpt'))
  # How long and how it runs may change on resume...
  runs.write_run_files(run_dir, None, train=dict(train, num_steps=40, log_every=1,
                                                 model_dir='moved'), model=TINY,
                       pipeline=dict(pipeline, skip_bad_pairs=True))  # As its error advises.
  # ...what it trains may not: every difference is named, config.json is kept.
  with pytest.raises(runs.RunDirError,
                     match=r"pipeline.mixture: 'anaglyph' -> 'diplopia'; train.learning_rate"):
    runs.write_run_files(run_dir, None, train=dict(train, learning_rate=1e-3), model=TINY,
                         pipeline=dict(pipeline, mixture='diplopia'))
  assert json.loads((tmp_path / 'r' / runs.CONFIG_FILE).read_text())['pipeline'] == dict(
      pipeline, skip_bad_pairs=True)
  with pytest.raises(runs.RunDirError, match='model.'):
    runs.write_run_files(run_dir, None, train=train, model={'other': 1}, pipeline=pipeline)


@dataclasses.dataclass(frozen=True)
class _StepConfig:
  learning_rate: float = 1e-4
  widths: tuple = (8, 16)


def test_a_refused_resume_names_config_fields_the_tools_turn_into_flags(tmp_path):
  run_dir = str(tmp_path / 'r')
  runs.write_run_files(run_dir, None, train=_StepConfig(), model=TINY)
  tf.train.Checkpoint(step=tf.Variable(1)).save(os.path.join(run_dir, 'ckpt'))
  with pytest.raises(runs.RunDirError, match=r'would change _StepConfig\.learning_rate: '
                     r'0\.0001 -> 0\.001\. Give'):
    runs.write_run_files(run_dir, None, train=_StepConfig(learning_rate=1e-3), model=TINY)


def test_a_file_as_run_directory_is_named(tmp_path):
  (tmp_path / 'list.txt').write_text('x')
  with pytest.raises(runs.RunDirError, match=r'--model_dir=.*list.txt is an existing file'):
    runs.write_run_files(str(tmp_path / 'list.txt'), None, model=TINY)


@pytest.mark.parametrize('stage', ['refiner', 'features'])
def test_a_stage_run_is_named_with_how_to_use_it(tmp_path, stage):
  runs.write_run_files(str(tmp_path), None, train={'num_steps': 1}, **{stage: {'width': 4}})
  with pytest.raises(ValueError, match=rf'is a {stage} run \(--architecture={stage}\), not a '
                                       r'joint network: .*--as_pretrained'):
    runs.read_run_info(str(tmp_path))
