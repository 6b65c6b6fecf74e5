r"""Input pipeline throughput: pairs per second at 256x512 crops, in one run.

  python experiments/bench_data.py [--num_pairs=200 --kitti_files=40]

Sources: the embedded `sample` source (scenes rendered on the fly at the size of
--scene_height/--scene_width), and a folder of KITTI-sized (375x1242) PNG pairs this
script writes, read through a split list exactly as `--dataset=kitti_raw` does. Not a
test: this machine is shared and noisy; compare the two rows of one run.
"""

import os
import tempfile
import time

from absl import app
from absl import flags
import cv2
import numpy as np

from mixstereo_tf import models
from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.data import kitti
from mixstereo_tf.data import pipeline
from mixstereo_tf.data import sample

flags.DEFINE_integer('num_pairs', 200, 'Pairs timed per source (after 10 warm-up pairs).')
flags.DEFINE_integer('kitti_files', 40, 'Distinct KITTI-sized pairs written to disk.')
flags.DEFINE_integer('scene_height', 288, 'Height of `sample` scenes (>= the crop).')
flags.DEFINE_integer('scene_width', 576, 'Width of `sample` scenes (>= the crop).')
cli_flags.define_mixture()
FLAGS = flags.FLAGS


def write_kitti_folder(root: str, count: int) -> str:
  """Writes `count` random-texture 375x1242 pairs in the KITTI raw layout; returns a list."""
  rng = np.random.default_rng(0)
  lines = []
  for i in range(count):
    for camera in ('image_02', 'image_03'):
      folder = os.path.join(root, '2011_09_26', '2011_09_26_drive_0001_sync', camera, 'data')
      os.makedirs(folder, exist_ok=True)
      noise = rng.integers(0, 256, (94, 311, 3), dtype=np.uint8)
      image = cv2.resize(noise, (1242, 375), interpolation=cv2.INTER_LINEAR)
      cv2.imwrite(os.path.join(folder, f'{i:010d}.png'), image)
    path = f'2011_09_26/2011_09_26_drive_0001_sync/image_0%d/data/{i:010d}.jpg'
    lines.append(f'{path % 2} {path % 3}')  # The lists name .jpg; the files are .png.
  list_path = os.path.join(root, 'files.txt')
  with open(list_path, 'w') as f:
    f.write('\n'.join(lines) + '\n')
  return list_path


def pairs_per_second(dataset, count: int) -> float:
  """Elements per second of `dataset` over `count` elements, after 10 warm-up elements."""
  iterator = iter(dataset)
  for _ in range(10):
    next(iterator)
  start = time.perf_counter()
  for _ in range(count):
    next(iterator)
  return count / (time.perf_counter() - start)


def main(argv):
  del argv
  config = pipeline.PipelineConfig(mixture=FLAGS.mixture or 'anaglyph', crop_height=256,
                                   crop_width=512)
  rows = []
  samples = sample.sample_records('train', num_scenes=FLAGS.num_pairs + 10,
                                  height=FLAGS.scene_height, width=FLAGS.scene_width,
                                  max_disparity=models.ModelConfig().max_disparity)
  rows.append((f'sample ({FLAGS.scene_height}x{FLAGS.scene_width} scenes rendered)',
               pairs_per_second(pipeline.train_dataset(samples, config), FLAGS.num_pairs)))
  with tempfile.TemporaryDirectory() as root:
    list_path = write_kitti_folder(root, FLAGS.kitti_files)
    samples = kitti.read_split_list(list_path, root).samples
    rows.append(('KITTI-sized PNGs (375x1242, split list)',
                 pairs_per_second(pipeline.train_dataset(samples, config), FLAGS.num_pairs)))
  print(f'{"source":<48}{"pairs/s at 256x512":>20}')
  for name, rate in rows:
    print(f'{name:<48}{rate:>20.1f}')
  print(f'cores: {os.cpu_count()}')


if __name__ == '__main__':
  app.run(main)
