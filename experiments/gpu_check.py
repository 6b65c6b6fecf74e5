r"""The paper's path on this machine's accelerator: what runs, how fast, in how much memory.

  bash experiments/gpu_check.sh            # the paper's configuration (meant for a GPU)
  bash experiments/gpu_check.sh --small    # the demo's small network (proves it on a CPU)

Writes experiments/results/gpu_check.md: the environment (versions, the device line, TF32,
oneDNN); training steps/s of the paper's joint network (17.2M parameters, 256x512 crops,
96 levels, batch 1, the paper's loss and TF1 RMSProp) with XLA off and on, in float32 and
with --mixed_precision, each with its first step (tracing and XLA compilation) apart and
its peak memory; and one SavedModel inference on a 375x1242 KITTI-sized frame. Every
measurement runs in a fresh process (peak memory, dtype policy and XLA caches of its own)
on one constant batch: the input pipeline is not timed. Meant to take under 10 minutes on
one GPU (not yet run on one; XLA's compile time is the unknown): each variant times at
most --check_steps steps or --check_seconds, and a worker is stopped after 5 minutes.
"""

import dataclasses
import datetime
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time

from absl import app
from absl import flags

flags.DEFINE_enum('check_config', os.environ.get('GPU_CHECK_CONFIG', 'paper'),
                  ('paper', 'small'), "paper: the paper's network and crop; small: "
                  "experiments/demo.flags' network and crop (a CPU proof run).")
flags.DEFINE_integer('check_steps', 50, 'Timed training steps per variant (at most).')
flags.DEFINE_float('check_seconds', 30.0, 'Timing window per variant, after its first step '
                   '(at least 2 steps are timed).')
flags.DEFINE_string('check_output', 'experiments/results/gpu_check.md',
                    'The Markdown report.')
flags.DEFINE_string('check_worker', None, "Internal: 'train' or 'saved_model' (one "
                    'measurement in this process, printed as JSON).')
flags.DEFINE_boolean('check_xla', False, "Internal: the worker's jit_compile.")
flags.DEFINE_boolean('check_mixed', False, "Internal: the worker's --mixed_precision.")
FLAGS = flags.FLAGS

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MARK = 'GPU_CHECK_RESULT '
FRAME = (375, 1242)  # A KITTI frame.
VARIANTS = ((False, False), (True, False), (False, True), (True, True))  # (XLA, mixed).
WORKER_TIMEOUT_S = 300


def _configs():
  """{name: (ModelConfig, crop)}: the paper's defaults and the demo's small network."""
  from mixstereo_tf import models  # pylint: disable=g-import-not-at-top
  small = models.ModelConfig(separation_widths=(16, 32, 32, 64, 64, 64), stereo_features=8,
                             stereo_residual_blocks=2, stereo_3d_widths=(8, 8, 8, 16),
                             max_disparity=32)
  return {'paper': (models.ModelConfig(), (256, 512)), 'small': (small, (64, 128))}


def _device_type(tf) -> str:
  return 'GPU' if tf.config.list_logical_devices('GPU') else 'CPU'


def _peak_memory(tf, device_type: str) -> int:
  """Bytes: TensorFlow's GPU allocator peak, or on a CPU the process' peak resident size."""
  if device_type == 'GPU':
    return int(tf.config.experimental.get_memory_info('GPU:0')['peak'])
  import resource  # pylint: disable=g-import-not-at-top
  return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def _batch(tf, crop, shift=4):
  """A textured pair with constant disparity `shift` and its anaglyph, in [-1, 1]."""
  from mixstereo_tf.core import mixtures  # pylint: disable=g-import-not-at-top
  height, width = crop
  texture = tf.random.stateless_uniform([1, height, width + shift, 3], [0, 1], -1.0, 1.0)
  left, right = texture[:, :, shift:], texture[:, :, :width]
  return {'left': left, 'right': right, 'mixture': mixtures.mix('anaglyph', left, right)}


def measure_training(xla: bool, mixed: bool) -> dict:
  """One variant's first step and steps/s (this process: fresh policy and caches)."""
  # pylint: disable=g-import-not-at-top
  from mixstereo_tf.cli import startup  # pylint: disable=unused-import (quiet TF)
  import tensorflow as tf
  from mixstereo_tf import models
  from mixstereo_tf.ops import conv3d
  from mixstereo_tf.training import objective
  from mixstereo_tf.training import optimizers
  from mixstereo_tf.training import step as step_lib
  device_type = _device_type(tf)
  policy = step_lib.precision_policy(mixed, device_type)
  tf.keras.mixed_precision.set_global_policy(policy)
  tf.keras.utils.set_random_seed(0)
  config, crop = _configs()[FLAGS.check_config]
  config = dataclasses.replace(
      config, conv3d_implementation=conv3d.auto_implementation(device_type, xla))
  model = models.build_model(config)
  optimizer = optimizers.make_optimizer('rmsprop_tf1', 1e-4)
  if policy == 'mixed_float16':  # As training/loop.py does.
    optimizer = tf.keras.mixed_precision.LossScaleOptimizer(optimizer)
  trainer = step_lib.TrainStep(model, optimizer, objective.LossConfig(), 'joint',
                               tf.distribute.get_strategy(), xla)
  optimizer.build(trainer.variables)
  batch = _batch(tf, crop)
  start = time.perf_counter()
  loss = float(trainer(batch)[0]['loss'])
  first = time.perf_counter() - start
  steps, start = 0, time.perf_counter()
  window = FLAGS.check_seconds
  while steps < FLAGS.check_steps and (steps < 2 or time.perf_counter() - start < window):
    loss = float(trainer(batch)[0]['loss'])  # The loop reads the loss every step too.
    steps += 1
  seconds = time.perf_counter() - start
  return {'xla': xla, 'mixed': mixed, 'policy': policy, 'device': device_type,
          'conv3d': config.conv3d_implementation, 'first_step_s': first, 'steps': steps,
          'steps_per_s': steps / seconds, 'peak_bytes': _peak_memory(tf, device_type),
          'final_loss': loss, 'parameters': int(model.count_params())}


def measure_saved_model() -> dict:
  """Export of the configuration's model (seed-0 weights), load, and a 375x1242 frame."""
  # pylint: disable=g-import-not-at-top
  from mixstereo_tf.cli import startup  # pylint: disable=unused-import (quiet TF)
  import numpy as np
  import tensorflow as tf
  from mixstereo_tf import models
  from mixstereo_tf.artifacts import graphs
  from mixstereo_tf.artifacts import runs
  from mixstereo_tf.artifacts import serving
  device_type = _device_type(tf)
  tf.keras.utils.set_random_seed(0)
  config, crop = _configs()[FLAGS.check_config]
  model = models.build_model(config)
  times = {}
  with tempfile.TemporaryDirectory() as folder:
    start = time.perf_counter()
    serving.export_saved_model(graphs.serving_function(model), model.variables,
                               runs.RunInfo('anaglyph', crop[0], crop[1], config), folder)
    times['export_s'] = time.perf_counter() - start
    start = time.perf_counter()
    unmix = tf.saved_model.load(folder).signatures['serving_default']
    times['load_s'] = time.perf_counter() - start
    frame = tf.constant(np.random.default_rng(0).integers(0, 256, (*FRAME, 3), np.uint8))
    calls = []
    for _ in range(4):
      start = time.perf_counter()
      outputs = unmix(image=frame)
      float(tf.reduce_mean(outputs['disparity']))  # Waits for the device.
      calls.append(time.perf_counter() - start)
  return dict(times, device=device_type, first_call_s=calls[0],
              later_call_s=sum(calls[1:]) / 3, shape=list(outputs['disparity'].shape),
              peak_bytes=_peak_memory(tf, device_type))


def _worker_result(*args) -> dict:
  """Runs one measurement in a fresh process; its result, or {'error': tail of stderr}."""
  command = [sys.executable, os.path.abspath(__file__), f'--check_config={FLAGS.check_config}',
             f'--check_steps={FLAGS.check_steps}', f'--check_seconds={FLAGS.check_seconds}',
             *args]
  print('[gpu_check]', ' '.join(command[2:]), flush=True)
  try:
    result = subprocess.run(command, cwd=REPO, capture_output=True, text=True,
                            timeout=WORKER_TIMEOUT_S, check=False)
  except subprocess.TimeoutExpired:
    return {'error': f'did not finish in {WORKER_TIMEOUT_S} s'}
  for line in result.stdout.splitlines():
    if line.startswith(MARK):
      return json.loads(line[len(MARK):])
  tail = [line for line in result.stderr.splitlines() if line.strip()][-3:]
  return {'error': f'exit {result.returncode}: ' + ' / '.join(tail)[-400:]}


def environment() -> dict:
  """Versions and devices, read without starting TensorFlow's devices (the workers' GPU
  memory stays theirs)."""
  # pylint: disable=g-import-not-at-top
  from mixstereo_tf.cli import startup  # pylint: disable=unused-import (quiet TF)
  import keras
  import tensorflow as tf
  from mixstereo_tf.cli import device
  build = tf.sysconfig.get_build_info()
  driver = 'no nvidia-smi'
  if shutil.which('nvidia-smi'):
    driver = subprocess.run(
        ['nvidia-smi', '--query-gpu=name,driver_version,memory.total', '--format=csv,noheader'],
        capture_output=True, text=True, check=False).stdout.strip().replace('\n', '; ')
  return {'device line': device.line(), 'Python': platform.python_version(),
          'TensorFlow': f'{tf.__version__} (built for CUDA {build.get("cuda_version", "-")}, '
                        f'cuDNN {build.get("cudnn_version", "-")})',
          'Keras': keras.__version__, 'nvidia-smi': driver or 'no GPU listed',
          'TF32': ('on (TensorFlow default: float32 convolutions and matmuls in TF32 on '
                   'Ampere and newer)' if tf.config.experimental.tensor_float_32_execution_enabled()
                   else 'off'),
          'oneDNN (CPU kernels)': device.onednn_state(),
          'CPU': f'{_cpu_name()}, {os.cpu_count()} logical cores',
          'XLA_FLAGS / TF_XLA_FLAGS': f'{os.environ.get("XLA_FLAGS", "-")} / '
                                      f'{os.environ.get("TF_XLA_FLAGS", "-")}'}


def _cpu_name() -> str:
  try:
    with open('/proc/cpuinfo', encoding='utf-8') as f:
      names = [line.split(':', 1)[1].strip() for line in f if line.startswith('model name')]
  except OSError:
    names = []
  return names[0] if names else (platform.processor() or platform.machine())


def _gib(value: int) -> str:
  return f'{value / 1024 ** 3:.2f} GiB'


def _training_rows(results) -> list:
  rows = ['| XLA | precision | first step, s (trace + compile) | steps timed | steps/s | '
          's/step | peak memory |', '| --- | --- | ---: | ---: | ---: | ---: | ---: |']
  for (xla, mixed), r in zip(VARIANTS, results):
    name = f'| {"on" if xla else "off"} | {"mixed" if mixed else "float32"}'
    if 'error' in r:
      rows.append(f'{name} ({r.get("policy", "-")}) | failed: {r["error"]} | | | | |')
      continue
    rows.append(f'{name} ({r["policy"]}) | {r["first_step_s"]:.1f} | {r["steps"]} | '
                f'{r["steps_per_s"]:.3f} | {1 / r["steps_per_s"]:.3f} | '
                f'{_gib(r["peak_bytes"])} |')
  return rows


def markdown(env: dict, results, inference: dict, seconds: float) -> str:
  """The report (module docstring)."""
  on_gpu = env['device line'].startswith('GPU')
  config, crop = _configs()[FLAGS.check_config]
  small = '' if FLAGS.check_config == 'paper' else ' --small'
  params = next((r['parameters'] for r in results if 'parameters' in r), None)
  lines = ['# GPU check', '',
           f'Written by `bash experiments/gpu_check.sh{small}`'
           f' on {datetime.date.today().isoformat()} in {seconds / 60:.1f} min. '
           + ('' if on_gpu else '**No GPU was available: this is a CPU run**, which proves the '
              'script, not the GPU path; its numbers say nothing about a GPU.'), '',
           f'Configuration `{FLAGS.check_config}`: {params:,} parameters, max_disparity '
           f'{config.max_disparity}, {crop[0]}x{crop[1]} crops, batch 1, the paper\'s loss, '
           'TF1 RMSProp; one constant batch (no input pipeline).' if params else '', '',
           '## Environment', '', '| | |', '| --- | --- |']
  lines += [f'| {key} | {value} |' for key, value in env.items()]
  lines += ['', '## Training steps', '', *_training_rows(results), '',
            'Peak memory: TensorFlow\'s GPU allocator peak, or on a CPU the process\' peak '
            'resident size (TensorFlow itself included). mixed on a GPU is mixed_float16 with '
            'loss scaling; on a CPU mixed_bfloat16.', '',
            f'## SavedModel inference, one {FRAME[0]}x{FRAME[1]} frame', '']
  if 'error' in inference:
    lines.append(f'failed: {inference["error"]}')
  else:
    lines += ['| export, s | load, s | first call, s | later calls, s (mean of 3) | '
              'disparity shape | peak memory |', '| ---: | ---: | ---: | ---: | --- | ---: |',
              f'| {inference["export_s"]:.1f} | {inference["load_s"]:.1f} | '
              f'{inference["first_call_s"]:.2f} | {inference["later_call_s"]:.3f} | '
              f'{inference["shape"]} | {_gib(inference["peak_bytes"])} |']
  return '\n'.join(lines) + '\n'


def main(argv):
  del argv
  if FLAGS.check_worker:
    result = (measure_training(FLAGS.check_xla, FLAGS.check_mixed)
              if FLAGS.check_worker == 'train' else measure_saved_model())
    print(MARK + json.dumps(result), flush=True)
    return
  start = time.perf_counter()
  env = environment()
  print('[gpu_check]', env['device line'], flush=True)
  results = [_worker_result('--check_worker=train', f'--check_xla={xla}',
                            f'--check_mixed={mixed}') for xla, mixed in VARIANTS]
  inference = _worker_result('--check_worker=saved_model')
  text = markdown(env, results, inference, time.perf_counter() - start)
  os.makedirs(os.path.dirname(FLAGS.check_output) or '.', exist_ok=True)
  with open(FLAGS.check_output, 'w', encoding='utf-8') as f:
    f.write(text)
  print(text)


if __name__ == '__main__':
  app.run(main)
