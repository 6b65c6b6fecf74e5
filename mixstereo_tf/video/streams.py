"""Video files through PyAV (FFmpeg's libraries in-process): decode, encode, remux.

    info, frames = open_video('in.mp4')        # VideoInfo, iterator of Frame (uint8 RGB)
    with VideoWriter('part.mp4', info.frame_rate) as writer:
      writer.write(image, time)               # time: exact Fraction seconds
    assembly.assemble([assembly.Part('part.mp4')], 'out.mp4', info.frame_rate,
                      info.time_base, audio_source='in.mp4', rotation=info.rotation)

Times are exact `Fraction` seconds (a frame's pts times its stream's time base), so frame
rates like 30000/1001 and variable frame rates survive. The encoder follows the output
extension (`encoders.encoder_for`). `assembly.assemble` concatenates encoded parts packet by packet
and copies the audio and subtitle packets of the source unchanged (no re-encode).
Rotation (the display matrix) is read from the decoded frames; FFmpeg's libraries take it
into a file only through the stream's side data, which PyAV cannot set, so `assemble`
adds it with a stream-copy pass of imageio-ffmpeg's ffmpeg binary when that package is
installed (else it is logged as lost).
"""

import dataclasses
import fractions
import itertools
import math
import struct
from typing import Iterator, Optional, Tuple

from absl import logging
import av
import numpy as np

from mixstereo_tf.core import image_range
from mixstereo_tf.video import encoders

Fraction = fractions.Fraction
# What PyAV raises for unreadable or unwritable media.
FFmpegError = av.FFmpegError
# Frame rate assumed when a video does not report one.
DEFAULT_FRAME_RATE = Fraction(25)


@dataclasses.dataclass(frozen=True)
class VideoInfo:
  """What `open_video` found.

  Attributes:
    width, height: frame size in pixels, as the frames are delivered (upright when
      `turned`).
    frame_rate: frames per second, exact (the stream's average rate; DEFAULT_FRAME_RATE
      when it reports none).
    time_base: the video stream's time base (the unit of its timestamps).
    frame_count: the container's count, None when it does not say.
    rotation: degrees counter-clockwise a player still turns the delivered frames (the
      display matrix; 0 once they are turned upright, or if the file has none).
    audio_streams: how many audio streams the file holds.
    turned: degrees counter-clockwise the reader turned the stored frames, so that they
      arrive as a player shows them: 90, 180 or -90 (0: as stored).
    aspect: the sample (pixel) aspect ratio of the delivered frames, None when square or
      unknown (anamorphic footage: e.g. 4/3 for 1440x1080 shown at 16:9).
    colour: the first frame's (primaries, transfer) tags, FFmpeg's AVColorPrimaries /
      AVColorTransferCharacteristic numbers (2: unspecified): what its RGB values mean.
    chroma_halved: the stream stores colour at half the width or height (4:2:0, 4:2:2,
      nv12: most video), as `hints.FrameHint.chroma_halved` says.
    bits: the stream's bits per sample (10: HDR and many phones' HEVC); frames of more
      than 8 are delivered as uint16 when asked (`open_video(deep=True)`).
  """
  width: int
  height: int
  frame_rate: Fraction
  time_base: Fraction
  frame_count: Optional[int]
  rotation: int
  audio_streams: int
  turned: int = 0
  aspect: Optional[Fraction] = None
  colour: Tuple[int, int] = (2, 2)
  chroma_halved: bool = False
  bits: int = 8


@dataclasses.dataclass(frozen=True)
class Frame:
  """One decoded frame: `image` uint8 RGB [H, W, 3] (uint16, the samples scaled to 0-65535,
  from a stream of more than 8 bits opened `deep`; None when skipped), `time` in exact
  seconds from the stream's timestamps, `index` from 0 in decoding order."""
  image: Optional[np.ndarray]
  time: Fraction
  index: int


def _frames(container: av.container.InputContainer, decoded: Iterator[av.VideoFrame],
            rate: Fraction, skip: int, quarter_turns: int = 0,
            rgb: str = 'rgb24') -> Iterator[Frame]:
  """Frames of `decoded` in format `rgb` (rgb24 or rgb48le), turned `quarter_turns` x 90
  degrees counter-clockwise; those before `skip` are not converted to RGB. Frames of
  another size than the first (a stream whose resolution changes: a broadcast, joined
  clips) are scaled to the first's, as FFmpeg's own tools do, with one warning naming
  where the size changed: every output keeps one size.

  Times come from the frames' pts (when missing: the previous time + 1 / rate) and are
  made strictly increasing, as every encoder needs. Closes the container at the end.
  """
  previous = size = None
  resized = set()  # The other sizes met, each warned about once.
  try:
    for index, frame in enumerate(decoded):
      size = size or (frame.width, frame.height)
      if (frame.width, frame.height) != size and (frame.width, frame.height) not in resized:
        resized.add((frame.width, frame.height))
        logging.warning('%s: frames from %d on are %dx%d, not %dx%d as the first: scaled to '
                        '%dx%d (the outputs keep the first frame\'s size).', container.name,
                        index, frame.width, frame.height, *size, *size)
      if frame.pts is not None and frame.time_base:
        time = frame.pts * Fraction(frame.time_base)
      else:
        time = Fraction(0) if previous is None else previous + 1 / rate
      if previous is not None and time <= previous:
        time = previous + 1 / rate
      previous = time
      image = (frame.to_ndarray(format=rgb, width=size[0], height=size[1])
               if index >= skip else None)
      if image is not None and quarter_turns:
        image = np.ascontiguousarray(np.rot90(image, quarter_turns))
      yield Frame(image, time, index)
  finally:
    container.close()


def _display_rotation(frame: av.VideoFrame) -> int:
  """Degrees counter-clockwise a player turns `frame`: its display matrix's angle (as
  FFmpeg's av_display_rotation_get, 16.16 fixed point), rounded; 0 without one. PyAV's
  `rotation` truncates it (a 30-degree file's 29.9996 read 29, and each pass through the
  tool lost a degree)."""
  for data in getattr(frame, 'side_data', ()):
    if getattr(data.type, 'name', '') == 'DISPLAYMATRIX' and len(bytes(data)) == 36:
      matrix = [value / 65536.0 for value in struct.unpack('<9i', bytes(data))]
      scales = math.hypot(matrix[0], matrix[3]), math.hypot(matrix[1], matrix[4])
      if min(scales) > 0:
        return round(-math.degrees(math.atan2(matrix[1] / scales[1], matrix[0] / scales[0])))
  return round(getattr(frame, 'rotation', 0) or 0)


def open_video(path: str, skip: int = 0, upright: bool = True,
               deep: bool = False) -> Tuple[VideoInfo, Iterator[Frame]]:
  """Opens a video: its VideoInfo and an iterator over its frames (`Frame`).

  Args:
    path: a video file.
    skip: the first `skip` frames are decoded but yield no image (resuming a job).
    upright: frames whose display matrix turns them by a multiple of 90 degrees (phones
      filming in portrait) are turned as a player shows them, so that the eyes of a
      mixture lie side by side as its viewer saw them (`VideoInfo.turned`); False: as
      stored.
    deep: frames of a stream with more than 8 bits per sample come as uint16 RGB.

  Raises:
    ValueError: the file cannot be opened, has no video stream or no decodable frame;
      the message names the path.
  """
  try:
    container = av.open(path)
  except (av.FFmpegError, OSError) as e:
    raise ValueError(f'Cannot open video file {path}: {e}') from None
  try:
    stream = container.streams.video[0]
    stream.thread_type = 'AUTO'
    decoded = container.decode(stream)
    first = next(decoded)
  except (IndexError, StopIteration, av.FFmpegError) as e:
    container.close()
    reason = 'no video stream' if isinstance(e, IndexError) else 'no decodable frame'
    raise ValueError(f'Cannot read video file {path}: {reason}') from None
  rate = Fraction(stream.average_rate or stream.guessed_rate or DEFAULT_FRAME_RATE)
  # FFmpeg >= 7 attaches the stream's display matrix to every decoded frame; older muxers
  # wrote a 'rotate' tag.
  rotation = _display_rotation(first) or int(float(stream.metadata.get('rotate', 0)))
  turns = rotation // 90 % 4 if upright and rotation % 90 == 0 else 0
  size = (first.height, first.width) if turns % 2 else (first.width, first.height)
  aspect = stream.sample_aspect_ratio or stream.codec_context.sample_aspect_ratio
  aspect = (1 / Fraction(aspect) if turns % 2 else Fraction(aspect)) if aspect else None
  info = VideoInfo(*size, rate, Fraction(stream.time_base or 1 / rate), stream.frames or None,
                   0 if turns else rotation, len(container.streams.audio),
                   turned=(rotation % 360 + 179) % 360 - 179 if turns else 0,  # (-180, 180].
                   aspect=aspect if aspect and aspect != 1 else None,
                   colour=(int(first.color_primaries), int(first.color_trc)),
                   chroma_halved=any(c.width < first.width or c.height < first.height
                                     for c in first.format.components),
                   bits=max(c.bits for c in first.format.components))
  rgb = 'rgb48le' if deep and info.bits > 8 else 'rgb24'
  return info, _frames(container, itertools.chain([first], decoded), rate, skip, turns, rgb)


class VideoWriter:
  """Encodes RGB frames [H, W, 3] into a video-only file (default encoder: the path's,
  `encoders.encoder_for`): uint8, or uint16 (0-65535), kept at the encoder's bits.

  The size comes from the first frame; odd sizes are padded by one row / column of edge
  replication (4:2:0 chroma needs even sizes); `aspect` is the sample aspect ratio encoded,
  `colour` the (primaries, transfer) tagged (`VideoInfo.colour`: the frames' RGB as read).
  Timestamps are `time / time_base` rounded and kept strictly increasing; AVI always counts
  frames (time base 1 / frame_rate).
  """

  def __init__(self, path: str, frame_rate: Fraction, time_base: Optional[Fraction] = None,
               encoder: Optional[encoders.EncoderSettings] = None,
               aspect: Optional[Fraction] = None, colour: Tuple[int, int] = (2, 2)):
    self.path, self.aspect, self.colour = path, aspect, colour
    self.settings = encoder or encoders.encoder_for(path)
    self.frame_rate = Fraction(frame_rate)
    frame_index = self.settings.codec == 'mjpeg' or not time_base
    self.time_base = 1 / self.frame_rate if frame_index else Fraction(time_base)
    self._container = self._stream = self._size = None
    self._last_pts = None

  def _open(self, size: Tuple[int, int]) -> None:
    try:
      self._container = av.open(self.path, 'w')
    except (av.FFmpegError, OSError) as e:
      raise ValueError(f'Cannot write video file {self.path}: {e}') from None
    stream = self._container.add_stream(self.settings.codec, rate=self.frame_rate,
                                        options=dict(self.settings.options))
    stream.width, stream.height = (size[1] + 1) // 2 * 2, (size[0] + 1) // 2 * 2
    stream.pix_fmt = self.settings.pix_fmt
    stream.codec_context.colorspace = self.settings.matrix
    stream.codec_context.color_range = self.settings.color_range
    stream.codec_context.color_primaries, stream.codec_context.color_trc = self.colour
    stream.time_base = stream.codec_context.time_base = self.time_base
    if self.aspect:
      stream.codec_context.sample_aspect_ratio = self.aspect
    self._stream, self._size = stream, size

  def write(self, image: np.ndarray, time: Fraction) -> None:
    """Encodes one frame shown at `time` seconds."""
    if self._container is None:
      self._open(image.shape[:2])
    elif image.shape[:2] != self._size:
      raise ValueError(f'Frame size {image.shape[:2]} differs from {self._size} in '
                       f'{self.path}')
    pad = ((0, self._stream.height - image.shape[0]), (0, self._stream.width - image.shape[1]),
           (0, 0))
    # `padded` must outlive the encode call: PyAV may wrap the array without copying it.
    if self.settings.bits == 8:
      image = image_range.eight_bits(image)
    padded = np.ascontiguousarray(np.pad(image, pad, 'edge'))
    frame = av.VideoFrame.from_ndarray(padded, format='rgb48le' if padded.dtype == np.uint16
                                       else 'rgb24')
    frame = frame.reformat(format=self.settings.pix_fmt,  # The encoder's, as tagged.
                           dst_colorspace=self.settings.matrix,
                           dst_color_range=self.settings.color_range)
    pts = round(Fraction(time) / self.time_base)
    if self._last_pts is not None:
      pts = max(pts, self._last_pts + 1)
    frame.pts, frame.time_base, self._last_pts = pts, self.time_base, pts
    for packet in self._stream.encode(frame):
      self._container.mux(packet)

  def close(self) -> None:
    """Flushes the encoder and finishes the file (no file when no frame was written)."""
    if self._container is not None:
      try:
        for packet in self._stream.encode(None):
          self._container.mux(packet)
      finally:
        self._container.close()
        self._container = None

  def __enter__(self):
    return self

  def __exit__(self, *exc):
    self.close()
