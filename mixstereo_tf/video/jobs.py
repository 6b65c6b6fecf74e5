"""Frame-by-frame video jobs whose outputs survive interruption and resume where they stopped.

    frames = run(VideoJob(input_path, {'sbs': 'out/a_sbs.mp4'}, settings), render)

`render(image)` returns {output key: uint8 RGB frame} for one input frame (or a call that
returns them, made in order on the encoding thread: `Rendered`). Frames are
encoded in segments of `VideoConfig.segment_frames` into `<folder>/<key>_<k>.mov` (a MOV
part holds exact timestamps for every codec), where `<folder>` is the first output path +
'.segments'. `manifest.json` there records the input (path, size, mtime), the settings and
each finished segment; a file is renamed into place only once finished, and the manifest is
replaced atomically after it. A re-run with a matching manifest keeps the finished segments
and renders from the first missing one; otherwise it starts afresh. At the end each output
is assembled (`assembly.assemble`: the segments' packets and the input's audio, copied) under
a temporary name `<stem>.partial<ext>` and renamed, so an interrupted run never leaves a
file with a final name that is not complete; then the folder is removed, with those of
earlier runs of the same input that stopped before their end (other outputs or settings).
"""

import dataclasses
import fractions
import json
import os
import shutil
from typing import Callable, Dict, Optional, Tuple, Union

import numpy as np

from mixstereo_tf.video import assembly
from mixstereo_tf.video import encoders
from mixstereo_tf.video import pipelining
from mixstereo_tf.video import streams

Fraction = fractions.Fraction
# What `render` gives for a frame: its images, or a call that gives them (run in order on
# the writer's thread: a frame still being finished, `frame_pipeline`).
Rendered = Union[Dict[str, np.ndarray], Callable[[], Dict[str, np.ndarray]]]
MANIFEST = 'manifest.json'
# (primaries, transfer) of outputs drawn in sRGB colours (`VideoJob.colour_maps`): BT.709's
# (FFmpeg's AVColorPrimaries / AVColorTransferCharacteristic 1), whose transfer players
# show as sRGB's.
SRGB_TAGS = (1, 1)
_VERSION = 1


@dataclasses.dataclass(frozen=True)
class VideoConfig:
  """How video jobs run.

  Attributes:
    segment_frames: frames per resumable segment.
    queue_depth: frames decoded ahead of, and frames waiting to be encoded after, the
      one being rendered (`pipelining`).
    keep_bits: a video of more than 8 bits per sample keeps them in its views' video
      (`VideoJob.deep`: H.264 High 10, which VLC, mpv and Kodi play, QuickTime and browsers
      do not); False: 8-bit views, which every player plays.
  """
  segment_frames: int = 60
  queue_depth: int = 4
  keep_bits: bool = True

  def __post_init__(self):
    if self.segment_frames < 1:
      raise ValueError(f'VideoConfig.segment_frames must be >= 1, got {self.segment_frames}.')
    if self.queue_depth < 1:
      raise ValueError(f'VideoConfig.queue_depth must be >= 1, got {self.queue_depth}.')


@dataclasses.dataclass(frozen=True)
class VideoJob:
  """One input video and its outputs.

  Attributes:
    input_path: the video to read.
    outputs: {key: final output path}; every path has the same extension (its container).
    settings: JSON-serialisable description of everything that changes the frames (the
      unmixer, the layout, ...); finished segments are reused only when it is equal.
    config: segments, queues, the bits kept (`VideoConfig`).
    stereo_modes: {key: `encoders.STEREO_MODES` name} of the outputs tagged as stereo
      (frame-packing SEI, Matroska StereoMode).
    deep: the outputs that keep an input's samples of more than 8 bits, encoded at its
      bits (`encoders.encoder_for`); the others at 8. Such an input's frames reach
      `render` as uint16 either way (`run`).
    colour_maps: the outputs drawn in sRGB colours whatever the input's (a disparity's
      colour map): tagged BT.709 (`SRGB_TAGS`), not with the input's primaries and
      transfer, which an HDR input's (BT.2020, HLG or PQ) would make players misshow.
  """
  input_path: str
  outputs: Dict[str, str]
  settings: Dict[str, object]
  config: VideoConfig = VideoConfig()
  stereo_modes: Dict[str, str] = dataclasses.field(default_factory=dict)
  deep: Tuple[str, ...] = ()
  colour_maps: Tuple[str, ...] = ()

  @property
  def folder(self) -> str:
    """Where the segments and the manifest live until the outputs are complete."""
    return next(iter(self.outputs.values())) + '.segments'


def partial_path(path: str) -> str:
  """The temporary name an output is assembled under: `<stem>.partial<ext>`."""
  root, extension = os.path.splitext(path)
  return f'{root}.partial{extension}'


def _identity(job: VideoJob) -> Dict[str, object]:
  """What a manifest must match for its segments to be reused."""
  stat = os.stat(job.input_path)
  return {'version': _VERSION, 'input': os.path.abspath(job.input_path),
          'size': stat.st_size, 'mtime_ns': stat.st_mtime_ns,
          'segment_frames': job.config.segment_frames, 'outputs': sorted(job.outputs),
          'encoder': dataclasses.asdict(encoders.encoder_for(next(iter(job.outputs.values())))),
          'stereo_modes': job.stereo_modes, 'settings': job.settings,
          **({'deep': list(job.deep)} if job.deep else {}),
          **({'colour_maps': list(job.colour_maps)} if job.colour_maps else {})}


def _segment_path(job: VideoJob, key: str, index: int) -> str:
  return os.path.join(job.folder, f'{key}_{index:05d}.mov')


def _write_manifest(job: VideoJob, manifest: Dict[str, object]) -> None:
  """Replaces the manifest atomically (a crash leaves the old or the new one)."""
  path = os.path.join(job.folder, MANIFEST)
  with open(path + '.tmp', 'w', encoding='utf-8') as f:
    json.dump(manifest, f, indent=1)
    f.flush()
    os.fsync(f.fileno())
  os.replace(path + '.tmp', path)


def load_progress(job: VideoJob) -> Dict[str, object]:
  """The manifest of `job.folder` when it matches the job and its segment files exist,
  else a fresh one (the folder emptied). Keys: the identity, 'segments' (a list of
  {'frames', 'start'}: start = the first frame's time, 'num/den' seconds) and 'complete'
  (the input's last frame is in a segment)."""
  identity = json.loads(json.dumps(_identity(job)))  # As read back (tuples become lists).
  try:
    with open(os.path.join(job.folder, MANIFEST), encoding='utf-8') as f:
      manifest = json.load(f)
  except (OSError, ValueError):
    manifest = None
  if manifest is not None and {k: manifest.get(k) for k in identity} == identity:
    segments = manifest.get('segments', [])
    if all(os.path.isfile(_segment_path(job, key, i))
           for i in range(len(segments)) for key in job.outputs):
      return manifest
  shutil.rmtree(job.folder, ignore_errors=True)
  os.makedirs(job.folder)
  manifest = dict(identity, segments=[], complete=False)
  _write_manifest(job, manifest)
  return manifest


class _Segment:
  """The files of one segment being written: each frame goes straight to its encoders."""

  def __init__(self, job: VideoJob, index: int, info: streams.VideoInfo, start: Fraction):
    self.job, self.index, self.start, self.frames = job, index, start, 0
    self.writers = {key: streams.VideoWriter(partial_path(_segment_path(job, key, index)),
                                              info.frame_rate, info.time_base,
                                              encoders.encoder_for(
                                                  path, job.stereo_modes.get(key),
                                                  info.bits if key in job.deep else 8),
                                              info.aspect, SRGB_TAGS
                                              if key in job.colour_maps else info.colour)
                    for key, path in job.outputs.items()}

  def write(self, frame: streams.Frame, images: Rendered) -> None:
    """Encodes one frame's images (`run`'s `render` result: calling it gives them)."""
    if callable(images):
      images = images()
    for key, writer in self.writers.items():
      writer.write(images[key], frame.time - self.start)
    self.frames += 1

  def finish(self) -> Dict[str, object]:
    """Completes the files, renames them into place; returns the manifest entry."""
    for key, writer in self.writers.items():
      writer.close()
      os.replace(writer.path, _segment_path(self.job, key, self.index))
    return {'frames': self.frames, 'start': str(self.start)}

  def abort(self) -> None:
    """Drops the unfinished files."""
    for writer in self.writers.values():
      try:
        writer.close()
      finally:
        if os.path.exists(writer.path):
          os.remove(writer.path)


def _finish(job: VideoJob, manifest: Dict[str, object], segment: _Segment) -> None:
  manifest['segments'].append(segment.finish())
  _write_manifest(job, manifest)


def _render_segments(job, manifest, info, frames, done, render) -> None:
  """Renders the frames from `done` on into segments recorded in `manifest`: decoding
  runs ahead in one thread, encoding (and the manifest's updates) follows in another,
  in order (`pipelining`), so `manifest` is only read here after the writer has drained;
  an unfinished segment's files are removed on any exception."""
  segment, count, index = None, 0, len(manifest['segments'])
  writer = pipelining.SerialWorker(job.config.queue_depth)
  try:
    with pipelining.Prefetcher(frames, job.config.queue_depth) as ahead:
      for frame in ahead:
        if frame.index < done:
          continue
        if segment is None:
          segment, count = _Segment(job, index, info, frame.time), 0
          index += 1
        writer.submit(segment.write, frame, render(frame.image))
        count += 1
        if count == job.config.segment_frames:
          writer.submit(_finish, job, manifest, segment)
          segment = None
    if segment is not None:
      writer.submit(_finish, job, manifest, segment)
      segment = None
    writer.drain()
  finally:
    writer.close()
    if segment is not None:
      segment.abort()


def _abandoned_folders(job: VideoJob):
  """The other segment folders beside `job.folder` whose manifest names the same input:
  runs of it with other outputs or settings that stopped before their end."""
  parent = os.path.dirname(job.folder) or '.'
  source = os.path.abspath(job.input_path)
  for name in sorted(os.listdir(parent)):
    folder = os.path.join(parent, name)
    if not name.endswith('.segments') or os.path.abspath(folder) == os.path.abspath(job.folder):
      continue
    try:
      with open(os.path.join(folder, MANIFEST), encoding='utf-8') as f:
        if json.load(f).get('input') == source:
          yield folder
    except (OSError, ValueError, AttributeError):
      continue


def run(job: VideoJob, render: Callable[[np.ndarray], Rendered],
        on_start: Optional[Callable[[streams.VideoInfo, int], None]] = None
        ) -> Dict[str, object]:
  """Renders every frame of `job.input_path` into `job.outputs`, resuming a previous run.

  Args:
    job: the input, outputs and settings.
    render: RGB input frame (uint8; uint16 from an input of more than 8 bits per sample,
      whatever `job.deep` keeps, as a video's opening frame was unmixed from,
      `cli.video_files.opening`) -> {output key: RGB frame, uint8 or uint16 (written at 8
      bits unless the key is deep)}, or a call returning them (`Rendered`, called on the
      writer's thread in frame order); a frame's outputs may differ in size from each
      other but not between frames.
    on_start: called with the VideoInfo and the number of frames already done before any
      frame is rendered (e.g. to start a progress bar).

  Returns:
    {'info': the VideoInfo, 'frames': frames in the outputs, 'resumed_frames': frames
    taken from an earlier run}.

  Raises:
    ValueError: the input cannot be read (the message names it) or an output not written.
  """
  manifest = load_progress(job)
  done = sum(entry['frames'] for entry in manifest['segments'])
  try:
    info, frames = streams.open_video(job.input_path, skip=done, deep=True)
  except ValueError:
    if not manifest['segments']:  # Nothing to resume: no folder left behind.
      shutil.rmtree(job.folder, ignore_errors=True)
    raise
  if on_start:
    on_start(info, done)
  if not manifest['complete']:
    _render_segments(job, manifest, info, frames, done, render)
    manifest['complete'] = True
    _write_manifest(job, manifest)
  frames.close()
  for key, path in job.outputs.items():
    parts = [assembly.Part(_segment_path(job, key, i), Fraction(entry['start']))
             for i, entry in enumerate(manifest['segments'])]
    assembly.assemble(parts, partial_path(path), info.frame_rate, info.time_base,
                      job.input_path, info.rotation, job.stereo_modes.get(key))
    os.replace(partial_path(path), path)
  shutil.rmtree(job.folder)
  for folder in _abandoned_folders(job):  # Its results are these now.
    shutil.rmtree(folder, ignore_errors=True)
  total = sum(entry['frames'] for entry in manifest['segments'])
  return {'info': info, 'frames': total, 'resumed_frames': done}
