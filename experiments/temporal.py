r"""Temporal consistency of video unmixing, measured on a synthetic anaglyph clip with
ground truth (issue 16): flicker, accuracy and speed with and without the per-shot state.

    PYTHONPATH=. python experiments/temporal.py [--frames_per_shot=20] [--speed_frames=3]
    PYTHONPATH=. python experiments/temporal.py --temporal_mixture=diplopia \
        --temporal_output=experiments/results/temporal_diplopia.md

The clip: two procedural scenes of `data/synthetic.py` (held-out textures), each seen by a
camera panning right (2 px per frame over scene A, 1 px over scene B, integer shifts so the
ground truth moves exactly), with a cut between them; each frame is a red-cyan anaglyph with
Gaussian noise (sigma 2 levels, new every frame, as a camera's). Every variant unmixes the
frames in order with `--mixture=auto`, by the classical method and by the shipped default
model (`mixstereo_tf/artifacts/pretrained`: since 2026-11-25 the learned matching stage,
which matches a shot's first frame and leaves the others to the census matcher around the
prior; per frame and per shot + prior only):
  * per frame: today's behaviour (encoding, range and disparity of each frame alone);
  * per shot: encoding and range once per shot (`temporal.VideoState`), no prior;
  * per shot + prior: also the previous frame's disparity as the matcher's prior (moved
    with the camera's pan since 2026-11-29, `video.motion`), with `TemporalConfig`'s narrow
    window and with the still-image window (MatcherConfig's).
Flicker: mean absolute change between consecutive frames of a shot, motion-compensated
(the known pan), of the left disparity (px) and of the restored left view (levels 0..255),
on pixels whose ground-truth disparity and clean colour do not change and whose match lies
inside both frames. Accuracy: bad-1 (%) and EPE (px) against the ground truth on the
non-occluded pixels of every frame. Speed: frames/s of the unmixer alone on the first
`--speed_frames` frames of scene A upscaled (bicubic) to 1280x720 and 1920x1080.
Writes experiments/results/temporal.md. With --temporal_mixture=diplopia the same clip is
mixed as double images I = (L + R) / 2 and unmixed with `--mixture=diplopia` (the double
images' prior: `diplopia_costs.add_prior`, a penalty on lags outside the window around the
previous frame's disparity).
"""

import os
import time

from absl import app
from absl import flags
import cv2
import numpy as np

from mixstereo_tf.cli import video_files
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import synthetic
from mixstereo_tf.data import texture_atlas
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.video import frame_pipeline
from mixstereo_tf.video import temporal

FLAGS = flags.FLAGS
flags.DEFINE_integer('frames_per_shot', 20, 'Frames of each of the two shots.')
flags.DEFINE_integer('speed_frames', 3, 'Frames timed at each large size.')
flags.DEFINE_enum('temporal_mixture', 'anaglyph', ['anaglyph', 'diplopia'],
                  'How the clip is mixed (and named to the unmixer: auto for anaglyphs).')
flags.DEFINE_string('temporal_output', os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                           'results', 'temporal.md'), 'Report path.')

HEIGHT, WIDTH, MAX_DISPARITY, NOISE = 180, 320, 32, 2.0
SHOTS = ((101, 2), (202, 1))  # (scene seed, pan px per frame).
VARIANTS = (
    ('per frame (--notemporal)', temporal.TemporalConfig(enabled=False)),
    ('per shot, no prior (--notemporal_prior)', temporal.TemporalConfig(use_prior=False)),
    ('per shot + prior (radius 1, spread 2; default)', temporal.TemporalConfig()),
    ('per shot + prior (radius 4, spread 4)',
     temporal.TemporalConfig(prior_radius=4, prior_spread=4)),
)
TIMED = (0, 1, 2)  # The variants timed at SIZES: per frame, per shot without and with prior.
METHODS = ('classical', 'model')  # The model runs the TIMED variants only.
SIZES = ((1280, 720), (1920, 1080))


def make_clip(frames_per_shot: int, mixture_name: str = 'anaglyph'):
  """[(mixture u8, gt disparity, nonocc, clean left, shot, pan)] of the two shots."""
  clip, rng = [], np.random.RandomState(0)
  for shot, (seed, pan) in enumerate(SHOTS):
    config = synthetic.SceneConfig(max_disparity=MAX_DISPARITY, height=HEIGHT,
                                   width=WIDTH + pan * (frames_per_shot - 1))
    scene = synthetic.render_scene(seed, config, texture_atlas.load_textures('heldout'))
    mixed = mixtures.mix(mixture_name, image_range.u8_to_signed(scene['left']),
                         image_range.u8_to_signed(scene['right']))
    mixture = image_range.signed_to_u8(mixed.numpy()).astype(np.float32)
    columns = np.arange(WIDTH, dtype=np.float32)
    for index in range(frames_per_shot):
      window = slice(pan * index, pan * index + WIDTH)
      noisy = mixture[:, window] + rng.normal(0.0, NOISE, (HEIGHT, WIDTH, 3))
      gt = scene['disparity_left'][:, window]
      inside = (columns - gt >= 0)  # The match lies inside this frame.
      clip.append((np.clip(np.round(noisy), 0, 255).astype(np.uint8), gt,
                   scene['nonocc_left'][:, window] & inside, scene['left'][:, window],
                   shot, pan))
  return clip


def unmix_clip(unmixer, frames, config):
  """Outputs of every frame, in order, with the per-shot state of `config`, as the video
  loop runs them (`frame_pipeline`: a frame's prior is what the one before reported; each
  frame's hint has a video frame's fields, `video_files.frame_fields`)."""
  state = temporal.VideoState(config)
  fields = video_files.frame_fields(chroma_halved=False, config=config)
  with frame_pipeline.FramePipeline(unmixer, state) as pipeline:
    pending = [pipeline.submit(frame, **fields) for frame in frames]
  return [p.result() for p in pending], state


def flicker(clip, outputs):
  """(disparity px, left view levels): motion-compensated mean change within shots."""
  changes_d, changes_v = [], []
  for t in range(1, len(clip)):
    _, gt, nonocc, clean, shot, pan = clip[t]
    _, gt0, nonocc0, clean0, shot0, _ = clip[t - 1]
    if shot != shot0:
      continue
    # Pixel x of frame t shows what pixel x + pan of frame t - 1 showed.
    now, before = np.s_[:, :WIDTH - pan], np.s_[:, pan:]
    static = ((gt[now] == gt0[before]) & (clean[now] == clean0[before]).all(-1) &
              nonocc[now] & nonocc0[before])
    d_now = outputs[t]['disparity_left'][now]
    d_before = outputs[t - 1]['disparity_left'][before]
    v_now = outputs[t]['left'][now].astype(np.float32)
    v_before = outputs[t - 1]['left'][before].astype(np.float32)
    changes_d.append(np.abs(d_now - d_before)[static])
    changes_v.append(np.abs(v_now - v_before).mean(-1)[static])
  return float(np.concatenate(changes_d).mean()), float(np.concatenate(changes_v).mean())


def accuracy(clip, outputs):
  """(bad-1 %, EPE px) over the non-occluded pixels of every frame, and the left view's
  RGB PSNR against the clean left view (dB, the frames' mean)."""
  errors = np.concatenate([np.abs(out['disparity_left'] - gt)[nonocc]
                           for (_, gt, nonocc, *_), out in zip(clip, outputs)])
  psnr = np.mean([metrics.psnr(out['left'], clean)
                  for (_, _, _, clean, *_), out in zip(clip, outputs)])
  return 100.0 * float(np.mean(errors > 1.0)), float(errors.mean()), float(psnr)


def speed(unmixer, frames, config, size):
  """Frames/s of the unmixer on `frames` upscaled to `size`."""
  large = [cv2.resize(f, size, interpolation=cv2.INTER_CUBIC) for f in frames]
  start = time.perf_counter()
  unmix_clip(unmixer, large, config)
  return len(large) / (time.perf_counter() - start)


def main(argv):
  del argv
  start = time.perf_counter()
  clip = make_clip(FLAGS.frames_per_shot, FLAGS.temporal_mixture)
  named = 'auto' if FLAGS.temporal_mixture == 'anaglyph' else FLAGS.temporal_mixture
  frames = [c[0] for c in clip]
  planted = FLAGS.frames_per_shot
  rows = []
  for method in METHODS:
    unmixer = predictors.build_unmixer(predictors.PredictorConfig(method, mixture=named))
    unmix_clip(unmixer, frames[:2], temporal.TemporalConfig())  # Compiles the kernels.
    for timed, (name, config) in enumerate(VARIANTS):
      if method == 'model' and timed not in TIMED:
        continue
      outputs, state = unmix_clip(unmixer, frames, config)
      detected = sorted({o['info']['mixture'] for o in outputs})
      row = [f'{method}: {name}', *flicker(clip, outputs), *accuracy(clip, outputs)]
      for size in SIZES:
        row.append(speed(unmixer, frames[:FLAGS.speed_frames], config, size)
                   if timed in TIMED else float('nan'))
      rows.append(row)
      print(row, 'encodings', detected, 'shot starts', state.shot_starts, flush=True)
  cuts = temporal.find_cuts(frames)
  lines = [
      f'# Temporal consistency (synthetic {FLAGS.temporal_mixture} clip)', '',
      f'`PYTHONPATH=. python experiments/temporal.py --frames_per_shot={FLAGS.frames_per_shot}'
      f' --speed_frames={FLAGS.speed_frames}'
      + ('' if named == 'auto' else f' --temporal_mixture={FLAGS.temporal_mixture}') +
      f'`; classical method and shipped model, `--mixture={named}`. Two '
      f'procedural scenes (held-out textures), {WIDTH}x{HEIGHT}, disparities up to '
      f'{synthetic.SceneConfig(MAX_DISPARITY).near_limit:.1f} px, '
      f'{FLAGS.frames_per_shot} frames each (camera '
      f'panning {SHOTS[0][1]} px/frame, then {SHOTS[1][1]} px/frame), a cut at frame '
      f'{planted}; Gaussian noise sigma {NOISE:g} levels per frame. Scene cuts found: '
      f'{cuts} (planted: [{planted}]).', '',
      'Flicker: motion-compensated mean absolute change between consecutive frames of a shot '
      'on pixels whose ground-truth disparity and colour do not change (disparity in px, '
      'restored left view in levels 0..255). bad-1 / EPE: non-occluded pixels, all frames; '
      'left PSNR: the restored left view against the clean one, RGB, mean over frames. '
      f'Frames/s: the unmixer alone on the first {FLAGS.speed_frames} frames upscaled '
      '(bicubic; the pan becomes 8 / 12 px per frame), kernels compiled beforehand, 2 '
      'shared CPU cores (noisy; `nan`: not timed).', '',
      '| variant | disparity flicker (px) | left-view flicker | bad-1 (%) | EPE (px) | '
      'left PSNR (dB) | fps 1280x720 | fps 1920x1080 |',
      '| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |']
  for name, f_d, f_v, bad, epe, psnr, fps_720, fps_1080 in rows:
    lines.append(f'| {name} | {f_d:.3f} | {f_v:.2f} | {bad:.2f} | {epe:.3f} | {psnr:.2f} | '
                 f'{fps_720:.2f} | {fps_1080:.2f} |')
  lines += ['', f'Total run time {time.perf_counter() - start:.0f} s.', '']
  os.makedirs(os.path.dirname(FLAGS.temporal_output), exist_ok=True)
  with open(FLAGS.temporal_output, 'w', encoding='utf-8') as f:
    f.write('\n'.join(lines))
  print('\n'.join(lines))


if __name__ == '__main__':
  app.run(main)
