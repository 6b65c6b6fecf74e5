"""Speed of the learned matching stage against the previous default and the classical
method, in one run (BENCHMARKS.md section 18): a 1280x720 anaglyph video end to end
(`benchmark_video.video_speed`: decode, unmix, encode side-by-side and disparity videos)
and a 4000x3000 photo (`photo_12mp.py`: wall seconds, CPU seconds, peak resident memory),
each measurement in its own process.

    python -m experiments.benchmark_learned
"""

import json
import os
import subprocess
import sys

from experiments import benchmark_video

ROWS = ('classical', 'refiner', 'model')
PHOTO = {'classical': ['--photo_method=classical'],
         'refiner': ['--photo_method=model', '--photo_pretrained=anaglyph'],
         'model': ['--photo_method=model']}


def _video(method):
  code = ('import json, mixstereo_tf; from experiments import benchmark_video as b; '
          f'print("RESULT", json.dumps(b.video_speed({method!r}, 1280, 720)))')
  out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                       check=True).stdout
  return json.loads(out.split('RESULT ', 1)[1])


def _photo(method):
  out = subprocess.run([sys.executable, 'experiments/photo_12mp.py', *PHOTO[method]],
                       capture_output=True, text=True, check=True).stdout
  return out.strip().splitlines()[-1]


def main():
  load = os.getloadavg()
  lines = ['| method | 1280x720 video, per frame: frames/s (unmix only) | per shot + prior | '
           '4000x3000 photo |', '| --- | --- | --- | --- |']
  for method in ROWS:
    video = _video(method)
    cells = [f"{video[v]['fps']:.2f} ({video[v]['unmix_fps']:.2f})"
             for v, _ in benchmark_video.QUALITY_VARIANTS]
    lines.append(f'| {method} | ' + ' | '.join(cells) + f' | {_photo(method)} |')
  print(f'load average at start {load[0]:.2f}, at end {os.getloadavg()[0]:.2f}')
  print('\n'.join(lines))


if __name__ == '__main__':
  main()
