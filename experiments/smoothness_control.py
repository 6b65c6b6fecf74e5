r"""Issue 29's control: does the smoothness term omega_s L_s change training at all?

  nice -n 10 python experiments/smoothness_control.py --control_steps=1000 \
      [--control_runs_dir=runs/smoothness_control] \
      [--control_table=experiments/results/smoothness_control.md]

L_s sees disparities in fractions of the image width (`--smoothness_scale=width`, the
paper's flagfiles; in pixels the shipped omega_s = 0.05 collapses the disparity,
`fidelity.md`), which shrinks its gradient by the width. This script trains the demo
configuration (experiments/demo.flags, seed 0) shortened to --control_steps, once with omega_s
as shipped and once with omega_s = 0; evaluates both on the `sample` held-out set (8
procedural scenes + Motorcycle); and measures, on training batches, the gradient that
omega_s L_s sends to the stereo network's weights and to the disparities next to that of
omega_w L_w. A finished run is not trained again and its evaluation is kept. The table's
reading (machine, interpretation) is appended by hand.
"""

import csv
import json
import os
import statistics
import subprocess
import sys
import time

from absl import app
from absl import flags

flags.DEFINE_integer('control_steps', 1000, 'Training steps of each run (the demo: 7000).')
flags.DEFINE_string('control_runs_dir', 'runs/smoothness_control', 'Where the two runs go.')
flags.DEFINE_string('control_table', 'experiments/results/smoothness_control.md',
                    'The Markdown table.')
flags.DEFINE_integer('control_batches', 8, 'Training batches the gradients are averaged over.')
FLAGS = flags.FLAGS

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHIPPED_OMEGA_S = 0.05  # objective.LossConfig's default and every paper flagfile's.
METRICS = ('psnr_left', 'psnr_right', 'bad1', 'bad3', 'epe')


def _run(*args) -> float:
  """Runs a module of this repository; returns its wall time in seconds."""
  command = [sys.executable, *args]
  print('[smoothness_control]', ' '.join(command), flush=True)
  start = time.perf_counter()
  subprocess.run(command, cwd=REPO, check=True)
  return time.perf_counter() - start


def train_and_evaluate(omega_s: float) -> str:
  """Trains (or resumes) one run and evaluates it; returns its run directory."""
  model_dir = os.path.join(FLAGS.control_runs_dir, f'omega_s_{omega_s:g}')
  seconds = _run('-m', 'mixstereo_tf.train', '--flagfile=experiments/demo.flags',
                 f'--model_dir={model_dir}', f'--num_steps={FLAGS.control_steps}',
                 f'--checkpoint_every={FLAGS.control_steps}', f'--omega_s={omega_s}',
                 '--seed=0')
  with open(os.path.join(model_dir, 'train_seconds.txt'), 'a', encoding='utf-8') as f:
    f.write(f'{seconds:.1f}\n')
  if not os.path.exists(os.path.join(model_dir, 'heldout.csv')):
    _run('-m', 'mixstereo_tf.evaluate', '--protocol=sample', f'--checkpoint={model_dir}',
         f'--output_csv={os.path.join(model_dir, "heldout.csv")}')
  return model_dir


def heldout_means(model_dir: str) -> dict:
  """Means over the held-out images of the evaluation CSV's metrics."""
  with open(os.path.join(model_dir, 'heldout.csv'), newline='', encoding='utf-8') as f:
    rows = list(csv.DictReader(f))
  return {key: statistics.mean(float(r[key]) for r in rows) for key in METRICS}


def _batches(model_dir: str, count: int):
  """The first `count` training batches of the run's own pipeline (seeded)."""
  # pylint: disable=g-import-not-at-top
  from mixstereo_tf.data import pipeline
  from mixstereo_tf.data import sources
  with open(os.path.join(model_dir, 'config.json'), encoding='utf-8') as f:
    configs = json.load(f)
  data = sources.DataConfig(**{k: tuple(v) if isinstance(v, list) else v
                               for k, v in configs['data'].items()})
  dataset = pipeline.train_dataset(sources.list_samples(data, 'train'),
                                   pipeline.PipelineConfig(**configs['pipeline']))
  return [{k: v for k, v in b.items() if k != 'name'} for b in dataset.take(count)]


def gradient_ratios(model, batches) -> dict:
  """Mean over batches of |grad omega_s L_s| / |grad omega_w L_w| (shipped weights),
  w.r.t. all the network's weights and w.r.t. the two disparity maps."""
  # pylint: disable=g-import-not-at-top
  import tensorflow as tf
  from mixstereo_tf.training import objective
  from mixstereo_tf.training import step as step_lib
  config = objective.LossConfig(omega_s=SHIPPED_OMEGA_S)
  weights, maps = [], []
  for batch in batches:
    with tf.GradientTape(persistent=True) as tape:
      outputs = step_lib.forward(model, batch, 'joint', training=True)
      terms = objective.stereo_losses(outputs['disparity_left'], outputs['disparity_right'],
                                      batch['left'], batch['right'], config)
      appearance = config.omega_w * (terms['stereo/appearance_left'] +
                                     terms['stereo/appearance_right'])
      smoothness = config.omega_s * (terms['stereo/smoothness_left'] +
                                     terms['stereo/smoothness_right'])
    disparities = [outputs['disparity_left'], outputs['disparity_right']]
    for targets, out in ((model.trainable_variables, weights), (disparities, maps)):
      norms = [tf.linalg.global_norm(tape.gradient(term, targets))
               for term in (smoothness, appearance)]
      out.append(float(norms[0] / norms[1]))
    del tape
  return {'weights': statistics.mean(weights), 'disparities': statistics.mean(maps)}


def measure(model_dirs) -> dict:
  """Gradient ratios at initialisation (seed 0) and at the end of each run."""
  # pylint: disable=g-import-not-at-top
  from mixstereo_tf.cli import startup  # pylint: disable=unused-import (quiet TF)
  import tensorflow as tf
  from mixstereo_tf import models
  from mixstereo_tf.artifacts import runs
  batches = _batches(model_dirs[0], FLAGS.control_batches)
  model, info = runs.load_run(model_dirs[0])
  tf.keras.utils.set_random_seed(0)
  ratios = {'initialisation': gradient_ratios(models.build_model(info.model_config), batches)}
  for model_dir in model_dirs:
    model, _ = runs.load_run(model_dir)
    ratios[os.path.basename(model_dir)] = gradient_ratios(model, batches)
  return ratios


def markdown(results: dict, ratios: dict) -> str:
  """The table of the two runs and the gradient ratios."""
  lines = ['# The smoothness term: omega_s as shipped vs omega_s = 0', '',
           f'Written by `python experiments/smoothness_control.py --control_steps='
           f'{FLAGS.control_steps}`: experiments/demo.flags shortened to {FLAGS.control_steps} '
           'steps (the demo trains 7000), seed 0, smoothness on disparity / width; '
           'evaluated on the `sample` held-out set (8 procedural scenes + Motorcycle).', '',
           '| omega_s | train time (s) | PSNR L | PSNR R | bad-1 | bad-3 | EPE (px) |',
           '| ---: | ---: | ---: | ---: | ---: | ---: | ---: |']
  for omega_s, (seconds, means) in results.items():
    lines.append(f'| {omega_s:g} | {seconds:.0f} | {means["psnr_left"]:.2f} | '
                 f'{means["psnr_right"]:.2f} | {100 * means["bad1"]:.2f}% | '
                 f'{100 * means["bad3"]:.2f}% | {means["epe"]:.2f} |')
  lines += ['', f'Gradient of {SHIPPED_OMEGA_S:g} L_s over that of omega_w L_w (both '
            f'views), mean of {FLAGS.control_batches} training batches:', '',
            '| weights of | w.r.t. the weights | w.r.t. the disparities |',
            '| --- | ---: | ---: |']
  for name, ratio in ratios.items():
    lines.append(f'| {name} | {ratio["weights"]:.2e} | {ratio["disparities"]:.2e} |')
  return '\n'.join(lines) + '\n'


def main(argv):
  del argv
  results, model_dirs = {}, []
  for omega_s in (SHIPPED_OMEGA_S, 0.0):
    model_dir = train_and_evaluate(omega_s)
    model_dirs.append(model_dir)
    with open(os.path.join(model_dir, 'train_seconds.txt'), encoding='utf-8') as f:
      seconds = sum(float(line) for line in f if line.strip())
    results[omega_s] = (seconds, heldout_means(model_dir))
  ratios = measure(model_dirs)
  os.makedirs(os.path.dirname(FLAGS.control_table) or '.', exist_ok=True)
  with open(FLAGS.control_table, 'w', encoding='utf-8') as f:
    f.write(markdown(results, ratios))
  print(open(FLAGS.control_table, encoding='utf-8').read())


if __name__ == '__main__':
  app.run(main)
