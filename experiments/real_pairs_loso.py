"""Leave one source out with the real pairs at hand (issue 27, "training data"; issue 28,
"plus the real pairs at hand"): does a learned stage, fine-tuned with real stereo pairs
beside the photograph warps, match better on a camera it never saw?

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

The echo features of double images the same way: `common` with
--flagfile=experiments/pretrained_echo.flags --init_from=diplopia_echo, run folders
runs/echo_loso_*, and --loso_mixture=diplopia.

Each real source is scored with the methods that never saw it: classical, the shipped
stage (`anaglyph_matching` / `diplopia_echo`, warps only), the control (the shipped stage
fine-tuned the same steps on warps alone: what the steps give) and the run that left that
source out (KITTI: the object frame and the KITTI 2015 frame, whose views alone are
scored). The procedural scenes, in no run's training, are scored with every run
(`FAMILIES`): anaglyphs window-aligned at 30% and made by FFmpeg, colour and gray (the
same-channel reference), as experiments/same_channel.py; double images (L + R) / 2 as
experiments/learned_diplopia.py. The learned rows are the stage alone.
"""

import dataclasses
import os
import sys
import tempfile
import time
from typing import Callable, Optional, Tuple

from absl import app
from absl import flags
import numpy as np

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.unmixing import shipped

from experiments import learned_diplopia
from experiments import same_channel
from experiments import validation

flags.DEFINE_list('loso_runs', None, 'source=run folder of each held-out source '
                  f'(sources: {", ".join(("motorcycle", "sceneflow", "kitti"))}).')
flags.DEFINE_string('loso_control', None, 'The run fine-tuned on warps alone.')
flags.DEFINE_enum('loso_mixture', 'anaglyph', ['anaglyph', 'diplopia'],
                  'Whose stage the runs train: the anaglyph matching features or the echo '
                  'features of double images.')
flags.DEFINE_string('loso_output', None, 'Markdown report (default: experiments/results/'
                    'real_pairs_loso_<mixture>.md).')
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


def _anaglyph_pairs(shared_dir):
  for group, scene, pair in same_channel.pairs(shared_dir, views_only=True):
    if not group.endswith(f'noise {validation.NOISE_SIGMA:g}'):
      yield scene, pair


def _double_pairs(shared_dir):
  """(scene, pair) of the same_channel scenes as captured (not window-aligned), the frames
  without ground truth scored on their views alone."""
  for scene, data in same_channel.scenes(shared_dir, views_only=True):
    yield scene, same_channel.without_estimated_truth(data, data)


@dataclasses.dataclass(frozen=True)
class Family:
  """How one mixture family's stage is scored.

  Attributes:
    encodings: the encodings made of each pair; the first is the one scored.
    reference: (encoding, method) of the ratio's denominator; method None: the row's own.
    labels: column names of the scored and the reference bad-1.
    unmixer: (encoding, 'classical' or 'shipped') -> Unmixer.
    pairs: shared_dir -> (scene, pair) to score.
    make: (pair, encoding) -> the uint8 mixture.
    stage, data, ratio: the report's title, what it says of its data and of its ratio.
  """
  encodings: Tuple[str, ...]
  reference: Tuple[str, Optional[str]]
  labels: Tuple[str, str]
  unmixer: Callable
  pairs: Callable
  make: Callable
  stage: str
  data: str
  ratio: str


FAMILIES = {
    'anaglyph': Family(
        ('anaglyph', same_channel.REFERENCE), (same_channel.REFERENCE, None),
        ('colour', 'gray'), lambda name, method: same_channel.unmixer(
            name, 'learned' if method == 'shipped' else method),
        _anaglyph_pairs, lambda pair, name: realworld.make_anaglyph(pair, name, 'ffmpeg'),
        'Learned matching stage',
        'FFmpeg colour and gray anaglyphs of the same_channel scenes, window-aligned at 30%',
        "colour bad-1 over the same method's on the gray anaglyph"),
    'diplopia': Family(
        ('diplopia',), ('diplopia', 'classical'), ('double image', 'classical'),
        lambda name, method: learned_diplopia.unmixer(
            'learned' if method == 'shipped' else method),
        _double_pairs, lambda pair, name: learned_diplopia.mix(pair, 0.5),
        'Learned echo stage',
        'double images (L + R) / 2 of the same_channel scenes, not window-aligned',
        "bad-1 over the classical method's (the issue's 0.75x)"),
}


def _unmixers(family, name, runs, control, folder):
  """{label: Unmixer} of encoding `name`: classical, shipped, control, 'without <source>'."""
  config = predictors.PredictorConfig(mixture=name, method='model')
  built = {'classical': family.unmixer(name, 'classical'),
           SHIPPED: family.unmixer(name, 'shipped')}
  for label, path in [(CONTROL, control)] + [(f'without {s}', p) for s, p in runs.items()]:
    entry = validation.model_entry(path, os.path.join(folder, f'{name}_{label}'.replace(' ', '_')))
    built[label] = shipped.pretrained_unmixer(entry, config)
  return built


def _evaluate(family, runs, control, shared_dir, folder):
  unmixers = {name: _unmixers(family, name, runs, control, folder)
              for name in family.encodings}
  rows = []
  for scene, pair in family.pairs(shared_dir):
    source = source_of(scene)
    for name in family.encodings:
      image = family.make(pair, name)
      for label, unmix in unmixers[name].items():
        if label.startswith('without') and source not in (PROCEDURAL, label.split()[-1]):
          continue  # That run trained on this source.
        rows.append(dict(source=source, scene=scene, encoding=name, method=label,
                         **realworld.score(pair, *(unmix(image)[k] for k in (
                             'left', 'right', 'disparity_left')))))
        print(scene, name, label, f"bad-1 {rows[-1]['bad1']:.3f}", file=sys.stderr,
              flush=True)
  return rows


def table(rows, family=FAMILIES['anaglyph']):
  """Markdown lines: per scene set and method, the scored encoding's bad-1, the
  reference's (`Family.reference`), their ratio, the scored encoding's views and their gain
  over classical's (dB)."""
  mean, cell = same_channel.mean, same_channel.cell
  scored, (ref_name, ref_method) = family.encodings[0], family.reference
  lines = [f'| scenes | method | bad-1 {family.labels[0]} | bad-1 {family.labels[1]} | ratio '
           '| views L / R | vs classical L / R |', '| --- ' * 7 + '|']
  for scenes in dict.fromkeys(same_channel.group(r['scene']) for r in rows):
    these = [r for r in rows if same_channel.group(r['scene']) == scenes]
    pick = lambda method, name: [r for r in these if r['method'] == method  # pylint: disable=cell-var-from-loop
                                 and r['encoding'] == name]
    base = pick('classical', scored)
    for method in dict.fromkeys(r['method'] for r in these):
      mine = pick(method, scored)
      bad1, ref = mean(mine, 'bad1'), mean(pick(ref_method or method, ref_name), 'bad1')
      ratio = f'{bad1 / ref:.2f}x' if np.isfinite(bad1) and np.isfinite(ref) else '-'
      views = [mean(mine, k) for k in ('psnr_left', 'psnr_right')]
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
  family = FAMILIES[FLAGS.loso_mixture]
  with tempfile.TemporaryDirectory() as folder:
    rows = _evaluate(family, runs, FLAGS.loso_control, FLAGS.shared_dir, folder)
  text = [f'# {family.stage}: leave one real source out', '',
          f'Written by `python -m experiments.real_pairs_loso --loso_mixture='
          f'{FLAGS.loso_mixture}` in {time.perf_counter() - start:.0f} s on '
          f'{os.cpu_count()} CPU cores. Control: `{FLAGS.loso_control}`; runs: '
          + ', '.join(f'`{r}`' for r in FLAGS.loso_runs) + f'. {family.data}; '
          'each real source is scored only by the methods that never trained on it (module '
          f'docstring). ratio: {family.ratio}.', '', *table(rows, family), '']
  output = FLAGS.loso_output or f'experiments/results/real_pairs_loso_{FLAGS.loso_mixture}.md'
  with open(output, 'w', encoding='utf-8') as handle:
    handle.write('\n'.join(text))
  print('\n'.join(text))


if __name__ == '__main__':
  app.run(main)
