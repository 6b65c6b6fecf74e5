"""Speed of encoding detection (`unmixing.detection.detect`, what `--mixture=auto` and every
unmix run first), before and after a change, in one run.

    python -m experiments.benchmark_detection [--before_checkout=DIR]

Inputs: the colour anaglyphs of `benchmark_matcher`'s three cases (1242x375, 1280x720
window-aligned, 4000x3000). Each tree is timed in its own fresh process, this file run as
a script there (its package and `experiments.benchmark_matcher` from that tree, checked):
one warm-up call, then the median and min wall seconds of `--detection_repeats` calls.
"""

import json
import os
import statistics
import subprocess
import sys
import time

from absl import app
from absl import flags

from experiments import checkouts  # pylint: disable=unused-import  # --before_checkout.

flags.DEFINE_integer('detection_repeats', 5, 'Timed calls per case.')
FLAGS = flags.FLAGS
_RESULT = 'RESULT '


def _measure(repeats: int) -> dict:
  """{case: {'median_s', 'min_s', 'detected'}} in this process's tree."""
  import numpy as np  # pylint: disable=import-outside-toplevel
  import mixstereo_tf  # pylint: disable=import-outside-toplevel
  from experiments import benchmark_matcher  # pylint: disable=import-outside-toplevel
  from mixstereo_tf.unmixing import detection  # pylint: disable=import-outside-toplevel
  out = {'package': mixstereo_tf.__file__}
  for case in benchmark_matcher.CASES:
    left, right = benchmark_matcher.anaglyph_case(case)[:2]
    image = np.clip(np.round(np.dstack([left, right])), 0, 255).astype(np.uint8)
    detection.detect(image)
    walls = []
    for _ in range(repeats):
      start = time.perf_counter()
      found = detection.detect(image)
      walls.append(time.perf_counter() - start)
    out[case] = {'median_s': statistics.median(walls), 'min_s': min(walls),
                 'detected': found.name}
  return out


def run_tree(tree: str, repeats: int) -> dict:
  """`_measure` in a fresh process of `tree` (a checkout, or the working tree)."""
  tree = os.path.abspath(tree)
  env = dict(os.environ, PYTHONPATH=tree)
  text = subprocess.run([sys.executable, os.path.abspath(__file__), str(repeats)],
                        capture_output=True, text=True, check=True, env=env,
                        cwd=tree).stdout
  result = json.loads(text.split(_RESULT, 1)[1])
  if not os.path.abspath(result['package']).startswith(tree + os.sep):
    raise RuntimeError(f'{tree}: the package came from {result["package"]} (a stale '
                       'install?).')
  return result


def main(argv):
  del argv
  trees = {'after': os.getcwd()}
  if FLAGS.before_checkout:
    trees = {'before': FLAGS.before_checkout, **trees}
  results = {label: run_tree(tree, FLAGS.detection_repeats) for label, tree in trees.items()}
  print('| tree | ' + ' | '.join(c for c in results['after'] if c != 'package') + ' |')
  for label, result in results.items():
    cells = [f"{v['median_s']:.3f} s ({v['min_s']:.3f}), {v['detected']}"
             for c, v in result.items() if c != 'package']
    print(f'| {label} | ' + ' | '.join(cells) + ' |')


if __name__ == '__main__':
  if len(sys.argv) == 2 and sys.argv[1].isdigit():  # A tree's worker (`run_tree`).
    print(_RESULT + json.dumps(_measure(int(sys.argv[1]))))
  else:
    app.run(main)
