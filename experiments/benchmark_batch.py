"""Seconds per image of `mixstereo-batch` (Apache Beam, 1 and 2 worker processes) against
`mixstereo-unmix` on one folder of real-size anaglyphs (experiments/BENCHMARKS.md, "Batch
(Apache Beam)").

    python experiments/benchmark_batch.py [--batch_bench_images=8] \
        [--batch_bench_method=classical] [--batch_bench_table=experiments/BENCHMARKS.md]

The folder: scikit-image's Motorcycle pair (Middlebury 2014) resized to 1.1 times
--batch_bench_size and cut at a different offset per image, encoded as red-cyan colour
anaglyphs (`mixtures`). Each command runs in a fresh process and output folder with
`--mixture=auto --disparity_range=auto`; its wall time (start-up included) over the
images is the number reported; in brackets the mean seconds inside the unmixer
(info.json), start-up and file I/O left out. The batch runs use Beam's local Python runner
(FnApiRunner) in the tool's own process (its default) and with 1 and 2 worker processes.
Every run's files must equal `mixstereo-unmix`'s (info.json apart). Prints the markdown
row and appends it to --batch_bench_table when given.
"""

import datetime
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

from absl import app
from absl import flags
import cv2
import skimage.data

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.cli import media
from mixstereo_tf.evaluation import realworld

flags.DEFINE_integer('batch_bench_images', 8, 'Anaglyphs in the folder.')
flags.DEFINE_string('batch_bench_size', '1400x1000', 'WIDTHxHEIGHT of each anaglyph.')
flags.DEFINE_enum('batch_bench_method', 'classical', ('classical', 'model'),
                  'classical, or model: the shipped model.')
flags.DEFINE_string('batch_bench_table', '', 'A markdown file to append the row to.')
FLAGS = flags.FLAGS

HEADER = ('| date | load start / end | images | method | unmix s/img | batch in-process '
          's/img | batch 1 worker s/img | batch 2 workers s/img | 2 vs 1 workers | outputs '
          'equal |\n|---|---|---|---|---:|---:|---:|---:|---:|---|')


def make_folder(folder: str, count: int, width: int, height: int) -> None:
  """`count` anaglyphs of width x height, each a different crop of the resized pair."""
  left, right, _ = skimage.data.stereo_motorcycle()
  size = (round(width * 1.1), round(height * 1.1))
  left, right = (cv2.resize(v, size, interpolation=cv2.INTER_CUBIC) for v in (left, right))
  for index in range(count):
    x = index * (size[0] - width) // max(count - 1, 1)
    y = (count - 1 - index) * (size[1] - height) // max(count - 1, 1)
    crop = {'left': left[y:y + height, x:x + width], 'right': right[y:y + height, x:x + width]}
    media.write_image(os.path.join(folder, f'scan{index:02d}.png'),
                      realworld.make_anaglyph(crop, 'anaglyph', 'ours'))


def timed(args) -> float:
  """Wall seconds of `python -m args`, which must exit 0."""
  start = time.perf_counter()
  result = subprocess.run([sys.executable, '-m', *args], capture_output=True, text=True,
                          check=False)
  if result.returncode:
    raise RuntimeError(f'{" ".join(args[:1])} failed:\n{result.stderr[-3000:]}')
  return time.perf_counter() - start


def unmixer_seconds(folder: str) -> float:
  """Mean seconds inside the unmixer per image (the info.json files' `seconds`)."""
  values = []
  for name in os.listdir(folder):
    if name.endswith('_info.json'):
      with open(os.path.join(folder, name), encoding='utf-8') as f:
        values.append(json.load(f)['seconds'])
  return sum(values) / len(values)


def same_outputs(reference: str, other: str) -> bool:
  """Every file of `reference` exists in `other` with the same bytes (info.json apart)."""
  for name in os.listdir(reference):
    if name.endswith('_info.json'):
      continue
    with open(os.path.join(reference, name), 'rb') as a, open(os.path.join(other, name),
                                                              'rb') as b:
      if a.read() != b.read():
        return False
  return True


def main(argv):
  del argv
  width, height = (int(v) for v in FLAGS.batch_bench_size.split('x'))
  work = tempfile.mkdtemp(prefix='batch_bench_')
  folder = os.path.join(work, 'in')
  os.makedirs(folder)
  make_folder(folder, FLAGS.batch_bench_images, width, height)
  common = [f'--method={FLAGS.batch_bench_method}', '--mixture=auto', f'--input={folder}']
  commands = {'unmix': ['mixstereo_tf.unmix'], 'batch0': ['mixstereo_tf.batch']}
  for workers in (1, 2):
    commands[f'batch{workers}'] = ['mixstereo_tf.batch', '--runner=FnApiRunner',
                                   f'--direct_num_workers={workers}',
                                   '--direct_running_mode=multi_processing']
  load = os.getloadavg()[0]  # The machine may be shared: 1-minute load at start and end.
  seconds, cells = {}, []
  for name, command in commands.items():
    out = os.path.join(work, name)
    seconds[name] = timed([*command, *common, f'--output_dir={out}'])
    cells.append(f'{seconds[name] / FLAGS.batch_bench_images:.2f} ({unmixer_seconds(out):.2f})')
  equal = all(same_outputs(os.path.join(work, 'unmix'), os.path.join(work, name))
              for name in commands if name != 'unmix')
  row = '| ' + ' | '.join([
      f'{datetime.datetime.now():%Y-%m-%d %H:%M}', f'{load:.2f} / {os.getloadavg()[0]:.2f}',
      f'{FLAGS.batch_bench_images} x {width}x{height}', FLAGS.batch_bench_method, *cells,
      f'{seconds["batch1"] / seconds["batch2"]:.2f}x', 'yes' if equal else 'NO']) + ' |'
  print(HEADER)
  print(row)
  if FLAGS.batch_bench_table:
    with open(FLAGS.batch_bench_table, 'a', encoding='utf-8') as f:
      f.write(row + '\n')
  shutil.rmtree(work)


if __name__ == '__main__':
  app.run(main)
