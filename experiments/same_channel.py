"""The same-channel diagnostic (issue "Learned cross-channel matching"): how much worse the
matching gets because an anaglyph's eyes are seen through different colour channels.

    python -m experiments.same_channel [--shared_dir=../shared/stereo_samples] \
        [--same_channel_output=experiments/results/same_channel.md]

Scenes with ground truth: the `sample` held-out scenes (8 procedural, averaged, + Motorcycle)
and, from --shared_dir, the SceneFlow frame and the KITTI object frame (sparse ground truth:
its Velodyne scan projected into the left camera). The KITTI 2015 frame there has none: it
is scored on its views alone (bad-1 '-'), its window placed by the census matcher's
consistent disparities of the pair's luma (`views_only_scene`). Each pair is window-aligned
at 30 % (`realworld.window_align`, as experiments/realworld.py) and made into anaglyphs by
FFmpeg: the colour ('anaglyph'), 'half_color' and 'dubois_ffmpeg' encodings and the gray
anaglyph ('gray'), whose two eyes carry the same luminance channel: the same-channel
reference. Scored: classical on each, the 'sgbm' peer baseline on the colour and the gray
anaglyph; bad-1 / bad-3 / EPE over the valid ground truth, views' RGB PSNR, and each bad-1
over the same method's on 'gray'.
The procedural scenes run twice, the second time with independent noise on each view
(`validation.noisy`): rendered views share their texture's noise exactly, which flatters
the same-channel reference (experiments/channel_information.py).
Row 'true disparity' (scenes with dense ground truth): the shipped restoration on the true
left disparity and the right one forward-warped from it (`eye_order.right_from_left`;
the learned stage's where either is unknown): what the views would be with perfect
matching, the views' headroom that matching can give.
"""

import csv
import functools
import os
import platform
import sys
import time

from absl import app
from absl import flags

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.data import image_io
from mixstereo_tf.data import real_pairs
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.core import image_range
from mixstereo_tf.core import precision
from mixstereo_tf.restoration import views
from mixstereo_tf.unmixing import eye_order
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.unmixing import shipped

import numpy as np

from experiments import markdown
from experiments import validation  # `noisy`; defines --photo_dir (unused here).

cli_flags.define_shared_dir()
flags.DEFINE_string('same_channel_output', 'experiments/results/same_channel.md',
                    'Markdown report (a .csv of the rows beside it).')
FLAGS = flags.FLAGS

FRACTION = 0.3
REFERENCE = 'gray'
# Row label -> the predictor: the classical method, the learned matching stage (the shipped
# 'anaglyph_matching' features), the refiner trained on it ('anaglyph_refined', which runs
# on it), the classical method's refiner on it, the refiner on the classical result, and
# OpenCV's SGBM, the peer baseline.
METHODS = {'classical': dict(method='classical'),
           'learned': dict(method='model', pretrained='anaglyph_matching'),
           'learned + its refiner': dict(method='model', pretrained='anaglyph_refined'),
           'learned + refiner': dict(method='model', pretrained='anaglyph'),
           'refiner': dict(method='model', pretrained='anaglyph'),
           'sgbm': dict(method='sgbm')}
# Rows whose shipped refiner runs on the learned stage instead of the classical method.
ON_LEARNED = {'learned + refiner': 'anaglyph_matching'}
ENCODINGS = ('anaglyph', 'half_color', 'dubois_ffmpeg', REFERENCE)
RUNS = tuple((name, method) for method in ('classical', 'learned', 'learned + its refiner',
                                           'learned + refiner', 'refiner')
             for name in ENCODINGS) + (('anaglyph', 'sgbm'), (REFERENCE, 'sgbm'))
KITTI_FRAME = 'kitti_object_velodyne'
KITTI_2015_FRAME = ('kitti2015_aanet_000151', 'image_2.png', 'image_3.png')
TRUTH = 'true disparity'
DENSE = 0.9  # Share of valid ground truth from which a scene gets the TRUTH row.


def group(name):
  """The table's scene group of a scene name."""
  return 'procedural (mean)' if name.startswith('synthetic') else name


@functools.cache
def unmixer(name, method):
  """The Unmixer of a row label (`METHODS`) for encoding `name`."""
  config = predictors.PredictorConfig(mixture=name, **METHODS[method])
  if method in ON_LEARNED:
    return shipped.pretrained_unmixer(pretrained.choose(config.pretrained, name), config,
                                      pretrained.get(ON_LEARNED[method]))
  return predictors.build_unmixer(config)


def views_only_scene(left, right):
  """A pair without ground truth, scored on its views alone: `realworld.
  estimated_disparities`, there only to place the window; 'views_only' tells `_evaluate` to
  drop them after."""
  return dict(realworld.estimated_disparities(left, right), views_only=True)


def without_estimated_truth(data, pair):
  """`pair` (`data` or a crop of it) with 'valid_left' all False where data's disparities
  were only estimated (`views_only_scene`: they place the window, they score nothing)."""
  if data.get('views_only'):
    return dict(pair, valid_left=np.zeros_like(pair['valid_left']))
  return pair


def scenes(shared_dir, views_only=False):
  """(name, data) of every scene with ground truth (module docstring); with `views_only`,
  then the frames without (`views_only_scene`, data['views_only'] set)."""
  yield from realworld.scenes(shared_dir)
  folder = os.path.join(shared_dir or '', KITTI_FRAME)
  if shared_dir and os.path.isdir(folder):
    yield KITTI_FRAME, real_pairs.kitti_object_frame(folder)
  if not views_only:
    return
  folder, left, right = KITTI_2015_FRAME
  folder = os.path.join(shared_dir or '', folder)
  if shared_dir and os.path.isdir(folder):
    yield KITTI_2015_FRAME[0], views_only_scene(
        *(image_io.read_image(os.path.join(folder, name)) for name in (left, right)))


def _score(pair, out):
  """realworld.score plus the end-point error (pixels) over the valid ground truth."""
  row = realworld.score(pair, out['left'], out['right'], out['disparity_left'])
  shift = pair['shift']  # The metrics read GT <= 0 as unknown: compare unshifted.
  row['epe'] = metrics.end_point_error(out['disparity_left'] + shift,
                                       pair['disparity_left'] + shift, pair['valid_left'])
  return row


def true_disparity_views(pair, image, name, learned):
  """The TRUTH row's outputs (module docstring) for anaglyph `image` of `pair`; `learned`:
  the learned stage's outputs on it, where the truth is unknown."""
  d_left = np.where(pair['valid_left'], pair['disparity_left'],
                    learned['disparity_left']).astype(np.float32)
  d_right = eye_order.right_from_left(d_left)
  d_right = np.where(np.isfinite(d_right), d_right,
                     learned['disparity_right']).astype(np.float32)
  restored = views.restore_views(image_range.u8_to_unit(image), name, d_left, d_right)
  return {'left': image_range.unit_to_u8(restored['left']),
          'right': image_range.unit_to_u8(restored['right']),
          'disparity_left': d_left, 'info': learned['info']}


def pairs(shared_dir, views_only=False):
  """(group, scene, window-aligned pair) of every run (`scenes`; those without ground truth
  with `views_only`, their valid_left all False); the rendered scenes (grouped) twice, the
  second time with `validation.noisy` views."""
  for number, (scene, data) in enumerate(scenes(shared_dir, views_only)):
    pair = without_estimated_truth(data, realworld.window_align(data, FRACTION))
    yield group(scene), scene, pair
    if group(scene) != scene:
      yield (f'{group(scene)} + noise {validation.NOISE_SIGMA:g}', scene,
             validation.noisy(pair, number))


def _evaluate(shared_dir):
  rows = []
  for scenes_group, scene, pair in pairs(shared_dir, views_only=True):
    dense = np.mean(pair['valid_left']) >= DENSE
    learned = {}  # Encoding -> the learned stage's outputs, for the TRUTH rows.
    for name, method in RUNS + tuple((n, TRUTH) for n in ENCODINGS if dense):
      image = realworld.make_anaglyph(pair, name, 'ffmpeg')
      start = time.perf_counter()
      out = (true_disparity_views(pair, image, name, learned[name]) if method == TRUTH
             else unmixer(name, method)(image))
      if method == 'learned':
        learned[name] = out
      rows.append(dict(scene=scene, group=scenes_group, encoding=name, method=method,
                       shift=pair['shift'], searched=out['info']['disparity_range'],
                       seconds=round(time.perf_counter() - start, 2), **_score(pair, out)))
      print(scenes_group, scene, name, method, f"bad-1 {rows[-1]['bad1']:.3f}",
            file=sys.stderr, flush=True)
  return rows


def mean(rows, key):
  """The mean of column `key` over `rows`, NaN (no ground truth) left out; NaN if none."""
  values = [r[key] for r in rows if np.isfinite(r[key])]
  return float(np.mean(values)) if values else float('nan')


def method_table(rows, methods, title='method', seconds=False):
  """Markdown rows: per scene group and method (row 'method' of `rows`), the mean bad-1 and
  RGB PSNR L / R (and seconds): the tables of matching_ablations and peer_anaglyphreversion."""
  lines = [f'| scenes | {title} | bad-1 | RGB PSNR L / R (dB) |' + (' seconds |' if seconds
                                                                   else ''),
           '| --- ' * (5 if seconds else 4) + '|']
  for name in dict.fromkeys(group(r['scene']) for r in rows):
    for method in methods:
      these = [r for r in rows if group(r['scene']) == name and r['method'] == method]
      average = lambda key: float(np.mean([r[key] for r in these]))  # pylint: disable=cell-var-from-loop
      lines.append(f"| {name} | {method} | {100 * average('bad1'):.1f}% | "
                   f"{average('psnr_left'):.2f} / {average('psnr_right'):.2f} |"
                   + (f" {average('seconds'):.1f} |" if seconds else ''))
  return lines


def cell(value, percent=False):
  """'12.3%' of a share (percent) or '1.23', '-' of NaN (a scene without ground truth)."""
  if not np.isfinite(value):
    return '-'
  return f'{100 * value:.1f}%' if percent else f'{value:.2f}'


def _table(rows):
  lines = ['| scenes | encoding | method | bad-1 | bad-3 | EPE px | RGB PSNR L / R | '
           f'bad-1 / {REFERENCE} (same method) |', '| --- ' * 8 + '|']
  for group in dict.fromkeys(r['group'] for r in rows):
    for name, method in RUNS + tuple((n, TRUTH) for n in ENCODINGS):
      these = [r for r in rows if r['group'] == group and r['encoding'] == name
               and r['method'] == method]
      if not these:
        continue
      gray = mean([r for r in rows if r['group'] == group and r['encoding'] == REFERENCE
                    and r['method'] == method], 'bad1')
      bad1 = mean(these, 'bad1')
      ratio = ('-' if method == TRUTH or not np.isfinite(bad1) else 'reference'
               if name == REFERENCE else f'{bad1 / gray:.2f}x')
      lines.append(f"| {group} | {name} | {method} | {cell(bad1, True)} | "
                   f"{cell(mean(these, 'bad3'), True)} | {cell(mean(these, 'epe'))} | "
                   f"{mean(these, 'psnr_left'):.2f} / {mean(these, 'psnr_right'):.2f} | "
                   f'{ratio} |')
  return lines


def _write_csv(rows, path):
  with open(path, 'w', newline='') as handle:
    writer = csv.DictWriter(handle, list(dict.fromkeys(k for r in rows for k in r)))
    writer.writeheader()
    writer.writerows(rows)


def _precision() -> str:
  """The header's words for the precision the learned stages ran in."""
  if not precision.inference_bfloat16():
    return 'float32'
  return ('bfloat16 (`core/precision.py`; their rows differ from float32, '
          f'`{precision.ENVIRONMENT}=0`: the default\'s by up to 0.2 points of bad-1 and '
          '0.09 dB, the refiners\' by up to 0.3 points and 0.24 dB, 2026-11-30)')


def main(argv):
  del argv
  start = time.perf_counter()
  rows = _evaluate(FLAGS.shared_dir)
  _write_csv(rows, os.path.splitext(FLAGS.same_channel_output)[0] + '.csv')
  machine = ' '.join(filter(None, (platform.system(), platform.machine(),
                                   platform.processor())))
  command = 'python -m experiments.same_channel' + (
      f' --shared_dir={FLAGS.shared_dir}' if FLAGS.shared_dir else '')
  text = ['# Same-channel diagnostic: colour anaglyphs against the gray anaglyph', '',
          f'Written by `{command}` on {machine} ({os.cpu_count()} CPU cores) in '
          f'{time.perf_counter() - start:.0f} s; the learned stages in {_precision()}. '
          f'Each pair window-aligned at '
          f'{FRACTION:.0%} (`realworld.window_align`), anaglyphs made by FFmpeg\'s stereo3d '
          '(imageio-ffmpeg); disparity range estimated from each image (as '
          '`--disparity_range=auto`). classical = `--method=classical`; learned = the '
          'learned matching stage, the default (`--pretrained=anaglyph_matching`: learned '
          'descriptors of both eyes, cosine costs, SGM; trained on warped photographs only, '
          'so every camera here is unseen); learned + its refiner = the refiner trained on '
          "the learned stage's results (`--pretrained=anaglyph_refined`, which runs on it; "
          'photograph textures, no stereo pair); learned + refiner = the classical '
          "method's refiner (`--pretrained=anaglyph`) on the learned stage instead of the "
          'classical method; refiner = that refiner on the classical result (a previous '
          'default); sgbm = '
          "`--method=sgbm`, OpenCV's StereoSGBM untuned (block 5, P1 = 200, P2 = 800, "
          "OpenCV's defaults otherwise) on the left eye's channel against the mean of the "
          "right eye's (`mixstereo_tf/classical/sgbm.py`). gray: both eyes carry "
          'luminance, so its matching is same-channel: the reference of the last column. '
          'bad-1 / bad-3: share of valid ground-truth pixels off by more than 1 / 3 px; '
          'EPE: mean absolute error, px. KITTI: the object frame, sparse ground truth '
          'from its Velodyne scan (no occlusion filtering); the KITTI 2015 frame of '
          '--shared_dir (`kitti2015_aanet_000151`) has none: views only, its window placed '
          "by the census matcher's consistent disparities of the pair's luma. true "
          'disparity (scenes with dense ground truth): the shipped restoration on the true '
          "left disparity and the right one forward-warped from it (the learned stage's "
          'where unknown): the views that perfect matching would give with this '
          f'restoration. procedural + noise {validation.NOISE_SIGMA:g}: the same scenes '
          f'with independent Gaussian noise (sigma {validation.NOISE_SIGMA:g} grey levels) '
          'on each view (`validation.noisy`): a rendered pair shows the same texture, '
          'noise and quantisation included, in both views, which census codes of flat '
          'regions match in a same-channel pairing only '
          '(experiments/results/channel_information.md).', '',
          *_table(rows), '']
  markdown.write(FLAGS.same_channel_output, text)


if __name__ == '__main__':
  app.run(main)
