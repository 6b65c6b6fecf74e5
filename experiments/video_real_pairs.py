r"""Camera pans cut from real stereo pairs: what the video prior, moved with the camera
(`video.motion`) or not, does to the views and disparities of real images.

    python -m experiments.video_real_pairs --shared_dir=../shared/stereo_samples

Scenes with ground truth, none a training source: Motorcycle (`realworld.scenes`, 741 x
500), and from --shared_dir the SceneFlow frame and the KITTI object frame (sparse lidar
truth). Each becomes a 24-frame red-cyan anaglyph video of crops (at most 1280 x 720)
panning 4 px a frame, Gaussian noise of 2 levels new every frame (seed 0), unmixed in order
through `frame_pipeline` as the video path runs them (`temporal.unmix_clip`;
`--mixture=anaglyph`), by the shipped default and by the classical method, per shot: with
the prior moved (the default), with the prior left in place, and without a prior
(`--notemporal_prior`). Scores: the views' RGB PSNR against the true crops (the 64
columns nearest the side a match can leave left out), bad-1 on the pixels with truth,
frames/s of the loop (2 cores, one run). Writes experiments/results/video_real_pairs.md.
"""

import os
import time

from absl import app
from absl import flags
import numpy as np

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.cli import flags as cli_flags
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import real_pairs
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.video import motion
from mixstereo_tf.video import temporal

from experiments import markdown
from experiments import temporal as clip_lib

cli_flags.define_shared_dir()
flags.DEFINE_string('video_real_pairs_output', 'experiments/results/video_real_pairs.md',
                    'Markdown report.')
FLAGS = flags.FLAGS
FRAMES, PAN, NOISE = 24, 4, 2.0
VARIANTS = (('moved prior (default)', temporal.TemporalConfig()),
            ('prior in place', temporal.TemporalConfig(
                motion=motion.MotionConfig(enabled=False))),
            ('no prior', temporal.TemporalConfig(use_prior=False)))


def _scenes():
  """(name, data) of Motorcycle and the --shared_dir frames."""
  for name, data in realworld.scenes(FLAGS.shared_dir):
    if name.startswith('motorcycle') or name == realworld.SCENEFLOW_FRAME:
      yield name, data
  folder = os.path.join(FLAGS.shared_dir or '', 'kitti_object_velodyne')
  if FLAGS.shared_dir and os.path.isdir(folder):
    yield 'kitti_object_velodyne', real_pairs.kitti_object_frame(folder)


def _clip(data, rng):
  """(anaglyph frames, [(left, right, disparity, valid)] of each crop)."""
  height, width = data['left'].shape[:2]
  crop_w, crop_h = min(1280, width - PAN * (FRAMES - 1)), min(720, height)
  valid = data.get('valid_left', data.get('nonocc_left'))
  frames, truths = [], []
  for index in range(FRAMES):
    where = np.s_[:crop_h, PAN * index:PAN * index + crop_w]
    left, right = data['left'][where], data['right'][where]
    mixed = mixtures.mix('anaglyph', image_range.u8_to_signed(left),
                         image_range.u8_to_signed(right))
    noisy = image_range.signed_to_u8(mixed.numpy()) + rng.normal(0, NOISE, left.shape)
    frames.append(np.clip(np.rint(noisy), 0, 255).astype(np.uint8))
    truths.append((left, right, data['disparity_left'][where], valid[where]))
  return frames, truths


def _psnr(view, truth, keep):
  error = view.astype(np.float64) - truth
  return 10 * np.log10(255.0 ** 2 / np.mean(error[keep] ** 2))


def _scores(unmixer, frames, truths, config):
  """(left PSNR, right PSNR, bad-1 %, frames/s) of the clip unmixed with `config`."""
  start = time.perf_counter()
  outputs, _ = clip_lib.unmix_clip(unmixer, frames, config)
  seconds = time.perf_counter() - start
  left = np.mean([_psnr(o['left'], t[0], np.s_[:, 64:]) for o, t in zip(outputs, truths)])
  right = np.mean([_psnr(o['right'], t[1], np.s_[:, :-64]) for o, t in zip(outputs, truths)])
  bad1 = np.mean([np.mean(np.abs(o['disparity_left'] - t[2])[t[3]] > 1)
                  for o, t in zip(outputs, truths)])
  return left, right, 100 * bad1, len(frames) / seconds


def main(argv):
  del argv
  rows = []
  for method in ('model', 'classical'):
    unmixer = predictors.build_unmixer(predictors.PredictorConfig(method=method,
                                                                  mixture='anaglyph'))
    for name, data in _scenes():
      frames, truths = _clip(data, np.random.default_rng(0))
      unmixer(frames[0])  # Compiles kernels, traces the model.
      for variant, config in VARIANTS:
        left, right, bad1, rate = _scores(unmixer, frames, truths, config)
        rows.append(f'| {name} ({frames[0].shape[1]}x{frames[0].shape[0]}) | {method} | '
                    f'{variant} | {left:.2f} | {right:.2f} | {bad1:.2f} | {rate:.2f} |')
  markdown.write(FLAGS.video_real_pairs_output, [
      '# Camera pans cut from real stereo pairs (`experiments/video_real_pairs.py`)', '',
      f'{FRAMES} frames a scene, panning {PAN} px a frame, red-cyan anaglyph with noise of '
      f'{NOISE:g} levels; `model` is the shipped default, per shot. Frames/s: one run on '
      'this machine (noisy).', '',
      '| scene | method | prior | left PSNR (dB) | right PSNR (dB) | bad-1 (%) | frames/s |',
      '| --- | --- | --- | ---: | ---: | ---: | ---: |', *rows])


if __name__ == '__main__':
  app.run(main)
