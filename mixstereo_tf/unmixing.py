"""The unmix tool's logic: choose an unmixer, run it over images and videos, write results.

Outputs per input `<name>` in the output folder, where `<name>` is the file stem, or stem
+ '_' + extension when inputs share a stem (`media.output_names`): the views
(`<name>_left.png` and `<name>_right.png` for the 'separate' layout, else
`<name>_<layout>.png`), the colour-mapped left disparity `<name>_disparity.png` (one fixed
range per run), KITTI-style `<name>_disparity16.png` (uint16, d * 256) and float32 pixels
`<name>_disparity.npy`. Per video: the layout as `<name>_<layout>.mp4` (or `_left` /
`_right`) and `<name>_disparity.mp4`. Progress (`ProgressBar`) is shown for several inputs
and for every video's frames.
"""

import dataclasses
import os
import time
from typing import Callable, Dict, List, Optional, TextIO, Tuple

from absl import logging
import cv2
import numpy as np
import tensorflow as tf

from mixstereo_tf import baselines
from mixstereo_tf import inference
from mixstereo_tf import media
from mixstereo_tf import mixtures
from mixstereo_tf.baselines import sgm

METHODS = ('model', 'classical')
UnmixFn = Callable[[np.ndarray], Dict[str, np.ndarray]]


@dataclasses.dataclass(frozen=True)
class Unmixing:
  """A ready unmixer: fn(uint8 [H, W, 3]) -> {'left', 'right', 'disparity_left', ...}."""
  fn: UnmixFn
  mixture: str
  default_max_disparity: float


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


def _duration(seconds: float) -> str:
  minutes, seconds = divmod(int(round(seconds)), 60)
  return f'{minutes} min {seconds:02d} s' if minutes else f'{seconds} s'


def format_progress(done: int, total: Optional[int], seconds: float,
                    frames: Optional[int] = None, label: str = '', bar_width: int = 10) -> str:
  """One progress line, e.g. '[###.......] 3/10  1.2 frames/s  ETA 6 s'.

  Args:
    done: items (inputs or video frames) finished.
    total: items in all; None when unknown (a video without a frame count): the line then
      has neither bar nor ETA ('37 done  1.2 frames/s').
    seconds: wall time since the start.
    frames: frames produced so far (default `done`); frames/s is frames / seconds.
    label: optional prefix, e.g. the video's file name.
    bar_width: characters between the brackets.
  """
  frames = done if frames is None else frames
  parts = [label] if label else []
  if total:
    filled = bar_width * min(done, total) // total
    parts.append(f'[{"#" * filled}{"." * (bar_width - filled)}] {done}/{total}')
  else:
    parts.append(f'{done} done')
  parts.append(f'{frames / seconds if seconds > 0 else 0.0:.1f} frames/s')
  if total:
    # The ETA extrapolates the time per finished item; unknown before the first one.
    left = max(total - done, 0) * seconds / done if done else None
    parts.append('ETA ' + ('?' if left is None else _duration(left)))
  return '  '.join(parts)


class ProgressBar:
  """Shows `format_progress` lines: redrawn in place on a terminal, logged otherwise.

  On a `stream` that is a TTY the line is rewritten after a carriage return at most every
  `redraw_seconds`; otherwise (a pipe, a file, no stream) it goes to the INFO log at most
  every `log_seconds`, so logs stay short. The first update and the last one (done >=
  total, or `force`) are always shown; a count already shown is not repeated.
  """

  def __init__(self, total: Optional[int], label: str = '', stream: Optional[TextIO] = None,
               clock: Callable[[], float] = time.perf_counter, redraw_seconds: float = 0.2,
               log_seconds: float = 10.0):
    self.total, self.label = total, label
    self._stream = stream if stream is not None and stream.isatty() else None
    self._clock = clock
    self._start = clock()
    self._interval = redraw_seconds if self._stream else log_seconds
    self._shown_at = self._shown_done = None
    self._drawn = 0  # Characters of the line currently on the terminal.

  def update(self, done: int, frames: Optional[int] = None, force: bool = False) -> None:
    """Shows the progress after `done` items (and `frames` frames) unless shown recently."""
    now = self._clock()
    last = force or (self.total is not None and done >= self.total)
    if done == self._shown_done or (
        self._shown_at is not None and not last and now - self._shown_at < self._interval):
      return
    self._shown_at, self._shown_done = now, done
    line = format_progress(done, self.total, now - self._start, frames, self.label)
    if self._stream is None:
      logging.info('%s', line)
      return
    # Spaces overwrite the end of a longer previous line.
    self._stream.write('\r' + line.ljust(self._drawn))
    self._stream.flush()
    self._drawn = len(line)

  def clear(self) -> None:
    """Erases the terminal line before other output; the next update redraws it."""
    if self._drawn:
      self._stream.write('\r' + ' ' * self._drawn + '\r')
      self._stream.flush()
      self._drawn, self._shown_at, self._shown_done = 0, None, None

  def close(self) -> None:
    """Ends the terminal line, leaving the last progress on screen."""
    if self._drawn:
      self._stream.write('\n')
      self._stream.flush()
      self._drawn = 0


def _classical(mixture: str) -> Unmixing:
  """The training-free baseline; its display range is its disparity search range."""
  if mixture not in baselines.SUPPORTED_MIXTURES:
    raise ValueError(f'--method=classical does not support --mixture={mixture}; '
                     f'supported: {", ".join(baselines.SUPPORTED_MIXTURES)}.')
  return Unmixing(lambda image: baselines.unmix_classical(image, mixture), mixture,
                  sgm.SgmConfig().max_disparity)


def make_unmixing(method: str = 'model', saved_model: Optional[str] = None,
                  checkpoint: Optional[str] = None, mixture: Optional[str] = None,
                  restore_colour: Optional[bool] = None) -> Unmixing:
  """Builds the unmixer the flags ask for.

  Args:
    method: 'model' (a trained network) or 'classical' (training-free baseline).
    saved_model: export directory (method 'model'; exactly one of this and `checkpoint`).
    checkpoint: run directory or checkpoint prefix (method 'model').
    mixture: the input's mixture operator; must equal the model's recorded one (default:
      the recorded one); required for 'classical'.
    restore_colour: paper section 4.2 colour restoration (default: channel anaglyphs).

  Raises:
    ValueError: inconsistent arguments, named as flags.
  """
  if mixture is not None:
    mixtures.get_mixture(mixture)  # ValueError listing the valid names.
  if method == 'classical':
    if saved_model or checkpoint:
      raise ValueError('--method=classical takes neither --saved_model nor --checkpoint.')
    if mixture is None:
      raise ValueError('--method=classical needs --mixture.')
    return _classical(mixture)
  if method != 'model':
    raise ValueError(f'Unknown --method={method!r}; valid: {", ".join(METHODS)}.')
  if bool(saved_model) == bool(checkpoint):
    raise ValueError('Give exactly one of --saved_model and --checkpoint.')

  def check_mixture(run_info):
    if mixture is not None and mixture != run_info.mixture:
      raise ValueError(f'--mixture={mixture} but the model was trained on '
                       f'{run_info.mixture!r} mixtures ({saved_model or checkpoint}).')

  if saved_model:
    unmixer = inference.Unmixer.from_saved_model(saved_model, restore_colour)
    check_mixture(unmixer.run_info)
  else:
    # The recorded mixture is checked before the model is built.
    model_dir, _ = inference.resolve_checkpoint(checkpoint)
    check_mixture(inference.read_run_info(os.path.join(model_dir, inference.CONFIG_FILE)))
    unmixer = inference.Unmixer.from_model(*inference.load_run(checkpoint), restore_colour)
  return Unmixing(unmixer, unmixer.run_info.mixture,
                  unmixer.run_info.model_config.max_disparity)


def _reason(error: Exception) -> str:
  """A one-line reason for a failed input (TensorFlow messages can span many lines)."""
  message = error.message if isinstance(error, tf.errors.OpError) else str(error)
  lines = message.strip().splitlines()
  return f'{type(error).__name__}: {lines[0] if lines else ""}'


# What one input may raise without stopping the others: unreadable or malformed files
# (ValueError, cv2.error), failures inside TensorFlow (e.g. an image too large for memory)
# and file-system errors while reading or writing.
_INPUT_ERRORS = (ValueError, cv2.error, tf.errors.OpError, OSError)


def _unmix_video(fn: UnmixFn, item: media.MediaItem, output_dir: str, layout: str,
                 max_disparity: float, report: UnmixReport,
                 progress_stream: Optional[TextIO]) -> int:
  """Unmixes every frame of a video into layout and disparity videos; returns frames."""
  fps, total, frames = media.video_frames(item.path)
  suffixes = ['left', 'right'] if layout == 'separate' else [layout]
  writers = {s: media.VideoWriter(os.path.join(output_dir, f'{item.name}_{s}.mp4'), fps)
             for s in suffixes + ['disparity']}
  bar = ProgressBar(total, os.path.basename(item.path), progress_stream)
  count = 0
  try:
    for frame in frames:
      start = time.perf_counter()
      outputs = fn(frame)
      report.unmix_seconds += time.perf_counter() - start
      for suffix, image in media.layout_images(outputs['left'], outputs['right'], layout):
        writers[suffix].write(image)
      writers['disparity'].write(
          media.colorize_disparity(outputs['disparity_left'], max_disparity))
      count += 1
      bar.update(count)
    bar.update(count, force=True)  # The container's frame count may be wrong or missing.
  finally:
    bar.close()
    for writer in writers.values():
      writer.close()
  return count


def unmix_inputs(unmixing: Unmixing, input_spec: str, output_dir: str,
                 layout: str = 'separate', max_display_disparity: Optional[float] = None,
                 progress_stream: Optional[TextIO] = None) -> UnmixReport:
  """Unmixes every image / video of `input_spec` (see `media.iter_inputs`).

  An input that cannot be read, unmixed or written is logged with its path and the reason,
  recorded in `UnmixReport.failures` and skipped; the others still run.

  `max_display_disparity` (pixels shown brightest) defaults to the unmixer's range.
  Progress (`ProgressBar`) is drawn on `progress_stream` when it is a terminal (the CLI
  passes stderr), else logged.

  Raises:
    ValueError: bad layout / display range, or `input_spec` names nothing usable.
  """
  if layout not in media.LAYOUTS:
    raise ValueError(f'Unknown --layout={layout!r}; valid: {", ".join(media.LAYOUTS)}.')
  max_disparity = max_display_disparity or unmixing.default_max_disparity
  if not max_disparity > 0:
    raise ValueError(f'--max_display_disparity must be positive, got {max_disparity}.')
  items = list(media.iter_inputs(input_spec))
  os.makedirs(output_dir, exist_ok=True)
  report = UnmixReport()
  run_start = time.perf_counter()
  bar = ProgressBar(len(items), stream=progress_stream) if len(items) > 1 else None
  for index, item in enumerate(items, 1):
    try:
      if item.is_video:
        if bar:
          bar.clear()  # The video draws its own frame progress.
        frames = _unmix_video(unmixing.fn, item, output_dir, layout, max_disparity, report,
                              progress_stream)
      else:
        image = media.read_image(item.path)
        unmix_start = time.perf_counter()
        outputs = unmixing.fn(image)
        report.unmix_seconds += time.perf_counter() - unmix_start
        media.write_image_outputs(outputs, output_dir, item.name, layout, max_disparity)
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
