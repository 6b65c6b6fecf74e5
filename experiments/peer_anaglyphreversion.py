"""A public peer as a baseline: `andreldc/anaglyphreversion` run locally beside our methods.

    git clone https://github.com/andreldc/anaglyphreversion /tmp/anaglyphreversion
    python -m experiments.peer_anaglyphreversion --peer_dir=/tmp/anaglyphreversion \
        [--shared_dir=../shared/stereo_samples]

The peer (window costs on a differential representation of the red and the cyan channels,
Gaussian aggregation, a left-right check, refinement, then a colourisation that fills each
eye's missing channels from matched neighbours of similar colour) is imported from
--peer_dir and called as its own `reverse.reverse(anaglyph_bgr, min_disp, max_disp)`; no
code of it is in this project. It searches positive disparities only, so every scene is
used as captured (not window-aligned) and the peer is given the ground truth's range
(its own configuration gives a range per image; ours estimate theirs from the image).
Scenes: those of experiments/same_channel.py (procedural held-out scenes, Motorcycle, the
shared SceneFlow and KITTI object frames), colour anaglyphs by FFmpeg. Rows: the peer,
classical, the learned stage (the default), the learned stage + refiner and the refiner, in the
same run; bad-1 over the valid ground truth and the views' RGB PSNR.
"""

import contextlib
import io
import os
import sys
import tempfile
import time

from absl import app
from absl import flags
import cv2

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.evaluation import realworld

import numpy as np

from experiments import markdown
from experiments import same_channel

flags.DEFINE_string('peer_dir', None, 'A checkout of andreldc/anaglyphreversion.')
flags.DEFINE_string('peer_output', 'experiments/results/peer_anaglyphreversion.md',
                    'Markdown report.')
flags.DEFINE_integer('peer_procedural', 3, 'Procedural held-out scenes used (the peer is '
                     'slow: its colourisation loops in Python).')
flags.mark_flag_as_required('peer_dir')
FLAGS = flags.FLAGS
ENCODING = 'anaglyph'
OURS = ('classical', 'learned', 'learned + refiner', 'refiner')


def _peer(peer_dir):
  """The peer's `reverse` function, imported from its checkout. It closes GUI windows
  after every step, which headless OpenCV cannot: that call is made a no-op."""
  cv2.destroyAllWindows = lambda: None
  sys.path.insert(0, os.path.abspath(peer_dir))
  import reverse  # pylint: disable=g-import-not-at-top,import-outside-toplevel
  return reverse.reverse


def _run_peer(reverse, anaglyph_rgb, data):
  """(left, right, disparity_left) of the peer; its prints are swallowed and the images
  it writes to the working folder land in a temporary one."""
  valid = data['valid_left']
  low, high = np.percentile(data['disparity_left'][valid], [0.5, 99.5])
  with contextlib.redirect_stdout(io.StringIO()), tempfile.TemporaryDirectory() as folder, \
      contextlib.chdir(folder):
    left, right, pickled, _ = reverse(np.ascontiguousarray(anaglyph_rgb[..., ::-1]),
                                      max(1, int(np.floor(low))), int(np.ceil(high)) + 1)
  disparity = np.asarray(pickled['refined_disparity_map'][0], np.float32)
  return left[..., ::-1], right[..., ::-1], disparity


def _scenes(shared_dir, procedural):
  kept = 0
  for name, data in same_channel.scenes(shared_dir):
    if name.startswith('synthetic'):
      kept += 1
      if kept > procedural:
        continue
    yield name, dict(data, shift=0)


def _evaluate(reverse, shared_dir, procedural):
  rows = []
  for scene, pair in _scenes(shared_dir, procedural):
    image = realworld.make_anaglyph(pair, ENCODING, 'ffmpeg')
    start = time.perf_counter()
    left, right, disparity = _run_peer(reverse, image, pair)
    rows.append(dict(scene=scene, method='peer', seconds=time.perf_counter() - start,
                     **realworld.score(pair, left, right, disparity)))
    for method in OURS:
      start = time.perf_counter()
      out = same_channel.unmixer(ENCODING, method)(image)
      rows.append(dict(scene=scene, method=method, seconds=time.perf_counter() - start,
                       **realworld.score(pair, out['left'], out['right'],
                                         out['disparity_left'])))
    for row in rows[-1 - len(OURS):]:
      print(scene, row['method'], f"bad-1 {row['bad1']:.3f}", f"{row['psnr_left']:.2f}",
            f"{row['psnr_right']:.2f}", file=sys.stderr, flush=True)
  return rows


def main(argv):
  del argv
  start = time.perf_counter()
  rows = _evaluate(_peer(FLAGS.peer_dir), FLAGS.shared_dir, FLAGS.peer_procedural)
  text = ['# Peer baseline: andreldc/anaglyphreversion beside our methods', '',
          f'Written by `python -m experiments.peer_anaglyphreversion --peer_dir=... '
          f'--shared_dir=...` in {time.perf_counter() - start:.0f} s on {os.cpu_count()} '
          'CPU cores. Colour anaglyphs (FFmpeg\'s stereo3d, `realworld.make_anaglyph`) of '
          'the pairs as captured (positive disparities; the peer searches the ground '
          "truth's 0.5-99.5 percentile range, ours estimate it from the image). "
          f'Procedural: the first {FLAGS.peer_procedural} held-out scenes. learned = the '
          'default, `--pretrained=anaglyph_matching`; learned + refiner = the shipped refiner '
          'run on the learned stage instead of the classical method; refiner = the previous '
          'default (`--pretrained=anaglyph`). Seconds on a machine shared with training '
          'runs.', '', *same_channel.method_table(rows, ('peer',) + OURS, seconds=True), '']
  markdown.write(FLAGS.peer_output, text)


if __name__ == '__main__':
  app.run(main)
