"""Speed of the learned matching stage against the previous default and the classical
method, in one run (BENCHMARKS.md section 18): a 1280x720 anaglyph video end to end
(`benchmark_video.video_speed`: decode, unmix, encode side-by-side and disparity videos)
and a 4000x3000 photo (`photo_12mp.py`: wall seconds, CPU seconds, peak resident memory),
each measurement in its own process.

    python -m experiments.benchmark_learned [--before_checkout=DIR] [--nolearned_photos]
        [--learned_video_bits=10] [--nolearned_video_keep_bits] [--learned_video_mixture=dubois]

With --before_checkout (a checkout of an earlier commit, e.g. `git worktree add DIR REV`)
each row's video is also run in that checkout (its package and experiments) in the same
run: the "before" of a change.
"""

import os
import subprocess
import sys

from absl import app
from absl import flags

from experiments import benchmark_video
from experiments import checkouts  # Defines --before_checkout.

flags.DEFINE_integer('learned_video_bits', 8, 'Bits per sample of the video clip (10: '
                     'H.264 High 10, as a 10-bit phone or HDR video).')
flags.DEFINE_bool('learned_video_keep_bits', True, 'Views of a 10-bit clip written at 10 '
                  'bits; --nolearned_video_keep_bits: at 8, as --nokeep_video_bits.')
flags.DEFINE_string('learned_video_mixture', 'anaglyph', 'Encoding of the video clip '
                    '(anaglyph: detected by --mixture=auto; another: named).')
flags.DEFINE_bool('learned_photos', True, 'Also each row\'s 4000x3000 photo (minutes a '
                  'row); --nolearned_photos: the videos alone.')
FLAGS = flags.FLAGS

ROWS = ('classical', 'refiner', 'model')
PHOTO = {'classical': ['--photo_method=classical'],
         'refiner': ['--photo_method=model', '--photo_pretrained=anaglyph'],
         'model': ['--photo_method=model']}


def _video(method, checkout=''):
  """`benchmark_video.video_speed` of `method` in its own process (in `checkout` when
  given)."""
  return checkouts.measure('benchmark_video', f'b.video_speed({method!r}, 1280, 720, '
                           f'bits={FLAGS.learned_video_bits}, '
                           f'mixture={FLAGS.learned_video_mixture!r}, '
                           f'keep_bits={FLAGS.learned_video_keep_bits})', checkout)


def _photo(method):
  # The working tree's package, not an installed copy that may be stale.
  out = subprocess.run([sys.executable, 'experiments/photo_12mp.py', *PHOTO[method]],
                       capture_output=True, text=True, check=True,
                       env=dict(os.environ, PYTHONPATH=os.getcwd())).stdout
  return out.strip().splitlines()[-1]


def _cells(video):
  """The video columns: frames/s of the whole call (inside the unmixer), per variant, and
  the left views' PSNR (dB) when measured."""
  return [f"{video[v]['fps']:.2f} ({video[v]['unmix_fps']:.2f})" + (
      f", {video[v]['left_psnr']:.2f} dB" if 'left_psnr' in video[v] else '')
          for v, _ in benchmark_video.QUALITY_VARIANTS]


def main(argv):
  del argv
  load = os.getloadavg()
  lines = ['| method | 1280x720 video, per frame: frames/s (unmix only), left view PSNR | '
           'per shot + prior | 4000x3000 photo |', '| --- | --- | --- | --- |']
  for method in ROWS:
    if FLAGS.before_checkout:
      lines.append(f'| {method}, before | ' + ' | '.join(
          _cells(_video(method, FLAGS.before_checkout))) + ' | |')
    photo = _photo(method) if FLAGS.learned_photos else 'not run'
    lines.append(f'| {method} | ' + ' | '.join(_cells(_video(method))) + f' | {photo} |')
  print(f'load average at start {load[0]:.2f}, at end {os.getloadavg()[0]:.2f}')
  print('\n'.join(lines))


if __name__ == '__main__':
  app.run(main)
