"""Video measurements of `benchmark.py` (section 16): flicker, accuracy and frames/s.

Quality (`video_quality`): the synthetic anaglyph clip of `experiments/temporal.py` (two
procedural scenes with ground truth, a panning camera, a cut, sensor noise; 320x180),
unmixed by one method per frame (--notemporal) and per shot with the previous frame's
disparity as the prior (the default): flicker (motion-compensated mean change between
consecutive frames on static pixels) of the left disparity (px) and of the restored left
view (levels), bad-1 and EPE on non-occluded pixels.

Speed (`video_speed`): the first shot of that clip upscaled (bicubic) to 1280x720 or
1920x1080 and written as an H.264 MP4, then unmixed by `unmix_files.unmix_inputs` exactly
as `mixstereo-unmix --input=clip.mp4 --layout=sbs` does (decoding, unmixing, encoding the
side-by-side and disparity videos, segments and manifest), after one warm-up frame
(numba's cache, tf.function tracing). Frames/s = frames / wall seconds of the whole call;
"unmix only" = frames / seconds the frame loop waited for the unmixer (since 2026-11-27 a
frame's views are restored beside the next frame's matching, which it does not count).
Methods: classical; model, the shipped
default (the learned matching stage, `--pretrained=anaglyph_matching`; with the temporal
prior only a shot's first frame is matched by it, the others around the prior); refiner,
the previous default (`--pretrained=anaglyph`; rows "model" before 2026-11-25).
"""

import fractions
import os
import shutil
import tempfile

import cv2

QUALITY_VARIANTS = (('per frame', False), ('per shot + prior', True))
SPEED_SIZES = ((1280, 720), (1920, 1080))
# Row label -> the predictor: the classical method, the shipped default (the learned
# matching stage, `--pretrained=anaglyph_matching`) and the previous default, the refiner.
METHODS = {'classical': dict(method='classical'), 'model': dict(method='model'),
           'refiner': dict(method='model', pretrained='anaglyph')}


def video_quality(method: str, frames_per_shot: int = 20) -> dict:
  """Flicker and accuracy of `method` on the clip, without and with the temporal state."""
  # pylint: disable=g-import-not-at-top (TensorFlow only in the worker processes)
  from experiments import temporal as clip_lib
  from mixstereo_tf.unmixing import predictors
  from mixstereo_tf.video import temporal
  clip = clip_lib.make_clip(frames_per_shot)
  frames = [c[0] for c in clip]
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(mixture='auto',
                                                                **METHODS[method]))
  clip_lib.unmix_clip(unmixer, frames[:2], temporal.TemporalConfig())  # Compiles kernels.
  result = {}
  for name, enabled in QUALITY_VARIANTS:
    outputs, _ = clip_lib.unmix_clip(unmixer, frames, temporal.TemporalConfig(enabled=enabled))
    flicker_d, flicker_v = clip_lib.flicker(clip, outputs)
    bad1, epe, _ = clip_lib.accuracy(clip, outputs)
    result[name] = {'flicker_px': flicker_d, 'flicker_levels': flicker_v, 'bad1': bad1,
                    'epe': epe}
  return result


def _write_clip(path: str, size, frames: int, bits: int = 8,
                mixture: str = 'anaglyph') -> None:
  """The clip (encoded as `mixture`) upscaled to `size`; `bits` 10: as 10-bit H.264 (High
  10, through PyAV itself: an earlier tree's writer takes 8-bit frames only), its frames
  upscaled from 16-bit copies."""
  # pylint: disable=g-import-not-at-top
  import av
  import numpy as np
  from experiments import temporal as clip_lib
  from mixstereo_tf.video import streams
  clip = [image for image, *_ in clip_lib.make_clip(frames, mixture)[:frames]]
  if bits == 8:
    with streams.VideoWriter(path, fractions.Fraction(25)) as writer:
      for index, image in enumerate(clip):
        writer.write(cv2.resize(image, size, interpolation=cv2.INTER_CUBIC),
                     fractions.Fraction(index, 25))
    return
  with av.open(path, 'w') as out:
    stream = out.add_stream('libx264', rate=25, options={'crf': '18', 'preset': 'veryfast'})
    stream.width, stream.height, stream.pix_fmt = *size, 'yuv420p10le'
    stream.codec_context.colorspace, stream.codec_context.color_range = 1, 1  # As made.
    for index, image in enumerate(clip):
      deep = cv2.resize(image.astype(np.uint16) * 257, size, interpolation=cv2.INTER_CUBIC)
      frame = av.VideoFrame.from_ndarray(deep, format='rgb48le').reformat(
          format='yuv420p10le', dst_colorspace=1, dst_color_range=1)
      frame.pts = index
      out.mux(stream.encode(frame))
    out.mux(stream.encode(None))


def _left_psnr(path: str, size, frames: int) -> float:
  """Mean RGB PSNR (dB, 8-bit scale) of the left views of side-by-side video `path`
  against the clip's clean left views upscaled as its frames were, the left 64 columns
  left out (matches there leave the frame); decoded by PyAV at 16 bits, whatever the
  package does."""
  # pylint: disable=g-import-not-at-top
  import av
  import numpy as np
  from experiments import temporal as clip_lib
  truths = [cv2.resize(left, size, interpolation=cv2.INTER_CUBIC).astype(np.float64)
            for _, _, _, left, *_ in clip_lib.make_clip(frames)[:frames]]
  psnr = []
  with av.open(path) as video:
    for truth, frame in zip(truths, video.decode(video=0)):
      view = frame.to_ndarray(format='rgb48le')[:, :size[0]] / 257.0
      psnr.append(10 * np.log10(255.0 ** 2 / np.mean((view - truth)[:, 64:] ** 2)))
  return float(np.mean(psnr))


def video_speed(method: str, width: int, height: int, frames: int = 12,
                bits: int = 8, mixture: str = 'anaglyph', keep_bits: bool = True) -> dict:
  """Frames/s of `unmix_inputs` on a `frames`-frame clip (`bits` per sample, encoded as
  `mixture`: the colour anaglyph detected by --mixture=auto, another encoding named),
  without and with the prior, and its left views' PSNR (`_left_psnr`); `keep_bits`:
  `jobs.VideoConfig.keep_bits` (False: --nokeep_video_bits)."""
  # pylint: disable=g-import-not-at-top
  from mixstereo_tf.unmixing import predictors
  from mixstereo_tf.video import temporal
  from mixstereo_tf.cli import media
  from mixstereo_tf.cli import unmix_files
  from mixstereo_tf.video import jobs
  from mixstereo_tf.video import streams
  root = tempfile.mkdtemp()
  try:
    path = os.path.join(root, 'clip.mp4')
    _write_clip(path, (width, height), frames, bits, mixture)
    named = 'auto' if mixture == 'anaglyph' else mixture
    unmixer = predictors.build_unmixer(predictors.PredictorConfig(mixture=named,
                                                                  **METHODS[method]))
    _, decoded = streams.open_video(path)
    unmixer(next(iter(decoded)).image)  # Warm-up: numba's cache, tracing.
    decoded.close()
    import mixstereo_tf  # pylint: disable=g-import-not-at-top
    result = {'frames': frames, 'package': os.path.dirname(mixstereo_tf.__file__)}
    for name, enabled in QUALITY_VARIANTS:
      output_dir = os.path.join(root, name.replace(' ', '_'))
      report = unmix_files.unmix_inputs(unmixer, path, output_dir, media.OutputOptions(
          layout='sbs', temporal_config=temporal.TemporalConfig(enabled=enabled),
          video_config=jobs.VideoConfig(keep_bits=keep_bits)))
      if report.failures or report.frames != frames:
        raise RuntimeError(f'unmix_inputs: {report}')
      result[name] = {'fps': report.frames_per_second,
                      'unmix_fps': frames / report.unmix_seconds,
                      'seconds': report.seconds,
                      'left_psnr': _left_psnr(os.path.join(output_dir, 'clip_sbs.mp4'),
                                              (width, height), frames)}
    return result
  finally:
    shutil.rmtree(root, ignore_errors=True)


def collect(run_worker, timeout: int) -> dict:
  """The section's results, one worker process per measurement."""
  results = {}
  for method in METHODS:
    results[f'video/quality/{method}'] = run_worker('video_quality', timeout, method=method)
    for width, height in SPEED_SIZES:
      results[f'video/speed/{method}/{width}x{height}'] = run_worker(
          'video_speed', timeout, method=method, width=width, height=height)
  return results


def _cell(run: dict, key: str, variant: str, field: str, fmt: str) -> str:
  """One number of run['results'][key][variant], or why there is none."""
  result = run['results'].get(key)
  if result is None:
    return 'not run'
  if 'error' in result:
    return f'FAILED: {result["error"]}'
  return format(result[variant][field], fmt)


def render_section(run: dict, baseline, baseline_label: str, label: str) -> list:
  """Section 16 of BENCHMARKS.md; `baseline` (or None) gives the 'before' columns."""
  runs = [(baseline_label, baseline)] if baseline else []
  runs.append((label, run))
  lines = ['', '## 16. Video: flicker, accuracy and frames/s (`benchmark_video.py`)', '',
           __doc__.split('\n\n', 1)[1].strip(), '']
  quality = (('flicker_px', '.3f', 'disparity flicker px'),
             ('flicker_levels', '.2f', 'view flicker'), ('bad1', '.2f', 'bad-1 %'),
             ('epe', '.3f', 'EPE px'))
  lines += ['| method, variant | ' + ' | '.join(f'{title} ({name})' for *_, title in quality
                                               for name, _ in runs) + ' |',
            '|---|' + '---:|' * (len(quality) * len(runs))]
  for method in METHODS:
    for variant, _ in QUALITY_VARIANTS:
      cells = [_cell(r, f'video/quality/{method}', variant, field, fmt)
               for field, fmt, _ in quality for _, r in runs]
      lines.append(f'| {method}, {variant} | ' + ' | '.join(cells) + ' |')
  lines += ['', '| method, variant, size | ' + ' | '.join(
      f'frames/s ({name}) | unmix only ({name})' for name, _ in runs) + ' |',
            '|---|' + '---:|' * (2 * len(runs))]
  for method in METHODS:
    for variant, _ in QUALITY_VARIANTS:
      for width, height in SPEED_SIZES:
        key = f'video/speed/{method}/{width}x{height}'
        cells = [_cell(r, key, variant, field, '.2f') for _, r in runs
                 for field in ('fps', 'unmix_fps')]
        lines.append(f'| {method}, {variant}, {width}x{height} | ' + ' | '.join(cells) + ' |')
  return lines


WORKERS = {'video_quality': video_quality, 'video_speed': video_speed}
