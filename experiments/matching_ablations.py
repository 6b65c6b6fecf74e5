"""Ablations of the learned matching stage: training data and feature width, one run each.

    common="--flagfile=experiments/pretrained_features.flags --num_steps=800"
    python -m mixstereo_tf.train $common --model_dir=runs/abl_w32
    python -m mixstereo_tf.train $common --feature_width=16 --model_dir=runs/abl_w16
    python -m mixstereo_tf.train $common --nophoto_warps --model_dir=runs/abl_nowarp
    python -m mixstereo_tf.train $common --feature_layers=6 \
        --feature_dilations=1,1,2,4,1,1 --model_dir=runs/abl_dil
    python -m experiments.matching_ablations --shared_dir=../shared/stereo_samples \
        --ablation_runs="recipe (width 32, photo warps)=runs/abl_w32,width 16=runs/abl_w16,\
no photo warps (procedural scenes)=runs/abl_nowarp,6 layers dilated 1-1-2-4-1-1 \
(receptive field 21)=runs/abl_dil"

The photo-warp ablation at the recipe's full length (experiments/results/
matching_ablations_3000.md; runs/pretrained_features is the shipped model's run):
    python -m mixstereo_tf.train --flagfile=experiments/pretrained_features.flags \
        --nophoto_warps --model_dir=runs/nowarp_3000
    python -m experiments.matching_ablations --shared_dir=../shared/stereo_samples \
        --ablation_runs="recipe at 3000 steps (shipped; photo warps)=runs/pretrained_features,\
no photo warps (procedural scenes) at 3000 steps=runs/nowarp_3000" \
        --ablation_output=experiments/results/matching_ablations_3000.md

The width at the recipe's full length (experiments/results/matching_width*.md; 2026-11-27,
55 min on 2 cores with AVX-512), against the shipped width-32 model of the same recipe,
on the colour anaglyphs and on the gray ones (the same-channel reference):
    python -m mixstereo_tf.train --flagfile=experiments/pretrained_features.flags \
        --feature_width=64 --model_dir=runs/features_w64
    runs="shipped (width 32; 3000 steps)=mixstereo_tf/artifacts/pretrained/anaglyph_matching,\
width 64 (3000 steps)=runs/features_w64"
    python -m experiments.matching_ablations --shared_dir=../shared/stereo_samples \
        --ablation_runs="$runs" --ablation_output=experiments/results/matching_width.md
    python -m experiments.matching_ablations --shared_dir=../shared/stereo_samples \
        --ablation_runs="$runs" --ablation_encoding=gray \
        --ablation_output=experiments/results/matching_width_gray.md
    python -m experiments.matching_validation --photo_dir=photos/warps \
        --variants="learned (shipped; width 32)=shipped,learned width 64 (3000 steps)=\
runs/features_w64" --validation_output=experiments/results/matching_validation_width.md

Every run is cut to the same number of steps (the shipped recipe trains 3000), so the rows
compare the choices, not the training time. Each run's newest checkpoint is scored as the
learned stage of the tools (`shipped.pretrained_unmixer`) on the colour anaglyphs of
experiments/same_channel.py's scenes (window-aligned at 30%, FFmpeg), beside the classical
method in the same run: bad-1 over the valid ground truth and the views' RGB PSNR.
"""

import os
import sys
import tempfile
import time

from absl import app
from absl import flags

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.unmixing import shipped

from experiments import markdown
from experiments import same_channel
from experiments import validation

flags.DEFINE_list('ablation_runs', None, 'label=run folder, comma-separated.')
flags.DEFINE_string('ablation_output', 'experiments/results/matching_ablations.md',
                    'Markdown report.')
flags.DEFINE_enum('ablation_encoding', 'anaglyph', ['anaglyph', 'gray'],
                  "The anaglyphs scored: colour, or 'gray' (the same-channel reference).")
flags.mark_flag_as_required('ablation_runs')
FLAGS = flags.FLAGS


def _unmixers(runs_spec, folder, encoding):
  """{label: Unmixer} of `encoding`: classical, then each run exported to `folder` and
  loaded."""
  config = predictors.PredictorConfig(mixture=encoding, method='model')
  built = {'classical': predictors.build_unmixer(predictors.PredictorConfig(
      mixture=encoding, method='classical'))}
  for index, item in enumerate(runs_spec):
    label, _, path = item.rpartition('=')
    if not label or not os.path.isdir(path):
      raise ValueError(f'--ablation_runs: {item!r} is not label=run folder.')
    entry = validation.model_entry(path, os.path.join(folder, f'run{index}'))
    built[label] = shipped.pretrained_unmixer(entry, config)
  return built


def _evaluate(unmixers, shared_dir, encoding):
  rows = []
  for scene, data in same_channel.scenes(shared_dir):
    pair = realworld.window_align(data, same_channel.FRACTION)
    image = realworld.make_anaglyph(pair, encoding, 'ffmpeg')
    for label, unmix in unmixers.items():
      out = unmix(image)
      rows.append(dict(scene=scene, method=label, **realworld.score(
          pair, out['left'], out['right'], out['disparity_left'])))
      print(scene, label, f"bad-1 {rows[-1]['bad1']:.3f}", file=sys.stderr, flush=True)
  return rows


def main(argv):
  del argv
  start = time.perf_counter()
  with tempfile.TemporaryDirectory() as folder:
    unmixers = _unmixers(FLAGS.ablation_runs, folder, FLAGS.ablation_encoding)
    rows = _evaluate(unmixers, FLAGS.shared_dir, FLAGS.ablation_encoding)
  text = ['# Learned matching stage: ablations', '',
          f'Written by `python -m experiments.matching_ablations` in '
          f'{time.perf_counter() - start:.0f} s on {os.cpu_count()} CPU cores. Runs: '
          + ', '.join(f'`{r}`' for r in FLAGS.ablation_runs) + '. '
          + ('Colour' if FLAGS.ablation_encoding == 'anaglyph' else 'Gray') + ' anaglyphs by '
          'FFmpeg of the same_channel scenes, window-aligned at 30%; the learned rows are '
          'the stage alone (no refiner); see experiments/results/same_channel.md for the '
          'refiner on / off.', '', *same_channel.method_table(rows, list(unmixers), 'stage'), '']
  markdown.write(FLAGS.ablation_output, text)


if __name__ == '__main__':
  app.run(main)
