"""Unmixing files: every image and video of an input specification, results to a folder.

Outputs per input `<name>` in the output folder, where `<name>` is the file stem, or stem
+ '_' + extension when inputs share a stem (`media.output_names`): the views
(`<name>_left.png` and `<name>_right.png` for the 'separate' layout, else
`<name>_<layout>.png`), the colour-mapped left disparity `<name>_disparity.png` (over the
range found, or a fixed one), KITTI-style `<name>_disparity16.png` (uint16, d * 256; only
when every disparity lies in 0..255.996 px) and float32 signed pixels
`<name>_disparity.npy`, and a side-car `<name>_info.json` (mixture used and detected,
range searched, scale, method, seconds; `write_info`). Per video: the layout as `<name>_<layout>.mp4` (or `_left` /
`_right`) and `<name>_disparity.mp4`. Progress (`progress.ProgressBar`) is shown for several
inputs and for every video's frames.
"""

import dataclasses
import json
import os
import time
from typing import Dict, List, Optional, TextIO, Tuple

from absl import logging
import cv2
import tensorflow as tf

from mixstereo_tf import colormap
from mixstereo_tf import inference
from mixstereo_tf import media
from mixstereo_tf import progress


@dataclasses.dataclass
class UnmixReport:
  """What `unmix_inputs` did: counts, failures as (path, reason), timings in seconds."""
  processed: int = 0
  frames: int = 0
  failures: List[Tuple[str, str]] = dataclasses.field(default_factory=list)
  seconds: float = 0.0
  unmix_seconds: float = 0.0

  @property
  def frames_per_second(self) -> float:
    """Frames over the whole run, reading and writing included."""
    return self.frames / self.seconds if self.seconds > 0 else 0.0


def failure_message(report: UnmixReport) -> Optional[str]:
  """The error that ends the run with a non-zero status: any input failed."""
  if not report.failures:
    return None
  paths = ', '.join(path for path, _ in report.failures[:5])
  more = ', ...' if len(report.failures) > 5 else ''
  return (f'error: {len(report.failures)} of {report.processed + len(report.failures)} '
          f'input(s) failed: {paths}{more}')


def _reason(error: Exception) -> str:
  """A one-line reason for a failed input (TensorFlow messages can span many lines)."""
  message = error.message if isinstance(error, tf.errors.OpError) else str(error)
  lines = message.strip().splitlines()
  return f'{type(error).__name__}: {lines[0] if lines else ""}'


# What one input may raise without stopping the others: unreadable or malformed files
# (ValueError, cv2.error), failures inside TensorFlow (e.g. an image too large for memory)
# and file-system errors while reading or writing.
_INPUT_ERRORS = (ValueError, cv2.error, tf.errors.OpError, OSError)


def _unmix_video(unmixer: inference.Unmixer, item: media.MediaItem, output_dir: str, layout: str,
                 max_disparity: float, report: UnmixReport,
                 progress_stream: Optional[TextIO]) -> int:
  """Unmixes every frame of a video into layout and disparity videos; returns frames."""
  fps, total, frames = media.video_frames(item.path)
  suffixes = ['left', 'right'] if layout == 'separate' else [layout]
  writers = {s: media.VideoWriter(os.path.join(output_dir, f'{item.name}_{s}.mp4'), fps)
             for s in suffixes + ['disparity']}
  bar = progress.ProgressBar(total, os.path.basename(item.path), progress_stream)
  count = 0
  try:
    for frame in frames:
      start = time.perf_counter()
      outputs = unmixer(frame)
      report.unmix_seconds += time.perf_counter() - start
      for suffix, image in media.layout_images(outputs['left'], outputs['right'], layout):
        writers[suffix].write(image)
      writers['disparity'].write(colormap.colorize(outputs['disparity_left'], max_disparity))
      count += 1
      bar.update(count)
    bar.update(count, force=True)  # The container's frame count may be wrong or missing.
  finally:
    bar.close()
    for writer in writers.values():
      writer.close()
  return count


def write_info(output_dir: str, item: media.MediaItem, info: Dict[str, object]) -> str:
  """Writes `<name>_info.json` beside an input's results: what was done (the mixture used
  and detected, with its confidence, the disparity range searched, the network's shift and
  scale, the method, the seconds spent) and the files written."""
  path = os.path.join(output_dir, f'{item.name}_info.json')
  with open(path, 'w', encoding='utf-8') as f:
    json.dump(dict(info, input=item.path), f, indent=2, sort_keys=True)
  return path


def unmix_inputs(unmixer: inference.Unmixer, input_spec: str, output_dir: str,
                 layout: str = 'separate', max_display_disparity: Optional[float] = None,
                 progress_stream: Optional[TextIO] = None) -> UnmixReport:
  """Unmixes every image / video of `input_spec` (see `media.iter_inputs`).

  An input that cannot be read, unmixed or written is logged with its path and the reason,
  recorded in `UnmixReport.failures` and skipped; the others still run.

  `max_display_disparity` fixes the colour maps to 0..that many pixels; by default each
  image's map spans the disparities found (videos: the unmixer's range). Each image also
  gets `<name>_info.json` (`write_info`).
  Progress (`ProgressBar`) is drawn on `progress_stream` when it is a terminal (the CLI
  passes stderr), else logged.

  Raises:
    ValueError: bad layout / display range, or `input_spec` names nothing usable.
  """
  if layout not in media.LAYOUTS:
    raise ValueError(f'Unknown layout {layout!r}; valid: {", ".join(media.LAYOUTS)}.')
  if max_display_disparity is not None and not max_display_disparity > 0:
    raise ValueError(f'max_display_disparity must be positive, got {max_display_disparity}.')
  max_disparity = max_display_disparity or unmixer.max_disparity
  items = list(media.iter_inputs(input_spec))
  os.makedirs(output_dir, exist_ok=True)
  report = UnmixReport()
  run_start = time.perf_counter()
  bar = progress.ProgressBar(len(items), stream=progress_stream) if len(items) > 1 else None
  for index, item in enumerate(items, 1):
    try:
      if item.is_video:
        if bar:
          bar.clear()  # The video draws its own frame progress.
        frames = _unmix_video(unmixer, item, output_dir, layout, max_disparity, report,
                              progress_stream)
      else:
        image = media.read_image(item.path)
        unmix_start = time.perf_counter()
        outputs = unmixer(image)
        report.unmix_seconds += time.perf_counter() - unmix_start
        written = media.write_image_outputs(outputs, output_dir, item.name, layout,
                                            max_display_disparity)
        write_info(output_dir, item, dict(outputs.get('info', {}), **written))
        frames = 1
    except _INPUT_ERRORS as e:
      if bar:
        bar.clear()
      logging.error('[%d/%d] skipped %s: %s', index, len(items), item.path, _reason(e))
      report.failures.append((item.path, _reason(e)))
    else:
      report.processed += 1
      report.frames += frames
    if bar:
      bar.update(index, report.frames)
  if bar:
    bar.close()
  report.seconds = time.perf_counter() - run_start
  return report
