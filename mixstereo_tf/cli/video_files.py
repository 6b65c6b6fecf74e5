"""Unmixing one video file: its frames, resumably, into layout, disparity and format videos.

`unmix_video` is `unmix_files.unmix_item`'s video path (outputs listed in `unmix_files`):
frames go through a shot's temporal state and the frame pipeline, are drawn on the
writer's thread and written in resumable segments (`video.jobs`); the colour maps span the
range searched on the first frame (`display_range`).
"""

import dataclasses
import os
import time
from typing import Callable, Dict, List, Optional, TextIO, Tuple

from absl import logging
import numpy as np

from mixstereo_tf.cli import info_file
from mixstereo_tf.cli import input_listing
from mixstereo_tf.cli import media
from mixstereo_tf.cli import progress
from mixstereo_tf.cli import stereo_formats
from mixstereo_tf.core import colormap
from mixstereo_tf.core import image_range
from mixstereo_tf.unmixing import mixture_choice
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.video import encoders
from mixstereo_tf.video import frame_pipeline
from mixstereo_tf.video import jobs
from mixstereo_tf.video import streams
from mixstereo_tf.video import temporal


def default_settings(unmixer: predictors.Unmixer) -> Dict[str, object]:
  """What identifies an unmixer in a video job's manifest when the caller gives nothing."""
  return {'method': unmixer.method, 'mixture': unmixer.mixture,
          'max_disparity': unmixer.max_disparity, 'restore_colour': unmixer.restore_colour}


def _video_outputs(item: input_listing.MediaItem, output_dir: str, layout: str,
                   formats: Tuple[str, ...]) -> Tuple[Dict[str, str], Tuple[str, ...],
                                                      Dict[str, str]]:
  """A video's ({key: output path}, the stereo formats drawn as videos, {format skipped:
  why}); the skipped ones are logged."""
  extension = os.path.splitext(item.path)[1].lower()
  extension = media.OUTPUT_CONTAINERS.get(extension, extension)
  drawn, skipped = stereo_formats.video_formats(formats)
  for name, why in skipped.items():
    logging.warning('%s: --output_format=%s %s.', item.path, name, why)
  keys = (['left', 'right'] if layout == 'separate' else [layout]) + ['disparity']
  outputs = {key: os.path.join(output_dir, f'{item.name}_{key}{extension}')
             for key in keys + list(drawn)}
  return outputs, drawn, skipped


def _frame_images(result: Dict[str, object], layout: str, display: Tuple[float, float],
                  drawn: Tuple[str, ...]) -> Dict[str, object]:
  """One unmixed frame's images: {output key: RGB}, the views' (uint16 from a deep video's
  frame) at their depth, the colour maps (over `display`) and `drawn` formats uint8."""
  images = dict(media.layout_images(result['left'], result['right'], layout))
  images['disparity'] = colormap.colorize(result['disparity_left'], display[1], display[0])
  if drawn:
    pair = stereo_formats.StereoResult(image_range.eight_bits(result['left']),
                                       image_range.eight_bits(result['right']),
                                       result['disparity_left'], images['disparity'],
                                       display)
    images.update((name, stereo_formats.FORMATS[name].frame(pair)) for name in drawn)
  return images


# A shot's decisions, as the video's info lists them (`shot_entry`).
SHOT_KEYS = ('mixture', 'disparity_range', 'eye_order', 'mixing_weight')


def shot_entry(frame: int, info: Dict[str, object]) -> Dict[str, object]:
  """{'first_frame': frame} and the SHOT_KEYS a frame's info holds."""
  return dict(first_frame=frame, **{k: info[k] for k in SHOT_KEYS if k in info})


def record_shot(shots: List[Dict[str, object]], frame: int, info: Dict[str, object],
                starts_shot: bool) -> None:
  """Appends the entry of `frame` to `shots` when it starts a shot (a scene cut or a
  segment's first frame, with --temporal) or decides otherwise than the last entry
  (frame by frame)."""
  entry = shot_entry(frame, info)
  last = shots[-1] if shots else {}
  if starts_shot or any(entry.get(k) != last.get(k) for k in ('mixture', 'eye_order')):
    shots.append(entry)


class Opening:
  """The frame `opening` unmixed: its index in the video, its info, the bits per sample of
  the video (`bits`) and of the views made from it (`view_bits`: 16 where the method
  makes them from a deep video's samples, else 8), and the call, which the frame pipeline
  takes for that frame where its hint is the same (`frame_pipeline.Unmixed`), once: its
  images are not held through the video."""

  def __init__(self, index: int, unmixed: frame_pipeline.Unmixed, bits: int = 8):
    self.index, self._unmixed, self.bits = index, unmixed, bits
    self.view_bits = 16 if np.asarray(unmixed.outputs.get('left', 0)).dtype == np.uint16 else 8
    self.info: Dict[str, object] = dict(unmixed.outputs.get('info', {}))

  def take(self, index: int) -> Optional[frame_pipeline.Unmixed]:
    """The call, for the video's frame `index` when it is this one (then no more)."""
    if index != self.index:
      return None
    unmixed, self._unmixed = self._unmixed, None
    return unmixed


def frame_fields(chroma_halved: bool, config: temporal.TemporalConfig) -> Dict[str, object]:
  """A video frame's hint fields: the views and left disparity written (a double image's
  its first stage's with the shot's prior, else refined as a still's), and its storage."""
  prior = config.enabled and config.use_prior
  return {'unread': 'disparity_right', 'base_disparities': prior, 'chroma_halved': chroma_halved}


def _drawn_when_done(pending, state: Dict[str, object], layout: str,
                     display: Tuple[float, float], drawn: Tuple[str, ...],
                     starts_shot: bool) -> Callable[[], Dict[str, object]]:
  """The call that draws a frame's images once its unmixing (`pending`, a Future) is done,
  made in frame order on the video writer's thread (`jobs.Rendered`); it records the
  video's first frame's info (not a resumed run's first: `opening`'s stands for it), the
  shot the frame starts (`record_shot`) and the progress in `state`."""
  def images():
    result = pending.result()
    if state['info'] is None and not state['done']:
      state['info'] = dict(result.get('info', {}))
    record_shot(state['shots'], state['done'] + state['rendered'], result.get('info', {}),
                starts_shot)
    drawn_images = _frame_images(result, layout, display, drawn)
    state['rendered'] += 1
    state['bar'].update(state['done'] + state['rendered'], state['rendered'])
    return drawn_images

  return images


def unmix_video(unmixer: predictors.Unmixer, item: input_listing.MediaItem, opened: Opening,
                output_dir: str, layout: str, display: Tuple[float, float],
                settings: Dict[str, object], video_config: jobs.VideoConfig,
                progress_stream: Optional[TextIO],
                report, temporal_config: temporal.TemporalConfig,
                formats: Tuple[str, ...] = (), request: Optional[Dict] = None) -> int:
  """Unmixes every frame of a video into layout, disparity and `formats` videos (resumable,
  `video.jobs`; side by side and top-bottom tagged so; views kept above 8 bits), writes
  `<name>_info.json` (with `request`; `opened`'s info, the `opening` frame's, when this
  run resumed) and returns the frames unmixed in this run; `report` gains the seconds
  spent unmixing. Frames go through a `temporal.VideoState` (shots; frames with no
  anaglyph found read as `opened`'s encoding until a shot finds one) and `frame_pipeline`
  (`opened`'s frame not unmixed again), then drawn and written on the writer's thread."""
  start = time.perf_counter()
  shots = temporal.VideoState(temporal_config, opened.info.get('mixture'))
  outputs, drawn, skipped = _video_outputs(item, output_dir, layout, formats)
  state = {'bar': None, 'done': 0, 'rendered': 0, 'info': None, 'shots': []}
  pipeline = frame_pipeline.FramePipeline(unmixer, shots)

  def on_start(info, done):
    state['bar'] = progress.ProgressBar(info.frame_count, os.path.basename(item.path),
                                        progress_stream, resumed=done)
    state['done'], state['chroma_halved'] = done, info.chroma_halved

  def render(frame):
    unmix_start = time.perf_counter()
    index = state['done'] + shots.frames  # This run's frames begun before this one.
    fields = frame_fields(state['chroma_halved'], temporal_config)
    pending = pipeline.submit(frame, index % video_config.segment_frames == 0,
                              opened.take(index), **fields)
    report.unmix_seconds += time.perf_counter() - unmix_start
    return _drawn_when_done(pending, state, layout, display, drawn, shots.started_shot())

  job = _job(item, outputs, dict(settings, layout=layout, display_range=list(display),
                                 temporal=dataclasses.asdict(temporal_config), formats=drawn),
             video_config, layout, opened)
  info_file.begin_outputs(output_dir, item)
  try:
    with pipeline:
      done = jobs.run(job, render, on_start)
    # The container's frame count may be wrong or missing.
    state['bar'].update(done['frames'], state['rendered'], force=True)
  finally:
    if state['bar']:
      state['bar'].close()
  info = done['info']
  info_file.write_info(output_dir, item, dict(
      state['info'] or opened.info, frames=done['frames'], resumed_frames=done['resumed_frames'],
      frame_rate=str(info.frame_rate), rotation=info.rotation, turned_upright=info.turned,
      display_range=[round(v, 3) for v in display], temporal=temporal_config.enabled,
      scene_cuts=[state['done'] + index for index in shots.cuts],
      shots=state['shots'], **({'shots_from_frame': state['done']} if state['done'] else {}),
      audio_streams=info.audio_streams, seconds=round(time.perf_counter() - start, 3),
      files=[os.path.basename(path) for path in outputs.values()],
      **({'skipped_formats': skipped} if skipped else {}),
      **_notes(info, done['frames'], item.path, _view_bits(outputs, job))), request)
  return state['rendered']


# A video's frames searched for its first anaglyph ('auto'): every SCAN_STRIDE-th of the
# first SCAN_FRAMES (a minute at 25 frames/s, five a second).
SCAN_FRAMES, SCAN_STRIDE = 1500, 5


def opening(unmixer: predictors.Unmixer, path: str,
            temporal_config: temporal.TemporalConfig = temporal.TemporalConfig()) -> Opening:
  """A video's first frame unmixed as the first frame of its shot (the hint the frame
  pipeline gives it, which then takes these outputs), or with `unmixer.mixture` 'auto'
  its first frame in which detection finds an anaglyph (`SCAN_STRIDE`, `SCAN_FRAMES`):
  the black frames, fades or titles before it are read as its encoding
  (`temporal.VideoState.fallback_mixture`).

  Raises:
    ValueError: no frame of those scanned shows an anaglyph, naming the video.
  """
  info, frames = streams.open_video(path, deep=True)
  last = None
  try:
    for index, frame in enumerate(frames):
      if index % SCAN_STRIDE and unmixer.mixture == mixture_choice.AUTO:
        continue
      hint = dataclasses.replace(
          temporal.VideoState(temporal_config).begin(frame.image, cut=True),
          **frame_fields(info.chroma_halved, temporal_config))
      try:
        return Opening(index, frame_pipeline.Unmixed(frame.image, hint,
                                                     unmixer(frame.image, hint=hint)),
                       info.bits)
      except mixture_choice.NoAnaglyphError as e:
        if index + SCAN_STRIDE >= SCAN_FRAMES:
          raise ValueError(f'No frame of the first {SCAN_FRAMES} of {path} looks like an '
                           f'anaglyph ({e}); name its mixture (--mixture).') from None
        last = e
  finally:
    frames.close()
  raise ValueError(f'No frame of {path} looks like an anaglyph ({last}); name its mixture '
                   '(--mixture).')


def display_range(unmixer: predictors.Unmixer, opened: Dict[str, object]
                  ) -> Tuple[float, float]:
  """A video's colour-map (low, high): the disparity range searched in its `opening` frame
  (the same on every run, so a resumed job colours its frames as the first run did). Later
  shots beyond it are clipped."""
  searched = opened.get('disparity_range')
  low, high = searched if searched else (0.0, unmixer.max_disparity)
  return float(low), float(max(high, low + 1))


def _job(item: input_listing.MediaItem, outputs: Dict[str, str], settings: Dict[str, object],
         video_config: jobs.VideoConfig, layout: str, opened: Opening
         ) -> jobs.VideoJob:
  """A video's job (`jobs.VideoJob`): side by side and top-bottom tagged as stereo; the
  views (the layout's) kept above 8 bits (`jobs.VideoJob.deep`) where `opened` found such
  samples and made its views of them, and video_config.keep_bits asks for them; the
  disparity's colour map tagged sRGB."""
  deep = video_config.keep_bits and opened.bits > 8 and opened.view_bits > 8
  views = ('left', 'right') if layout == 'separate' else (layout,)
  return jobs.VideoJob(item.path, outputs, settings, video_config,
                       {layout: media.STEREO_MODES[layout]}
                       if layout in media.STEREO_MODES else {},
                       views if deep else (), ('disparity',))


def _view_bits(outputs: Dict[str, str], job: jobs.VideoJob) -> Tuple[int, str]:
  """(Bits per sample of the views' videos, their encoder's label where more than 8, else
  why not more): the input's as encoded (`jobs.VideoJob.deep`), else 8 (asked, or the
  method's views)."""
  if job.deep:
    encoder = encoders.encoder_for(outputs[job.deep[0]], bits=16)
    return encoder.bits, encoder.label if encoder.bits > 8 else (
        f"this container's codec, {encoder.label}, has no more")
  if not job.config.keep_bits:
    return 8, 'asked: --nokeep_video_bits, for players without 10-bit H.264'
  return 8, 'this method makes 8-bit views'


def _notes(info, frames: int, path: str, view_bits: Tuple[int, str]) -> Dict[str, object]:
  """{'padding': why an output video is a row or column larger than the input}, if it is;
  {'ended_early': ...} (also logged) when the video ended well before the frames its
  container declares (a cut or damaged file: what decoded is written); for samples of
  more than 8 bits {'bit_depth': what was kept of them}, 'views_bit_depth': the views'
  videos' (`view_bits`: with their encoder, or why not more; logged where it is 8)."""
  notes = {}
  if info.width % 2 or info.height % 2:
    notes['padding'] = (f'{info.width}x{info.height} frames: an output video whose width or '
                        'height is odd gets one more column or row, copied from its edge '
                        '(4:2:0 video needs even sizes); crop it to recover the input size')
  if info.frame_count and frames < 0.95 * info.frame_count:
    notes['ended_early'] = (f'{path} ended after {frames} of the {info.frame_count} frames '
                            'its container declares (a cut or damaged file?); the decoded '
                            'ones are written')
    logging.warning('%s.', notes['ended_early'])
  bits, said = view_bits
  if info.bits > 8:
    notes['views_bit_depth'] = bits
    notes['bit_depth'] = f'{path} stores {info.bits}-bit samples: ' + (
        f'matched at 8 bits, its views made from 16-bit samples and written at {bits} '
        f'({said}); the disparity video and other formats at 8' if bits > 8
        else f'its views were written at 8 bits ({said})')
    if bits == 8:
      logging.warning('%s.', notes['bit_depth'])
  return notes
