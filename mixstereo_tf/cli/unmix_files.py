"""Unmixing files: every image and video of an input specification, results to a folder.

Images are read as viewers show them (EXIF orientation applied: `input_images.read_upright`).
Outputs per input `<name>` in the output folder, where `<name>` is the file stem, or stem + '_' +
extension when inputs share a stem (`input_listing.output_names`): the views (`<name>_left.png` and
`<name>_right.png` for the 'separate' layout, else `<name>_<layout>.png`; 16-bit from a 16-bit
anaglyph, RGBA from an image with transparency), the colour-mapped left disparity
`<name>_disparity.png` (over the range found, or a fixed one), KITTI-style `<name>_disparity16.png`
(uint16, d * 256; only when every disparity lies in 0..255.996 px) and float32 signed pixels
`<name>_disparity.npy`, the stereo formats asked for (`OutputOptions.formats`, `stereo_formats`),
and a side-car `<name>_info.json` (mixture used and detected, range searched, scale, method,
seconds, files, the EXIF orientation applied, the request; `info_file`). Per video, in the input's
container (`.mp4`, `.mov`, `.mkv`, `.avi`; `.webm` in `.mkv`) with its frame rate, timestamps,
audio and subtitle streams (copied), frames a player turns by quarter turns (portrait phone videos)
turned upright before they are unmixed and written so (other rotations copied): the layout as
`<name>_<layout><ext>` (or `_left` / `_right`; side by side and top-bottom tagged as such:
`encoders.STEREO_MODES`), `<name>_disparity<ext>`, `<name>_<format><ext>` for the formats drawn as
videos (rgbd, anaglyphs; the others are skipped, saying why) and `<name>_info.json` (the first
unmixed frame's info, frames, frame rate, rotation left to players, `turned_upright` degrees, audio
streams, the scene cuts found in this run, `shots`: each shot's first frame and decisions (mixture,
range, eye order, weight; from `shots_from_frame` on when a run resumed), files, the colour maps'
`display_range`; `video_files`). Videos are written resumably (`video.jobs`). Progress
(`progress.ProgressBar`) is shown for several inputs and for every video's frames.

Video frames are unmixed with temporal consistency (`temporal`, unless
`TemporalConfig.enabled` is off): the encoding and the range are decided once per shot and
each frame gets the previous frame's disparity as a prior. Every resumable segment starts
a new shot, so a resumed run starts each segment from the state an uninterrupted run has
there.
"""

import contextlib
import dataclasses
import logging as std_logging
import threading
import time
from typing import Dict, Iterator, List, Optional, TextIO, Tuple

from absl import logging
import numpy as np

from mixstereo_tf.cli import media
from mixstereo_tf.cli import progress
from mixstereo_tf.cli import info_file
from mixstereo_tf.cli import input_failures
from mixstereo_tf.cli import input_images
from mixstereo_tf.cli import input_listing
from mixstereo_tf.cli import video_files
from mixstereo_tf.core import hints
from mixstereo_tf.core import printable
from mixstereo_tf.unmixing import predictors


@dataclasses.dataclass
class UnmixReport:
  """What `unmix_inputs` did: counts, failures as (path, reason), timings in seconds
  (unmix_seconds: what the image or frame loop waited for the unmixer; a video frame's
  restoration that runs beside the next frame's matching is not counted)."""
  processed: int = 0
  frames: int = 0
  failures: List[Tuple[str, str]] = dataclasses.field(default_factory=list)
  seconds: float = 0.0
  unmix_seconds: float = 0.0

  @property
  def frames_per_second(self) -> float:
    """Frames over the whole run, reading and writing included."""
    return self.frames / self.seconds if self.seconds > 0 else 0.0


def _unmix_image(unmixer: predictors.Unmixer, item: input_listing.MediaItem, output_dir: str,
                 layout: str, max_display_disparity: Optional[float],
                 report: UnmixReport, formats: Tuple[str, ...] = (),
                 request: Optional[Dict] = None) -> int:
  """Unmixes one image and writes its outputs (with `formats`) and `<name>_info.json`;
  returns 1 (frame)."""
  found = input_images.header(item.path)
  image, orientation, lost = input_images.read_upright(item.path, found, deep=True, alpha=True)
  stored = hints.stored(found.chroma_halved)  # A 4:2:0 JPEG (unmixing/chroma).
  unmix_start = time.perf_counter()
  with input_images.blaming_truncation(item.path):
    outputs = unmixer(image, **stored)  # RGBA: unmixed without its alpha.
  report.unmix_seconds += time.perf_counter() - unmix_start
  lost += input_images.depth_lost(image, outputs['left'])
  if image.shape[2] == 4:  # Transparency kept: the views carry the input's alpha.
    outputs = dict(outputs, **{key: media.with_alpha(outputs[key], image[..., 3])
                               for key in ('left', 'right')})
  icc_profile = found.icc_profile
  info_file.begin_outputs(output_dir, item)
  written = media.write_image_outputs(outputs, output_dir, item.name, layout,
                                      max_display_disparity, formats, image, icc_profile)
  if icc_profile:
    written['icc_profile'] = f'the input\'s, {len(icc_profile)} bytes: kept in the views'
  if orientation != 1:
    written['exif_orientation'] = orientation  # Applied: the outputs are upright.
  if outputs['left'].dtype == np.uint16:
    written['views_bit_depth'] = 16  # The view PNGs; the formats and maps have 8 bits.
  if image.shape[2] == 4:
    written['views_alpha'] = "the input's transparency, pixel for pixel, in both views"
  written.update(input_images.reading_notes(item.path, found, lost))
  info_file.write_info(output_dir, item, dict(outputs.get('info', {}), **written), request)
  return 1


def unmix_item(unmixer: predictors.Unmixer, item: input_listing.MediaItem, output_dir: str,
               options: media.OutputOptions, report: UnmixReport,
               progress_stream: Optional[TextIO] = None) -> int:
  """Unmixes one image or video into `output_dir` (existing); returns the frames unmixed.

  The one path every tool writes an input's results by (`mixstereo-unmix`, the batch
  pipeline). Errors propagate (`input_failures.INPUT_ERRORS` are the per-input ones);
  `report` gains the seconds spent unmixing.
  """
  request = info_file.describe(options)
  if item.is_video:
    opened = video_files.opening(unmixer, item.path, options.temporal_config)
    display = ((0.0, float(options.max_display_disparity)) if options.max_display_disparity
               else video_files.display_range(unmixer, opened.info))
    return video_files.unmix_video(
        unmixer, item, opened, output_dir, options.layout, display,
        options.settings or video_files.default_settings(unmixer), options.video_config,
        progress_stream, report, options.temporal_config, options.formats, request)
  return _unmix_image(unmixer, item, output_dir, options.layout,
                      options.max_display_disparity, report, options.formats, request)


class _NamingInputs(std_logging.Filter):
  """Prefixes warnings and errors with the input they concern (`naming_input`): the one
  its thread runs, else, while a single input runs, that one (a warning of a helper
  thread, e.g. the video pipeline's); unnamed while several run (Beam's threads) and the
  thread runs none of them, or when the record says it names its input (NAMES_ITS_INPUT)."""

  def __init__(self):
    super().__init__()
    self.paths: Dict[int, str] = {}  # Thread id -> its input, printable.

  def filter(self, record: std_logging.LogRecord) -> bool:
    paths = dict(self.paths)  # A copy: other threads add and remove theirs.
    path = paths.get(record.thread or 0) or (next(iter(paths.values())) if len(paths) == 1
                                             else None)
    # The formatted message: a record whose arguments name the path is not named twice.
    message = record.getMessage()
    if (path and record.levelno >= std_logging.WARNING and not message.startswith(path)
        and not getattr(record, NAMES_ITS_INPUT, False)):
      record.msg, record.args = f'{path}: {message}', ()
    return True


NAMES_ITS_INPUT = 'names_its_input'  # In a log call's `extra`: `naming_input` adds no name.


_NAMING = _NamingInputs()


@contextlib.contextmanager
def naming_input(path: str) -> Iterator[None]:
  """While inside, the warnings logged by this thread (and by any thread while no other
  input runs) name `path`: the library's own (a detected encoding's doubt, a clipped
  range) do not know the file."""
  logger = logging.get_absl_logger()
  if _NAMING not in logger.filters:
    logger.addFilter(_NAMING)  # After core.printable's filter: the path is printable.
  thread = threading.get_ident()
  _NAMING.paths[thread] = printable.printable(path)
  try:
    yield
  finally:
    _NAMING.paths.pop(thread, None)


def unmix_inputs(unmixer: predictors.Unmixer, input_spec: str, output_dir: str,
                 options: media.OutputOptions = media.OutputOptions(),
                 progress_stream: Optional[TextIO] = None) -> UnmixReport:
  """Unmixes every image / video of `input_spec` (see `input_listing.iter_inputs`) by `unmix_item`.

  An input that cannot be read, unmixed or written is logged with its path and the reason,
  recorded in `UnmixReport.failures` and skipped; the others still run.

  Videos are written in resumable segments (`video.jobs`, `options.video_config`):
  re-running the same call after an interruption continues from the last finished segment,
  as long as the input and `options.settings` are unchanged. Progress (`ProgressBar`) is
  drawn on `progress_stream` when it is a terminal, else logged.

  Raises:
    ValueError: `input_spec` names nothing usable, or `output_dir` cannot take the results
      (`input_listing.prepare_output_dir`).
  """
  earlier = info_file.read_earlier(output_dir)
  items = list(input_listing.iter_inputs(input_spec, earlier.names, earlier.outputs))
  input_listing.prepare_output_dir(items, output_dir)
  report = UnmixReport()
  run_start = time.perf_counter()
  bar = progress.ProgressBar(len(items), stream=progress_stream) if len(items) > 1 else None
  for index, item in enumerate(items, 1):
    if bar and item.is_video:
      bar.clear()  # The video draws its own frame progress.
    try:
      with naming_input(item.path):
        frames = unmix_item(unmixer, item, output_dir, options, report, progress_stream)
    except input_failures.INPUT_ERRORS as e:
      input_failures.check_output_room(output_dir, e)
      if bar:
        bar.clear()
      why = input_failures.reason(e)
      logging.error('[%d/%d] skipped %s: %s', index, len(items), item.path, why)
      report.failures.append((item.path, why))
    else:
      report.processed += 1
      report.frames += frames
    if bar:
      bar.update(index, report.frames)
  if bar:
    bar.close()
  report.seconds = time.perf_counter() - run_start
  return report
