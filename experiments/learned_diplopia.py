"""Learned diplopia (issue "Learned diplopia"): the learned echo stage against the
classical de-diplopia and the previous shipped model, the mixing weight, the eye order.

    python -m experiments.learned_diplopia --shared_dir=../shared/stereo_samples \
        [--learned_diplopia_output=experiments/results/learned_diplopia.md]

Scenes with ground truth (as experiments/same_channel.py): the 8 procedural held-out
`sample` scenes (averaged), Motorcycle, and from --shared_dir the SceneFlow frame and the
KITTI object frame (sparse ground truth from its Velodyne scan). Not window-aligned: a
double image's disparities are positive by convention (docs/DESIGN.md).
  1. I = (L + R) / 2 (`--mixture=diplopia`): rows mixture (I as both views), classical,
     the refiner trained on a = 1/2 only (`--pretrained=diplopia`, the previous default),
     the refiner trained on any a on the classical method before its small-lag penalty
     (`--pretrained=diplopia_weighted`, the previous default), the same recipe on today's
     classical method (`--pretrained=diplopia_weighted_penalised`, the default), learned
     (`--pretrained=diplopia_echo`); bad-1, bad-3, D1, views' RGB PSNR.
  2. I = a L + (1 - a) R for a in WEIGHTS, classical method with `--mixing_weight=auto`: the
     estimate's error, views with the estimated a against views with the true a and with
     a = 1/2 (the separation before this issue: the ablation of the weight), and the views
     of both refiners with the estimated a; then their mean gain over the classical views
     at a != 1/2.
  3. Eye order: a run's eyes are in order when its left view is nearer (PSNR) to the true
     left view than to the true right one, and (a second criterion, not fooled by a weak
     separation of an unequal mix) when the restored views' difference points the way of
     the true one (`metrics.view_difference_agreement` > 0); the share over every run of
     1 and 2 (at a != 1/2 for the classical method and for the default refiner).
  4. Ablation of the cost (I = (L + R) / 2): the ZNCC share of the blended cost
     (`learned_diplopia.EchoConfig.zncc_weight`; 0: learned cost only, 1: classical).
The echo features were trained on photographs only (no stereo pair, no evaluation scene),
so each source here is held out: the leave-one-source-out table is this table.
"""

import os
import platform
import sys
import time

from absl import app
from absl import flags
import numpy as np

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.classical import diplopia_range
from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.unmixing import learned_diplopia
from mixstereo_tf.unmixing import predictors
from experiments import markdown
from experiments import same_channel

cli_flags.define_shared_dir()
flags.DEFINE_string('learned_diplopia_output', 'experiments/results/learned_diplopia.md',
                    'Markdown report (a .csv of the rows beside it).')
FLAGS = flags.FLAGS

METHODS = {'classical': dict(method='classical'),
           'refiner, a = 1/2': dict(method='model', pretrained='diplopia'),
           'refiner, any a (previous)': dict(method='model', pretrained='diplopia_weighted'),
           'refiner, any a': dict(method='model', pretrained='diplopia_weighted_penalised'),
           'learned': dict(method='model', pretrained='diplopia_echo')}
REFINERS = {'refiner_half': 'refiner, a = 1/2', 'default': 'refiner, any a'}  # Part 2's columns.
WEIGHTS = (0.3, 0.4, 0.5, 0.6, 0.7)
ZNCC_SHARES = (0.0, 0.25, 0.5, 0.75)


def mix(data, weight):
  """uint8 a L + (1 - a) R."""
  both = weight * data['left'].astype(np.float64) + (1 - weight) * data['right']
  return np.clip(np.rint(both), 0, 255).astype(np.uint8)


def unmixer(method, mixing_weight=None):
  """The Unmixer of a METHODS row for double images."""
  return predictors.build_unmixer(predictors.PredictorConfig(
      mixture='diplopia', mixing_weight=mixing_weight, **METHODS[method]))


def score(data, out):
  """realworld.score plus D1 (KITTI's outlier rate) and whether the eyes are in order."""
  row = realworld.score(data, out['left'], out['right'], out['disparity_left'])
  row['d1'] = metrics.d1_error(out['disparity_left'], data['disparity_left'],
                               data['valid_left'])
  row['in_order'] = bool(metrics.psnr(out['left'], data['left']) >
                         metrics.psnr(out['left'], data['right']))
  row['difference_in_order'] = bool(metrics.view_difference_agreement(
      out['left'], out['right'], data['left'], data['right']) > 0)
  return row


def evaluate(shared_dir):
  """Rows of parts 1 and 2 (module docstring)."""
  rows = []
  built = {m: unmixer(m) for m in METHODS}
  auto, given = unmixer('classical', 'auto'), {a: unmixer('classical', a) for a in WEIGHTS}
  half = built['classical']
  refiners = {key: unmixer(method, 'auto') for key, method in REFINERS.items()}
  echo = learned_diplopia.echo_function(pretrained.load_model(pretrained.get('diplopia_echo')))
  for scene, data in same_channel.scenes(shared_dir):
    base = dict(scene=scene, group=same_channel.group(scene))
    image = mix(data, 0.5)
    rows.append(dict(base, part=1, method='mixture', weight=0.5,
                     **realworld.score(data, image, image)))
    for method, run in built.items():
      start = time.perf_counter()
      out = run(image)
      rows.append(dict(base, part=1, method=method, weight=0.5,
                       seconds=time.perf_counter() - start, **score(data, out)))
      print(scene, method, f"bad-1 {rows[-1]['bad1']:.3f}", file=sys.stderr, flush=True)
    for weight in WEIGHTS:
      image = mix(data, weight)
      out = auto(image)
      got = {'true': score(data, given[weight](image)), 'half': score(data, half(image))}
      got.update({key: score(data, run(image)) for key, run in refiners.items()})
      views = {f'{name}_psnr_{eye}': value[f'psnr_{eye}'] for eye in ('left', 'right')
               for name, value in got.items()}
      views.update({f'{key}_{order}': got[key][order] for key in REFINERS
                    for order in ('in_order', 'difference_in_order')})
      rows.append(dict(base, part=2, method='classical auto', weight=weight,
                       estimate=out['info']['mixing_weight'], **views, **score(data, out)))
    rows += _cost_ablation(echo, data, base)
  return rows


def _cost_ablation(echo, data, base):
  """Part 4's rows of one scene."""
  image = mix(data, 0.5)
  search = diplopia_range.estimate_range(image)
  rows = []
  for share in ZNCC_SHARES:
    out = learned_diplopia.learned_unmix(echo, image, 'diplopia', search,
                                         config=learned_diplopia.EchoConfig(zncc_weight=share))
    rows.append(dict(base, part=4, method=f'zncc share {share}', weight=0.5,
                     **score(data, out)))
  return rows


def _mean(rows, key):
  return float(np.nanmean([float(r[key]) for r in rows])) if rows else float('nan')


def tables(rows):
  """Markdown of parts 1-4."""
  lines = _part1(rows) + _part2([r for r in rows if r['part'] == 2]) + _part3(rows)
  lines += ['',
            '## 4. Ablation: the ZNCC share of the learned stage\'s cost, I = (L + R) / 2', '',
            *same_channel.method_table([r for r in rows if r['part'] == 4],
                                       [f'zncc share {s}' for s in ZNCC_SHARES], 'cost'), '']
  return lines


def _part1(rows):
  """Part 1 (a = 1/2): every method beside classical, per group."""
  lines = ['## 1. I = (L + R) / 2', '',
           '| scenes | method | bad-1 | bad-3 | D1 | RGB PSNR L / R (dB) | bad-1 / classical |'
           ' views - classical L / R (dB) | seconds |', '| --- ' * 9 + '|']
  for name in dict.fromkeys(r['group'] for r in rows):
    these = lambda m: [r for r in rows if r['group'] == name and r['part'] == 1  # pylint: disable=cell-var-from-loop
                       and r['method'] == m]
    classical = these('classical')
    for method in ('mixture',) + tuple(METHODS):
      got = these(method)
      if method == 'mixture':
        lines.append(f"| {name} | mixture as both views | | | | {_mean(got, 'psnr_left'):.2f}"
                     f" / {_mean(got, 'psnr_right'):.2f} | | | |")
        continue
      gain = [_mean(got, k) - _mean(classical, k) for k in ('psnr_left', 'psnr_right')]
      lines.append(f"| {name} | {method} | {100 * _mean(got, 'bad1'):.1f}% | "
                   f"{100 * _mean(got, 'bad3'):.1f}% | {100 * _mean(got, 'd1'):.1f}% | "
                   f"{_mean(got, 'psnr_left'):.2f} / {_mean(got, 'psnr_right'):.2f} | "
                   f"{_mean(got, 'bad1') / _mean(classical, 'bad1'):.2f}x | "
                   f'{gain[0]:+.2f} / {gain[1]:+.2f} | {_mean(got, "seconds"):.1f} |')
  return lines


def _part2(part2):
  """Part 2: the weight's estimate and the views with it, per group and weight."""
  lines = ['', '## 2. The mixing weight: I = a L + (1 - a) R, classical method, '
            '`--mixing_weight=auto`', '',
            '| scenes | a | estimated a (mean) | mean abs error | views L / R, estimated a | '
            'views L / R, true a | views L / R, a = 1/2 | refiner trained on a = 1/2, '
            'estimated a | default (refiner trained on any a), estimated a |',
            '| --- ' * 9 + '|']
  for name in dict.fromkeys(r['group'] for r in part2):
    for weight in WEIGHTS:
      got = [r for r in part2 if r['group'] == name and r['weight'] == weight]
      error = np.mean([abs(r['estimate'] - weight) for r in got])
      lines.append(f"| {name} | {weight} | {_mean(got, 'estimate'):.3f} | {error:.3f} | "
                   f"{_mean(got, 'psnr_left'):.2f} / {_mean(got, 'psnr_right'):.2f} | "
                   f"{_mean(got, 'true_psnr_left'):.2f} / {_mean(got, 'true_psnr_right'):.2f} | "
                   f"{_mean(got, 'half_psnr_left'):.2f} / {_mean(got, 'half_psnr_right'):.2f} | "
                   f"{_mean(got, 'refiner_half_psnr_left'):.2f} / "
                   f"{_mean(got, 'refiner_half_psnr_right'):.2f} | "
                   f"{_mean(got, 'default_psnr_left'):.2f} / "
                   f"{_mean(got, 'default_psnr_right'):.2f} |")
  lines += ['', *_weighted_gains(part2)]
  return lines


def _part3(rows):
  """Part 3: the share of runs whose eyes come out in order, by two criteria."""
  lines = ['', '## 3. Eye order', '', 'Share of runs in order by two criteria. "Nearer": '
            'the left view is nearer (RGB PSNR) to the true left view than to the true right '
            'one; for a != 1/2 it also fails when a weak separation leaves the mixture, '
            'which then resembles the heavier eye. "Difference": the restored views\' '
            'difference L\' - R\' points the way of the true L - R (positive cosine, '
            '`metrics.view_difference_agreement`): swapped eyes flip it, a weak separation '
            'does not.', '', '| runs | in order (nearer) | in order (difference) |',
            '| --- | --- | --- |']
  for label, chosen, prefix in (
      ('a = 1/2 (every part and method)', lambda w: w == 0.5, ''),
      ('a != 1/2 (part 2, classical)', lambda w: w != 0.5, ''),
      ('a != 1/2 (part 2, the default refiner)', lambda w: w != 0.5, 'default_')):
    cells = []
    for key in (prefix + 'in_order', prefix + 'difference_in_order'):
      got = [r[key] for r in rows if key in r and chosen(r['weight'])]
      cells.append(f'{np.mean(got):.1%} of {len(got)}')
    lines.append(f'| {label} | ' + ' | '.join(cells) + ' |')
  return lines


def _weighted_gains(part2):
  """Part 2's summary: each refiner's views minus the classical ones (both with the
  estimated a), averaged over every scene group and a != 1/2, and the worst case."""
  lines = ['Views minus the classical views (dB, L / R), both with the estimated a, at '
           'a != 1/2: mean over the groups and weights, and the worst group and weight.', '',
           '| refiner | mean | worst |', '| --- | --- | --- |']
  cells = [[r for r in part2 if r['group'] == name and r['weight'] == weight]
           for name in dict.fromkeys(r['group'] for r in part2)
           for weight in WEIGHTS if weight != 0.5]
  for key, label in REFINERS.items():
    gains = np.array([[_mean(cell, f'{key}_psnr_{eye}') - _mean(cell, f'psnr_{eye}')
                       for eye in ('left', 'right')] for cell in cells])
    mean, worst = gains.mean(axis=0), gains.min(axis=0)
    lines.append(f'| {label} | {mean[0]:+.2f} / {mean[1]:+.2f} | '
                 f'{worst[0]:+.2f} / {worst[1]:+.2f} |')
  return lines


def main(argv):
  del argv
  start = time.perf_counter()
  rows = evaluate(FLAGS.shared_dir)
  same_channel._write_csv(rows, os.path.splitext(FLAGS.learned_diplopia_output)[0] + '.csv')  # pylint: disable=protected-access
  machine = ' '.join(filter(None, (platform.system(), platform.machine())))
  text = ['# Learned diplopia: the learned echo stage against classical', '',
          f'Written by `python -m experiments.learned_diplopia --shared_dir=...` on {machine} '
          f'({os.cpu_count()} CPU cores) in {time.perf_counter() - start:.0f} s. Disparity '
          'range estimated per image (`--disparity_range=auto`). bad-1 / bad-3: share of '
          'valid ground-truth pixels off by more than 1 / 3 px; D1: off by more than 3 px '
          'and 5 %. procedural: mean of 8 scenes. The echo features never saw a stereo '
          'pair or an evaluation scene: every source is held out.', '', *tables(rows)]
  markdown.write(FLAGS.learned_diplopia_output, text)


if __name__ == '__main__':
  app.run(main)
