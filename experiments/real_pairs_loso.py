"""Leave one source out with the real pairs at hand (issue 27, "training data"): does the
learned matching stage, fine-tuned with real stereo pairs beside the photograph warps,
match better on a camera it never saw?

    S=../shared/stereo_samples
    common="--flagfile=experiments/pretrained_features.flags --init_from=anaglyph_matching \
        --num_steps=400 --learning_rate=3e-4 --seed=1 --checkpoint_every=50"
    real="--real_pair_probability=0.5 --real_pairs"
    python -m mixstereo_tf.train $common --model_dir=runs/loso_warps
    python -m mixstereo_tf.train $common $real=$S/sceneflow_A-0032-0006,\
$S/kitti_object_velodyne --model_dir=runs/loso_no_motorcycle
    python -m mixstereo_tf.train $common $real=motorcycle,$S/kitti_object_velodyne \
        --model_dir=runs/loso_no_sceneflow
    python -m mixstereo_tf.train $common $real=motorcycle,$S/sceneflow_A-0032-0006 \
        --model_dir=runs/loso_no_kitti
    python -m experiments.real_pairs_loso --shared_dir=$S --loso_control=runs/loso_warps \
        --loso_runs=motorcycle=runs/loso_no_motorcycle,sceneflow=runs/loso_no_sceneflow,\
kitti=runs/loso_no_kitti

Each real source is scored with the methods that never saw it: classical, the shipped
stage (`anaglyph_matching`, warps only), the control (the shipped stage fine-tuned the same
steps on warps alone: what the steps give) and the run that left that source out (KITTI:
the object frame and the KITTI 2015 frame, whose views alone are scored). The procedural
scenes, in no run's training, are scored with every run. Each pair is window-aligned at 30%
and made into FFmpeg's colour anaglyph and gray anaglyph (the same-channel reference), as
experiments/same_channel.py does; the learned rows are the stage alone.
"""

import os
import sys
import tempfile
import time

from absl import app
from absl import flags
import numpy as np

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.unmixing import shipped

from experiments import same_channel
from experiments import validation

flags.DEFINE_list('loso_runs', None, 'source=run folder of each held-out source '
                  f'(sources: {", ".join(("motorcycle", "sceneflow", "kitti"))}).')
flags.DEFINE_string('loso_control', None, 'The run fine-tuned on warps alone.')
flags.DEFINE_string('loso_output', 'experiments/results/real_pairs_loso.md', 'Markdown report.')
flags.mark_flags_as_required(['loso_runs', 'loso_control'])
FLAGS = flags.FLAGS

ENCODINGS = ('anaglyph', same_channel.REFERENCE)
SOURCES = ('motorcycle', 'sceneflow', 'kitti')
SHIPPED, CONTROL = 'shipped stage (warps)', 'control (+ warps)'
PROCEDURAL = 'procedural'


def source_of(scene: str) -> str:
  """The source of a same_channel scene name: 'procedural', or one of SOURCES."""
  for source in SOURCES:
    if scene.lower().startswith(source):
      return source
  return PROCEDURAL


def parse_runs(items):
  """{source: run folder} of --loso_runs, or ValueError naming the bad item."""
  runs = {}
  for item in items:
    source, _, path = item.partition('=')
    if source not in SOURCES or not os.path.isdir(path):
      raise ValueError(f'--loso_runs: {item!r} is not source=run folder with a source of '
                       f'{", ".join(SOURCES)}.')
    runs[source] = path
  return runs


def _unmixers(name, runs, control, folder):
  """{label: Unmixer} of encoding `name`: classical, shipped, control, 'without <source>'."""
  config = predictors.PredictorConfig(mixture=name, method='model')
  built = {'classical': same_channel.unmixer(name, 'classical'),
           SHIPPED: same_channel.unmixer(name, 'learned')}
  for label, path in [(CONTROL, control)] + [(f'without {s}', p) for s, p in runs.items()]:
    entry = validation.model_entry(path, os.path.join(folder, label.replace(' ', '_')))
    built[label] = shipped.pretrained_unmixer(entry, config)
  return built


def _evaluate(runs, control, shared_dir, folder):
  unmixers = {name: _unmixers(name, runs, control, folder) for name in ENCODINGS}
  rows = []
  for group, scene, pair in same_channel.pairs(shared_dir, views_only=True):
    if group.endswith(f'noise {validation.NOISE_SIGMA:g}'):
      continue
    source = source_of(scene)
    for name in ENCODINGS:
      image = realworld.make_anaglyph(pair, name, 'ffmpeg')
      for label, unmix in unmixers[name].items():
        if label.startswith('without') and source not in (PROCEDURAL, label.split()[-1]):
          continue  # That run trained on this source.
        rows.append(dict(source=source, scene=scene, encoding=name, method=label,
                         **realworld.score(pair, *(unmix(image)[k] for k in (
                             'left', 'right', 'disparity_left')))))
        print(scene, name, label, f"bad-1 {rows[-1]['bad1']:.3f}", file=sys.stderr,
              flush=True)
  return rows


def table(rows):
  """Markdown lines: per scene set and method, colour and gray bad-1, their ratio, the
  colour anaglyph's views and their gain over classical's (dB)."""
  mean, cell = same_channel.mean, same_channel.cell
  lines = ['| scenes | method | bad-1 colour | bad-1 gray | ratio | views L / R | '
           'vs classical L / R |', '| --- ' * 7 + '|']
  for scenes in dict.fromkeys(same_channel.group(r['scene']) for r in rows):
    these = [r for r in rows if same_channel.group(r['scene']) == scenes]
    pick = lambda method, name: [r for r in these if r['method'] == method  # pylint: disable=cell-var-from-loop
                                 and r['encoding'] == name]
    base = pick('classical', 'anaglyph')
    for method in dict.fromkeys(r['method'] for r in these):
      colour, gray = pick(method, 'anaglyph'), pick(method, same_channel.REFERENCE)
      bad1, ref = mean(colour, 'bad1'), mean(gray, 'bad1')
      ratio = f'{bad1 / ref:.2f}x' if np.isfinite(bad1) and np.isfinite(ref) else '-'
      views = [mean(colour, k) for k in ('psnr_left', 'psnr_right')]
      gains = [v - mean(base, k) for v, k in zip(views, ('psnr_left', 'psnr_right'))]
      lines.append(f'| {scenes} | {method} | {cell(bad1, True)} | {cell(ref, True)} | '
                   f'{ratio} | {views[0]:.2f} / {views[1]:.2f} | '
                   f'{gains[0]:+.2f} / {gains[1]:+.2f} |')
  return lines


def main(argv):
  del argv
  start = time.perf_counter()
  try:
    runs = parse_runs(FLAGS.loso_runs)
  except ValueError as e:
    raise app.UsageError(str(e)) from None
  with tempfile.TemporaryDirectory() as folder:
    rows = _evaluate(runs, FLAGS.loso_control, FLAGS.shared_dir, folder)
  text = ['# Learned matching stage: leave one real source out', '',
          f'Written by `python -m experiments.real_pairs_loso` in '
          f'{time.perf_counter() - start:.0f} s on {os.cpu_count()} CPU cores. Control: '
          f'`{FLAGS.loso_control}`; runs: ' + ', '.join(f'`{r}`' for r in FLAGS.loso_runs)
          + '. FFmpeg colour and gray anaglyphs of the same_channel scenes, window-aligned '
          'at 30%; each real source is scored only by the methods that never trained on it '
          '(module docstring). ratio: colour bad-1 over the same method\'s on the gray '
          'anaglyph.', '', *table(rows), '']
  with open(FLAGS.loso_output, 'w', encoding='utf-8') as handle:
    handle.write('\n'.join(text))
  print('\n'.join(text))


if __name__ == '__main__':
  app.run(main)
