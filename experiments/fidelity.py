r"""Issue 14's measurements on the demo configuration: optimizer and smoothness unit.

  python experiments/fidelity.py [--runs_dir=runs/fidelity] \
      [--table=experiments/results/fidelity.md]

Trains the demo configuration (experiments/demo.flags, 7000 steps, seeded) four times:
RMSProp as TF1 ran it (`rmsprop_tf1`) and as Keras 3 runs it (`rmsprop_keras`), each with
the smoothness term on disparities in pixels and in fractions of the width; evaluates each
run on the `sample` held-out set; and writes one table (loss along training, held-out PSNR,
bad-1 / bad-3 / EPE) plus a panel of the held-out disparity maps to look at. A finished
run is not trained again (training resumes, evaluation is skipped when its CSV exists), so
the script can be re-run after an interruption.
"""

import csv
import glob
import os
import statistics
import subprocess
import sys

from absl import app
from absl import flags
import numpy as np

flags.DEFINE_string('runs_dir', 'runs/fidelity', 'Where the four training runs go.')
flags.DEFINE_string('table', 'experiments/results/fidelity.md', 'The Markdown table.')
flags.DEFINE_string('panel', 'experiments/results/fidelity_disparity.png',
                    'A PNG of held-out disparity maps, one row per variant.')
FLAGS = flags.FLAGS

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VARIANTS = (('rmsprop_keras', 'width'), ('rmsprop_keras', 'pixels'),
            ('rmsprop_tf1', 'width'), ('rmsprop_tf1', 'pixels'))
# Windows of steps whose logged batch losses are averaged (the loss curve in three numbers).
LOSS_WINDOWS = ((1, 500), (3001, 3500), (6501, 7000))


def _run(*args):
  command = [sys.executable, *args]
  print('[fidelity]', ' '.join(command), flush=True)
  subprocess.run(command, cwd=REPO, check=True)


def train_and_evaluate(optimizer: str, unit: str) -> str:
  """Trains (or resumes) one variant and evaluates it; returns its run directory."""
  model_dir = os.path.join(FLAGS.runs_dir, f'{optimizer}_{unit}')
  _run('-m', 'mixstereo_tf.train', '--flagfile=experiments/demo.flags',
       f'--model_dir={model_dir}', f'--optimizer={optimizer}', f'--smoothness_scale={unit}')
  if not os.path.exists(os.path.join(model_dir, 'heldout.csv')):
    _run('-m', 'mixstereo_tf.evaluate', '--protocol=sample', f'--checkpoint={model_dir}',
         f'--output_csv={os.path.join(model_dir, "heldout.csv")}')
  return model_dir


def logged_losses(model_dir: str) -> dict:
  """{step: loss} from the run's TensorBoard scalars."""
  import tensorflow as tf  # pylint: disable=g-import-not-at-top
  losses = {}
  for path in sorted(glob.glob(os.path.join(model_dir, 'train', 'events.out.tfevents.*'))):
    for event in tf.compat.v1.train.summary_iterator(path):
      for value in event.summary.value:
        if value.tag == 'loss':
          losses[event.step] = float(tf.make_ndarray(value.tensor))
  return losses


def heldout_means(model_dir: str) -> dict:
  """Means over the held-out images of the evaluation CSV's metrics."""
  with open(os.path.join(model_dir, 'heldout.csv'), newline='', encoding='utf-8') as f:
    rows = list(csv.DictReader(f))
  return {key: statistics.mean(float(r[key]) for r in rows)
          for key in ('psnr_left', 'psnr_right', 'bad1', 'bad3', 'epe')}


def disparity_panel(model_dirs, path: str) -> None:
  """Held-out disparity maps (synthetic scene 1 and Motorcycle), one row per variant."""
  # pylint: disable=g-import-not-at-top
  from mixstereo_tf.core import colormap
  from mixstereo_tf.unmixing import predictors
  from mixstereo_tf.cli import media
  from mixstereo_tf.data import sample
  from mixstereo_tf.data import sources
  from mixstereo_tf.evaluation import runner
  rows = []
  for model_dir in model_dirs:
    unmixer = predictors.build_unmixer(predictors.PredictorConfig(checkpoint=model_dir))
    records = sample.sample_records('heldout', max_disparity=int(unmixer.max_disparity))
    tiles = []
    for record in (records[1], records[-1]):
      data = sources.load_sample(record)
      out = unmixer(runner.synthesise_mixture(unmixer.mixture, data['left'], data['right']))
      tiles.append(colormap.colorize(out['disparity_left'], unmixer.max_disparity))
    height = min(t.shape[0] for t in tiles)
    rows.append(np.concatenate([t[:height] for t in tiles], axis=1))
  width = min(r.shape[1] for r in rows)
  media.write_image(path, np.concatenate([r[:, :width] for r in rows], axis=0))


def markdown(results) -> str:
  lines = ['# Fidelity measurements on the demo configuration', '',
           'Written by `python experiments/fidelity.py`: experiments/demo.flags (7000 steps, '
           'seed 0) per optimizer and smoothness unit, evaluated on the `sample` held-out set '
           '(8 procedural scenes + Motorcycle). Loss columns: mean logged batch loss over the '
           'steps given (every 50th step is logged). Disparity maps of each variant, in this '
           f'order: `{os.path.basename(FLAGS.panel)}`.', '',
           '| optimizer | smoothness unit | ' +
           ' | '.join(f'loss {a}-{b}' for a, b in LOSS_WINDOWS) +
           ' | PSNR L | PSNR R | bad-1 | bad-3 | EPE (px) |',
           '| --- | --- | ' + ' | '.join('---:' for _ in LOSS_WINDOWS) +
           ' | ---: | ---: | ---: | ---: | ---: |']
  for (optimizer, unit), (losses, means) in results.items():
    windows = [statistics.mean(v for s, v in losses.items() if a <= s <= b)
               for a, b in LOSS_WINDOWS]
    lines.append(f'| {optimizer} | {unit} | ' + ' | '.join(f'{w:.4f}' for w in windows) +
                 f' | {means["psnr_left"]:.2f} | {means["psnr_right"]:.2f} | '
                 f'{100 * means["bad1"]:.2f}% | {100 * means["bad3"]:.2f}% | '
                 f'{means["epe"]:.2f} |')
  return '\n'.join(lines) + '\n'


def main(argv):
  del argv
  results, model_dirs = {}, []
  for optimizer, unit in VARIANTS:
    model_dir = train_and_evaluate(optimizer, unit)
    model_dirs.append(model_dir)
    results[(optimizer, unit)] = (logged_losses(model_dir), heldout_means(model_dir))
  os.makedirs(os.path.dirname(FLAGS.table) or '.', exist_ok=True)
  with open(FLAGS.table, 'w', encoding='utf-8') as f:
    f.write(markdown(results))
  disparity_panel(model_dirs, FLAGS.panel)
  print(open(FLAGS.table, encoding='utf-8').read())


if __name__ == '__main__':
  app.run(main)
