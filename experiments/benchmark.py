r"""Performance benchmark of the whole system on this machine, in one run.

  python experiments/benchmark.py [--output=experiments/BENCHMARKS.md]
      [--baseline_json=before.json] [--json_out=after.json] [--label=after]

Every measurement runs in a fresh subprocess of this script (`--worker=...`), so peak
resident memory (VmHWM) is per measurement and an out-of-memory crash ends only that row.
Measurements: machine limits (conv3d, matmul), train steps (paper and demo configurations,
XLA on / off), analytic FLOPs per step, a per-module split of forward+backward time, the
input pipeline, SavedModel inference, the warp op against a gather-based reference, and the
stride-2 3D conv implementations, the paper-scale forward pass, the classical baseline
per 375x1242 frame, where the 3D encoder-decoder's time goes (per layer and per
stride-2 kernel), and the numba census-SGM matcher (`classical.matcher.match`) at 1242x375,
1280x720 (also with a video prior) and 4000x3000, against the NumPy `sgm.match`, and
videos (`benchmark_video`: flicker, accuracy and frames/s with and without the temporal
prior, both methods, 720p and 1080p). Times are medians of repeats after warm-up, with min/max.
With --baseline_json (a --json_out of an earlier run) the table gets a 'before' column.
Not a test: the machine is shared; the load average is recorded with the results.
"""

import datetime
import json
import os
import platform
import shlex
import subprocess
import sys
import tempfile

from absl import app
from absl import flags

flags.DEFINE_string('output', 'experiments/BENCHMARKS.md', 'Markdown report to write.')
flags.DEFINE_string('json_out', '', 'Optional JSON dump of all results (for a later '
                    '--baseline_json).')
flags.DEFINE_string('baseline_json', '', 'Results of an earlier run shown as "before".')
flags.DEFINE_string('label', 'this run', 'Name of this run in the report.')
flags.DEFINE_string('baseline_label', 'before', 'Name of the baseline run in the report.')
flags.DEFINE_string('baseline_note', '', 'What the baseline tree was (printed under its '
                    'machine line).')
flags.DEFINE_integer('paper_steps', 1, 'Timed train steps at paper scale (after warm-up).')
flags.DEFINE_integer('demo_steps', 20, 'Timed train steps of the demo configuration.')
flags.DEFINE_integer('timeout', 480, 'Seconds before a measurement subprocess is killed.')
flags.DEFINE_list('sections', ['machine', 'train', 'modules', 'pipeline', 'inference',
                               'warp', 'conv3d', 'forward', 'classical', 'layers',
                               'matcher', 'video'],
                  'Sections to run.')
flags.DEFINE_string('worker', '', 'Internal: run one measurement and print its JSON.')
flags.DEFINE_string('worker_args', '{}', 'Internal: JSON arguments of --worker.')
FLAGS = flags.FLAGS

_RESULT = 'BENCHMARK_RESULT '
INFERENCE_SIZES = ((375, 1242), (384, 384))
# Tried in order when 375x1242 does not run, to find the largest size that does.
FALLBACK_SIZES = ((320, 1024), (256, 832), (256, 512))
# experiments/benchmark_matcher.CASES; the NumPy matcher runs on the first two only.
MATCHER_CASES = ('1242x375', '1280x720', '4000x3000')


def machine_description() -> dict:
  """CPU model, core count, TF version, date and load average."""
  import tensorflow as tf  # pylint: disable=g-import-not-at-top
  model = platform.processor() or 'unknown'
  with open('/proc/cpuinfo') as f:
    for line in f:
      if line.startswith('model name'):
        model = line.split(':', 1)[1].strip()
        break
  with open('/proc/meminfo') as f:
    memory = int(f.readline().split()[1]) / 2**20
  return {'cpu': model, 'cores': os.cpu_count(), 'memory_gib': round(memory, 1),
          'tensorflow': tf.__version__, 'python': platform.python_version(),
          'date': datetime.datetime.now().strftime('%Y-%m-%d %H:%M'),
          'load': os.getloadavg()}


def run_worker(name: str, timeout: int, **kwargs) -> dict:
  """Runs one measurement in a fresh process; failures become {'error': reason}."""
  command = [sys.executable, os.path.abspath(__file__), f'--worker={name}',
             f'--worker_args={json.dumps(kwargs)}']
  print(f'[benchmark] {name} {kwargs}', flush=True)
  load = os.getloadavg()[0]
  try:
    done = subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                          check=False)
  except subprocess.TimeoutExpired:
    return {'error': f'timed out after {timeout} s', 'load': load}
  for line in done.stdout.splitlines():
    if line.startswith(_RESULT):
      result = json.loads(line[len(_RESULT):])
      result['load'] = load
      print(f'[benchmark]   -> {result}', flush=True)
      return result
  tail = [l for l in done.stderr.splitlines() if l.strip()][-3:]
  reason = f'exit code {done.returncode}: ' + ' | '.join(tail)
  if 'bad_alloc' in done.stderr or done.returncode == -9:
    reason = f'out of memory (exit code {done.returncode}, ' + (
        'std::bad_alloc)' if 'bad_alloc' in done.stderr else 'killed)')
  print(f'[benchmark]   -> failed: {reason}', flush=True)
  return {'error': reason, 'load': load}


def collect(steps_paper: int, steps_demo: int, timeout: int, sections) -> dict:
  """Runs every requested measurement; returns {row key: result dict}."""
  results = {}
  if 'machine' in sections:
    results['machine/conv3d'] = run_worker('conv3d_peak', timeout)
    results['machine/matmul'] = run_worker('matmul_peak', timeout)
  if 'train' in sections:
    for config, steps in (('paper', steps_paper), ('demo', steps_demo)):
      for jit in (False, True):
        results[f'train/{config}/jit={jit}'] = run_worker(
            'train', timeout, config=config, jit=jit, steps=steps)
  if 'modules' in sections:
    results['modules/paper'] = run_worker('modules', timeout, config='paper')
    results['flops/paper'] = run_worker('flops', timeout, config='paper')
    results['flops/demo'] = run_worker('flops', timeout, config='demo')
  if 'pipeline' in sections:
    results['pipeline'] = run_worker('pipeline', timeout)
  if 'inference' in sections:
    with tempfile.TemporaryDirectory() as root:
      export_dir = os.path.join(root, 'export')
      results['inference/export'] = run_worker('export', timeout, export_dir=export_dir)
      if 'error' not in results['inference/export']:
        for height, width in INFERENCE_SIZES:
          results[f'inference/{height}x{width}'] = run_worker(
              'inference', timeout, export_dir=export_dir, height=height, width=width)
        if 'error' in results['inference/375x1242']:
          for height, width in FALLBACK_SIZES:
            key = f'inference/{height}x{width}'
            results[key] = run_worker('inference', timeout, export_dir=export_dir,
                                      height=height, width=width)
            if 'error' not in results[key]:
              break
  if 'warp' in sections:
    results['warp'] = run_worker('warp', timeout)
  if 'conv3d' in sections:
    for implementation in ('native', 'dense'):
      results[f'conv3d/{implementation}'] = run_worker('conv3d_impl', timeout,
                                                       implementation=implementation)
  if 'forward' in sections:
    results['forward/paper'] = run_worker('forward', timeout, config='paper')
  if 'classical' in sections:
    results['classical'] = run_worker('classical', timeout)
  if 'layers' in sections:
    results['layers'] = run_worker('layers', timeout)
    results['stride2_kernels'] = run_worker('stride2_kernels', timeout)
  if 'matcher' in sections:
    for case in MATCHER_CASES:
      results[f'matcher/{case}'] = run_worker('matcher', timeout, case=case)
    for case in MATCHER_CASES[:2]:
      results[f'matcher/{case}/numpy'] = run_worker('matcher', timeout, case=case,
                                                    method='numpy')
  if 'video' in sections:
    from experiments import benchmark_video  # pylint: disable=g-import-not-at-top
    results.update(benchmark_video.collect(run_worker, timeout))
  return results


def run_here(name: str, args: dict) -> dict:
  """Runs measurement `name` in this process; adds the process' peak memory."""
  # pylint: disable=g-import-not-at-top (TensorFlow only in the worker processes)
  from experiments import benchmark_matcher
  from experiments import benchmark_ops
  from experiments import benchmark_video
  from experiments import benchmark_workers
  every = dict(benchmark_workers.WORKERS, **benchmark_ops.WORKERS,
               **benchmark_matcher.WORKERS, **benchmark_video.WORKERS)
  if name not in every:
    raise ValueError(f'--worker must be one of {sorted(every)}, got {name!r}.')
  result = every[name](**args)
  result['peak_gib'] = benchmark_workers.peak_gib()
  return result


def main(argv):
  del argv
  if FLAGS.worker:
    print(_RESULT + json.dumps(run_here(FLAGS.worker, json.loads(FLAGS.worker_args))),
          flush=True)
    return
  from experiments import benchmark_report  # pylint: disable=g-import-not-at-top
  command = 'python ' + ' '.join(shlex.quote(a) for a in
                                 [os.path.relpath(__file__, os.getcwd())] + sys.argv[1:])
  machine = machine_description()
  results = collect(FLAGS.paper_steps, FLAGS.demo_steps, FLAGS.timeout, FLAGS.sections)
  machine['load_after'] = os.getloadavg()
  run = {'label': FLAGS.label, 'command': command, 'machine': machine, 'results': results}
  baseline = None
  if FLAGS.baseline_json:
    with open(FLAGS.baseline_json) as f:
      baseline = json.load(f)
  if FLAGS.json_out:
    with open(FLAGS.json_out, 'w') as f:
      json.dump(run, f, indent=1)
  text = benchmark_report.render(run, baseline, FLAGS.baseline_label, FLAGS.baseline_note)
  with open(FLAGS.output, 'w') as f:
    f.write(text)
  print(text)


if __name__ == '__main__':
  sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
  app.run(main)
