"""Double-image video speed (issue "Learned diplopia"; BENCHMARKS.md section 19).

    python -m experiments.benchmark_diplopia [--diplopia_frames=6] [--before_checkout=DIR]
        [--diplopia_photo_size=4000x3000]

A procedural scene (held-out textures, disparities up to 51 px) rendered at 1280x720 and
panned 4 px per frame, mixed as I = (L + R) / 2, written as an H.264 MP4 and unmixed by
`unmix_files.unmix_inputs` as `mixstereo-unmix --mixture=diplopia --layout=sbs` does
(decoding, unmixing, encoding), after one warm-up frame: per frame (`--notemporal`: the
encoding and the range are found again on every frame) and per shot (the default: found at
the shot's first frame, and the previous frame's disparity is a soft prior,
`diplopia_costs.add_prior`). Frames/s of the whole call
and inside the unmixer, per method (`METHODS`);
then one frame's stages timed apart (range, cost volume, SGM and post-processing, mixing
weight, layers, seconds) for the classical method and the learned echo stage. Each
measurement runs in its own process; with --before_checkout (a checkout of an earlier
commit, e.g. `git worktree add DIR REV`) each is also run there, on the same clip: the
"before" of a change. With --diplopia_photo_size, also a double-image photo of that size
(`photo_12mp.py --photo_encoding=diplopia`: wall seconds and peak resident memory), the
working tree's script run on each checkout's package.
"""

import dataclasses
import fractions
import os
import shutil
import subprocess
import sys
import tempfile
import time

from absl import app
from absl import flags
import numpy as np

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import diplopia_costs
from mixstereo_tf.classical import diplopia_layers
from mixstereo_tf.classical import diplopia_range
from mixstereo_tf.classical import diplopia_weight
from mixstereo_tf.classical import parallel_sgm
from mixstereo_tf.cli import media
from mixstereo_tf.cli import unmix_files
from mixstereo_tf.core import hints
from mixstereo_tf.core import workers
from mixstereo_tf.data import synthetic
from mixstereo_tf.data import texture_atlas
from mixstereo_tf.unmixing import learned_diplopia
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.video import streams
from mixstereo_tf.video import temporal
from experiments import checkouts  # Defines --before_checkout.

flags.DEFINE_integer('diplopia_frames', 6, 'Frames of the clip.', lower_bound=1)
flags.DEFINE_string('diplopia_photo_size', '', 'WIDTHxHEIGHT of a double-image photo also '
                    'run per method (e.g. 4000x3000, minutes a row); empty: none.')
FLAGS = flags.FLAGS

WIDTH, HEIGHT, PAN = 1280, 720, 4
STAGES = ('range', 'costs', 'sgm', 'weight', 'layers')
# The classical method, the default (the refiner on the classical result, `--pretrained=
# diplopia_weighted_penalised`; the same network as `diplopia`, so the same speed) and the
# learned echo stage (`--pretrained=diplopia_echo`).
METHODS = {'classical': dict(method='classical'),
           'refiner (default)': dict(method='model', pretrained='diplopia_weighted_penalised'),
           'learned echo': dict(method='model', pretrained='diplopia_echo')}


PHOTO_METHODS = {'classical': ['--photo_method=classical'],
                 'refiner (default)': ['--photo_method=model']}


def photo(arguments, checkout=''):
  """`photo_12mp.py`'s line for a double image: the working tree's script on the package
  of `checkout` (the working tree's when empty), checked to be the one that ran."""
  tree = os.path.abspath(checkout or os.getcwd())
  out = subprocess.run(
      [sys.executable, os.path.abspath('experiments/photo_12mp.py'),
       '--photo_encoding=diplopia', f'--photo_size={FLAGS.diplopia_photo_size}', *arguments],
      capture_output=True, text=True, check=True, cwd=tree,
      env=dict(os.environ, PYTHONPATH=tree)).stdout.strip().splitlines()[-1]
  line, package = out.rsplit('; package ', 1)
  checkouts.check_package(package, checkout)
  return line


def frames(count):
  """uint8 [720, 1280, 3] double images of the panning scene."""
  config = synthetic.SceneConfig(max_disparity=64, height=HEIGHT, width=WIDTH + PAN * count)
  scene = synthetic.render_scene(3, config, texture_atlas.load_textures('heldout'))
  both = (scene['left'].astype(np.float32) + scene['right']) / 2
  return [np.rint(both[:, PAN * i:PAN * i + WIDTH]).astype(np.uint8) for i in range(count)]


def video_fps(method, path, count, per_shot=False):
  """(frames/s, frames/s inside the unmixer) of `method` on the clip at `path`, per frame
  or `per_shot` (`temporal.TemporalConfig.enabled`)."""
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(mixture='diplopia',
                                                                **METHODS[method]))
  # Warm-up: numba's cache, and tracing the network as video frames run it (their right
  # disparity unread, `unmix_files`).
  unmixer(frames(1)[0], hint=hints.FrameHint(unread='disparity_right'))
  output_dir = tempfile.mkdtemp()
  try:
    report = unmix_files.unmix_inputs(unmixer, path, output_dir, media.OutputOptions(
        layout='sbs', temporal_config=temporal.TemporalConfig(enabled=per_shot)))
  finally:
    shutil.rmtree(output_dir, ignore_errors=True)
  if report.failures or report.frames != count:
    raise RuntimeError(f'unmix_inputs: {report}')
  return report.frames_per_second, count / report.unmix_seconds


def stage_seconds(image, costs, density):
  """Seconds of each stage on one frame: range (at `density`), cost volume (`costs`), SGM
  and post-processing, mixing weight, layers; and the range searched."""
  image01 = image.astype(np.float32) / 255.0
  times, start = {}, time.perf_counter()
  search = diplopia_range.estimate_range(image, density=density)
  times['range'] = time.perf_counter() - start
  config = diplopia.DiplopiaConfig()
  config = dataclasses.replace(config, matching=dataclasses.replace(
      config.matching, min_disparity=search[0], max_disparity=search[1]))
  costs(image01[:64, :128], config)  # Tracing.
  start = time.perf_counter()
  volume = costs(image01, config)
  times['costs'] = time.perf_counter() - start
  start = time.perf_counter()
  matched = parallel_sgm.match_volume(volume, config.matching,
                                     threads=workers.usable_cpus(0))
  times['sgm'] = time.perf_counter() - start
  start = time.perf_counter()
  weight = diplopia_weight.estimate_weight(image01, matched['disparity_left'],
                                           matched['consistent_left'])
  times['weight'] = time.perf_counter() - start
  start = time.perf_counter()
  diplopia_layers.separate_layers(image01, matched['disparity_right'], weight=weight)
  times['layers'] = time.perf_counter() - start
  return search, times


# One frame's stage timings: label -> the expression of its costs function (`b`: this
# module, in the process that measures).
STAGE_ROWS = {
    # Checkouts before diplopia_costs held zncc_costs in diplopia.
    'classical': 'getattr(b, "diplopia_costs", b.diplopia).zncc_costs',
    'learned echo': ('b.learned_diplopia.echo_costs(b.learned_diplopia.echo_function('
                     'b.pretrained.load_model(b.pretrained.get("diplopia_echo"))))')}


def main(argv):
  del argv
  count = FLAGS.diplopia_frames
  runs = [('', '')] + ([(' (before)', FLAGS.before_checkout)] if FLAGS.before_checkout
                       else [])
  root = tempfile.mkdtemp()
  try:
    path = os.path.join(root, 'clip.mp4')
    writer = streams.VideoWriter(path, fractions.Fraction(25))
    for index, image in enumerate(frames(count)):
      writer.write(image, fractions.Fraction(index, 25))
    writer.close()
    print(f'| method | {WIDTH}x{HEIGHT} frames/s, per frame (unmix only) | per shot, the '
          'default (unmix only) |')
    print('|---|---:|---:|')
    for method in METHODS:
      for suffix, checkout in runs:
        cells = [checkouts.measure('benchmark_diplopia', f'b.video_fps({method!r}, '
                                   f'{path!r}, {count}, {per_shot})', checkout)
                 for per_shot in (False, True)]
        print(f'| {method}{suffix} | ' + ' | '.join(f'{fps:.3f} ({unmix:.3f})'
                                                    for fps, unmix in cells) + ' |',
              flush=True)
    print('\n| one frame | range searched | ' + ' | '.join(STAGES) + ' | total |')
    print('|---|---|' + '---:|' * (len(STAGES) + 1))
    for label, costs in STAGE_ROWS.items():
      for suffix, checkout in runs:
        search, times = checkouts.measure(
            'benchmark_diplopia', f'b.stage_seconds(b.frames({count})[0], {costs}, 0.02)',
            checkout)
        print(f'| {label}{suffix} | {list(search)} | ' +
              ' | '.join(f'{times[k]:.2f}' for k in STAGES) +
              f' | {sum(times.values()):.2f} |', flush=True)
    if FLAGS.diplopia_photo_size:
      print(f'\n| {FLAGS.diplopia_photo_size} double image | photo_12mp.py |\n|---|---|')
      for method, arguments in PHOTO_METHODS.items():
        for suffix, checkout in runs:
          print(f'| {method}{suffix} | {photo(arguments, checkout)} |', flush=True)
  finally:
    shutil.rmtree(root, ignore_errors=True)


if __name__ == '__main__':
  app.run(main)
