"""End-to-end tests of the training CLI on the embedded `sample` source."""

import dataclasses
import json
import os
import re
import signal
import socket
import subprocess
import sys
import time

import numpy as np
import tensorflow as tf

from mixstereo_tf import models
from mixstereo_tf import train
from mixstereo_tf.data import pipeline
from mixstereo_tf.data import sample
from mixstereo_tf.training import config as config_lib
from mixstereo_tf.training import loop
from mixstereo_tf.training import objective
from mixstereo_tf.training import step as step_lib
from tests.data import kitti_test

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TINY_FLAGS = ['--dataset=sample', '--sample_scenes=50', '--sample_height=32',
              '--sample_width=64', '--crop_height=32', '--crop_width=64', '--max_disparity=8',
              '--unet_widths=4,4', '--stereo_features=4', '--num_res_blocks=1',
              '--volume_features=4', '--log_every=1', '--summary_every=1000',
              '--image_summary_every=1000']


def _train_cli(model_dir, *extra):
  env = dict(os.environ, CUDA_VISIBLE_DEVICES='', TF_CPP_MIN_LOG_LEVEL='2',
             PYTHONPATH=REPO + os.pathsep + os.environ.get('PYTHONPATH', ''))
  return subprocess.Popen(
      [sys.executable, '-m', 'mixstereo_tf.train', f'--model_dir={model_dir}',
       *TINY_FLAGS, *extra], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
      env=env, cwd=REPO)


def _wait_for_step(process, step, timeout=240):
  deadline = time.time() + timeout
  lines = []
  for line in process.stdout:
    lines.append(line)
    match = re.search(r'step (\d+)/', line)
    if match and int(match.group(1)) >= step:
      return lines
    assert time.time() < deadline, ''.join(lines[-20:])
  raise AssertionError('training ended early:\n' + ''.join(lines[-20:]))


def test_sigterm_leaves_a_checkpoint_and_a_second_run_resumes_from_it(tmp_path):
  model_dir = tmp_path / 'run'
  first = _train_cli(model_dir, '--num_steps=100000', '--checkpoint_every=100000')
  _wait_for_step(first, 3)
  first.send_signal(signal.SIGTERM)
  output = first.communicate(timeout=120)[0]
  assert first.returncode == 128 + signal.SIGTERM, output
  saved = tf.train.latest_checkpoint(str(model_dir))
  assert saved is not None, output
  saved_step = int(saved.rsplit('-', 1)[1])
  assert saved_step >= 3
  assert (model_dir / 'flags.txt').exists()

  # The checkpoint restores every model and optimizer variable of the same configuration.
  config = config_lib.TrainConfig(model_dir=str(model_dir))
  model = models.build_model(models.ModelConfig(
      separation_widths=(4, 4), stereo_features=4, stereo_residual_blocks=1,
      stereo_3d_widths=(4,), max_disparity=8))
  optimizer = tf.keras.optimizers.RMSprop(config.learning_rate)
  optimizer.build(model.trainable_variables)
  tf.train.Checkpoint(model=model, optimizer=optimizer).restore(
      saved).assert_existing_objects_matched()
  assert int(optimizer.iterations.numpy()) == saved_step
  reader = tf.train.load_checkpoint(saved)
  # The optimizer tracks the trainable variables in model order: every one is restored.
  for i, variable in enumerate(model.trainable_variables):
    stored = reader.get_tensor(f'optimizer/_trainable_variables/{i}/.ATTRIBUTES/VARIABLE_VALUE')
    np.testing.assert_array_equal(variable.numpy(), stored)

  second = _train_cli(model_dir, f'--num_steps={saved_step + 2}', '--checkpoint_every=1')
  output = second.communicate(timeout=240)[0]
  assert second.returncode == 0, output
  assert f'Resumed from {saved} at step {saved_step}.' in output
  resumed = tf.train.latest_checkpoint(str(model_dir))
  assert resumed.endswith(f'ckpt-{saved_step + 2}')
  # The second run continued from the saved weights: two RMSProp steps move a weight by at
  # most ~2 x 3.2 x lr (first-step update lr / sqrt(1 - rho)), while a fresh
  # initialisation would differ by O(0.1).
  later = tf.train.load_checkpoint(resumed)
  for i in range(len(model.trainable_variables)):
    key = f'optimizer/_trainable_variables/{i}/.ATTRIBUTES/VARIABLE_VALUE'
    change = np.abs(later.get_tensor(key) - reader.get_tensor(key)).max()
    assert change <= 10 * config.learning_rate, (key, change)

  # Resuming under another mixture would train it under the old run's label: refused.
  third = _train_cli(model_dir, f'--num_steps={saved_step + 4}', '--mixture=diplopia')
  output = third.communicate(timeout=240)[0]
  assert third.returncode != 0 and "--mixture: 'anaglyph' -> 'diplopia'" in output
  assert tf.train.latest_checkpoint(str(model_dir)) == resumed


def test_jit_compile_true_trains_on_pipeline_batches(tmp_path):
  process = _train_cli(tmp_path / 'run', '--num_steps=2', '--jit_compile=true',
                       '--checkpoint_every=1')
  output = process.communicate(timeout=240)[0]
  assert process.returncode == 0, output[-3000:]
  assert 'jit_compile=True; conv3d dense' in output  # conv3d.auto_implementation on CPU.
  assert tf.train.latest_checkpoint(str(tmp_path / 'run')).endswith('ckpt-2')


def test_bad_flags_are_usage_errors_naming_the_flag(tmp_path):
  process = _train_cli(tmp_path / 'run', '--num_steps=1', '--crop_width=62')
  output = process.communicate(timeout=120)[0]
  assert process.returncode != 0
  assert '--crop_width=62 must be a multiple of' in output
  process = _train_cli(tmp_path / 'run', '--num_steps=0')
  output = process.communicate(timeout=120)[0]
  assert process.returncode != 0 and '--num_steps=0: 0 is not a positive integer' in output
  process = _train_cli(tmp_path / 'run', '--num_epochs=0')
  output = process.communicate(timeout=120)[0]
  assert process.returncode != 0 and '--num_epochs must be positive' in output
  process = _train_cli(tmp_path / 'seeded', '--num_steps=1', '--seed=-5')
  output = process.communicate(timeout=120)[0]
  assert process.returncode != 0 and '--seed=-5' in output and 'Traceback' not in output
  assert not os.path.exists(tmp_path / 'seeded' / 'config.json')  # Refused before writing.


def test_a_pair_that_does_not_decode_stops_with_its_list_line_not_a_traceback(tmp_path):
  data_dir = str(tmp_path / 'raw')
  kitti_test._raw_frame(data_dir, '0000000001')
  kitti_test._raw_frame(data_dir, '0000000002')
  broken = os.path.join(data_dir, kitti_test._DRIVE, 'image_02', 'data', '0000000002.png')
  with open(broken, 'wb') as f:
    f.write(b'not a png')
  listed = kitti_test._list(tmp_path, '\n'.join(kitti_test._entry(f'000000000{i}', '.png')
                                                for i in (1, 2)))
  process = _train_cli(tmp_path / 'run', '--num_steps=4', '--dataset=kitti_raw',
                       f'--data_dir={data_dir}', f'--train_list={listed}')
  output = process.communicate(timeout=240)[0]
  assert process.returncode == 1 and 'Traceback' not in output, output[-3000:]
  assert 'error: ValueError: ' in output and 'files.txt:2: ' in output
  assert 'run the same command to resume' in output


def test_a_few_dozen_steps_on_the_sample_source_lower_the_loss(tmp_path):
  samples = sample.sample_records('train', num_scenes=20, height=32, width=64,
                                  max_disparity=8)
  config = pipeline.PipelineConfig(crop_height=32, crop_width=64, seed=1, augment=False)
  probe = next(iter(pipeline.train_dataset(samples, dataclasses.replace(config, batch_size=4))))
  model_config = models.ModelConfig(separation_widths=(16, 16, 16), stereo_features=4,
                                    stereo_residual_blocks=1, stereo_3d_widths=(4,),
                                    max_disparity=8)

  def probe_loss(checkpoint=None):
    model = models.build_model(model_config)
    if checkpoint:
      tf.train.Checkpoint(model=model).read(checkpoint).expect_partial()
    outputs = step_lib.forward(model, probe, 'joint', training=True)
    return float(objective.total_loss(outputs, probe, objective.LossConfig(), 'joint')['loss'])

  tf.keras.utils.set_random_seed(0)
  initial = probe_loss()
  result = loop.train(
      config_lib.TrainConfig(model_dir=str(tmp_path), num_steps=150, learning_rate=2e-3,
                             checkpoint_every=1000, summary_every=1000,
                             image_summary_every=1000, log_every=10),
      model_config, objective.LossConfig(),
      lambda start: pipeline.train_dataset(samples, config, start))
  trained = probe_loss(result.last_checkpoint)
  # The untrained U-Net outputs ~0 (L1 of about 0.25 per view on the [0, 1] loss scale);
  # 150 steps of TF1 RMSProp (its accumulator starts at one: a warm-up of a few tens of
  # steps) learn to copy the observed channels. Measured once: 0.598 -> 0.376 (x0.63).
  assert trained < 0.75 * initial, (initial, trained)


def _free_port():
  with socket.socket() as s:
    s.bind(('localhost', 0))
    return s.getsockname()[1]


def test_multi_worker_strategy_from_tf_config_trains_with_two_workers(tmp_path):
  cluster = {'worker': [f'localhost:{_free_port()}', f'localhost:{_free_port()}']}
  workers = []
  for index in range(2):
    os.environ['TF_CONFIG'] = json.dumps({'cluster': cluster,
                                          'task': {'type': 'worker', 'index': index}})
    try:
      workers.append(_train_cli(tmp_path / 'run', '--strategy=multi_worker',
                                '--batch_size=2', '--num_steps=2', '--checkpoint_every=1'))
    finally:
      del os.environ['TF_CONFIG']
  outputs = [w.communicate(timeout=300)[0] for w in workers]
  for worker, output in zip(workers, outputs):
    assert worker.returncode == 0, output[-3000:]
  assert 'with 2 replica(s)' in outputs[0]
  # Only the chief (worker 0) writes into model_dir.
  assert tf.train.latest_checkpoint(str(tmp_path / 'run')).endswith('ckpt-2')


def test_bad_refiner_flags_are_usage_errors_naming_the_flag(tmp_path):
  for flag, message in (('--refiner_disparity_features=0',
                         '--refiner_disparity_features must be positive'),
                        ('--refiner_base=anaglyph', "--refiner_base 'anaglyph'")):
    process = _train_cli(tmp_path / 'run', '--architecture=refiner', '--num_steps=1', flag)
    output = process.communicate(timeout=120)[0]
    assert process.returncode != 0 and message in output, output[-2000:]


def test_bad_real_pair_flags_are_usage_errors_naming_the_flag(tmp_path):
  for flags, message in ((['--real_pair_probability=0.5'],
                          '--real_pair_probability > 0 needs --real_pairs'),
                         (['--real_pairs=motorcycle', '--real_pair_probability=2'],
                          '--real_pair_probability must lie in [0, 1]')):
    process = _train_cli(tmp_path / 'run', '--architecture=features', '--num_steps=1', *flags)
    output = process.communicate(timeout=120)[0]
    assert process.returncode != 0 and message in output, output[-2000:]


def test_a_typed_length_replaces_the_flagfile_one_and_two_typed_are_refused(tmp_path):
  flagfile = tmp_path / 'recipe.flags'
  flagfile.write_text('--num_epochs=3\n')
  process = _train_cli(tmp_path / 'run', f'--flagfile={flagfile}', '--num_steps=1')
  output = process.communicate(timeout=240)[0]
  assert process.returncode == 0, output[-2000:]
  assert '--num_steps=1 on the command line replaces --num_epochs=3.0 of the flagfile' in output
  assert tf.train.latest_checkpoint(str(tmp_path / 'run')).endswith('ckpt-1')
  process = _train_cli(tmp_path / 'both', '--num_epochs=3', '--num_steps=1')
  output = process.communicate(timeout=120)[0]
  assert process.returncode != 0
  assert '(both given: --num_steps=1, --num_epochs=3.0)' in output


def test_a_stopped_stage_training_exits_with_the_signal_code_after_its_checkpoint(tmp_path):
  process = _train_cli(tmp_path / 'run', '--architecture=refiner', '--num_steps=100000',
                       '--checkpoint_every=100000', '--sample_scenes=8')
  _wait_for_step(process, 2)
  process.send_signal(signal.SIGTERM)
  output = process.communicate(timeout=120)[0]
  assert process.returncode == 128 + signal.SIGTERM, output[-2000:]
  assert 'Stopped by SIGTERM at step' in output and 'Traceback' not in output
  assert tf.train.latest_checkpoint(str(tmp_path / 'run')) is not None


def test_a_tiny_network_with_the_census_cost_trains(tmp_path):
  process = _train_cli(tmp_path / 'run', '--census_cost', '--num_steps=1')
  output = process.communicate(timeout=240)[0]
  assert process.returncode == 0, output[-2000:]
  process = _train_cli(tmp_path / 'small', '--census_cost', '--num_steps=1',
                       '--unet_widths=4,4,4,4', '--crop_height=8', '--sample_height=8')
  output = process.communicate(timeout=120)[0]
  assert process.returncode != 0
  assert '--crop_height=8 must be a multiple of 8 for this architecture, at least 16' in output


def test_op_errors_name_the_failing_op_and_hint_at_data_only_for_the_pipeline():
  model = ('Exception encountered when calling StereoNet.call().\n\n\x1b[1m{{function_node '
           '__wrapped__MirrorPad_device_/job:localhost/replica:0/task:0/device:CPU:0}} '
           'paddings must be less than the dimension size [Op:MirrorPad]\x1b[0m\n\nArguments')
  assert train._op_error_line(tf.errors.InvalidArgumentError(None, None, model)) == (
      'paddings must be less than the dimension size [Op:MirrorPad]', False)
  data = 'Traceback\nValueError: files.txt:3: Image not found: x.png\n\t [[{{node PyFunc}}]]'
  assert train._op_error_line(tf.errors.InvalidArgumentError(None, None, data)) == (
      'ValueError: files.txt:3: Image not found: x.png', True)
