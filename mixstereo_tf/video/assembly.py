"""Joining encoded video parts and a source's audio into one file, by copying packets.

`assemble` concatenates the parts (files of one encoder configuration, `streams.VideoWriter`)
packet by packet, shifted by each part's start time, and interleaves the audio and
subtitle packets of a source file unchanged (no re-encode); rotation and the stereo layout
become stream metadata (`encoders.STEREO_MODES`).
"""

import dataclasses
import fractions
import heapq
import math
from typing import Dict, Iterator, Optional, Sequence, Tuple

from absl import logging
import av

from mixstereo_tf.video import encoders

Fraction = fractions.Fraction


@dataclasses.dataclass(frozen=True)
class Part:
  """An encoded video file and the seconds added to its timestamps in `assemble`."""
  path: str
  start: Fraction = Fraction(0)


def _video_packets(parts: Sequence[Part], stream) -> Iterator[Tuple[Fraction, av.Packet]]:
  """(decode time in seconds, packet) of every part in order, shifted by part.start.

  A part's first decode times fall before its start by the encoder's reordering delay,
  which grows with the spacing of its frames; where that reaches back over the previous
  part's last (a short last part of a variable-rate or cut video), they are moved just
  after it (never past the packet's presentation time): muxers need them increasing.
  """
  last = None
  for part in parts:
    with av.open(part.path) as container:
      source = container.streams.video[0]
      for packet in container.demux(source):
        if packet.size == 0:
          continue  # The demuxer's end-of-stream marker.
        base = Fraction(packet.time_base)
        shift = round(part.start / base)
        packet.pts = None if packet.pts is None else packet.pts + shift
        packet.dts = None if packet.dts is None else packet.dts + shift
        if packet.dts is not None and last is not None and packet.dts * base <= last:
          after = math.floor(last / base) + 1
          if packet.pts is None or after <= packet.pts:
            packet.dts = after
        packet.stream = stream
        stamp = packet.dts if packet.dts is not None else packet.pts
        last = stamp * base
        yield last, packet


def _source_packets(container, streams: Dict[int, object]
                    ) -> Iterator[Tuple[Fraction, av.Packet]]:
  """(decode time in seconds, packet) of the copied streams (`_COPIED`), unchanged but
  re-targeted."""
  if not streams:
    return
  for packet in container.demux([container.streams[i] for i in streams]):
    if packet.size == 0:
      continue
    stamp = packet.dts if packet.dts is not None else packet.pts
    stamp = 0 if stamp is None else stamp
    packet.stream = streams[packet.stream.index]
    yield stamp * Fraction(packet.time_base), packet


# Container tags that describe the file's own muxing, not its content: not copied.
_MUXING_TAGS = ('major_brand', 'minor_version', 'compatible_brands', 'encoder')
# Stream types copied from the source, packet by packet, with these tags.
_COPIED = ('audio', 'subtitle')
_STREAM_TAGS = ('language', 'title')


def _copy_streams(source, out, output: str) -> Dict[int, object]:
  """{source stream index: output stream} of the source's audio and subtitle streams, added
  to `out` with their language and title, and the source's content tags (title, creation
  time, ...) onto `out`; other streams (data, attachments) are logged as not copied. (The
  video's sample aspect ratio comes with the parts, which encode it:
  `streams.VideoWriter`.)"""
  copied = {s.index: out.add_stream_from_template(s) for s in source.streams
            if s.type in _COPIED}
  out.metadata.update({k: v for k, v in source.metadata.items() if k not in _MUXING_TAGS})
  for index, stream in copied.items():
    tags = source.streams[index].metadata
    stream.metadata.update({k: tags[k] for k in _STREAM_TAGS if k in tags})
  dropped = [f'#{s.index} ({s.type})' for s in source.streams
             if s.type not in _COPIED + ('video',)]
  if dropped:
    logging.warning('%s: streams of %s not copied: %s.', output, source.name,
                    ', '.join(dropped))
  return copied


def assemble(parts: Sequence[Part], output: str, frame_rate: Fraction,
             time_base: Optional[Fraction] = None, audio_source: Optional[str] = None,
             rotation: int = 0, stereo_mode: Optional[str] = None) -> None:
  """Writes the parts' video one after the other and the source's audio and subtitles into
  `output`.

  Packets are copied, not re-encoded: the parts must come from one encoder configuration
  (same codec parameters, checked). The video stream gets `frame_rate` and `time_base`
  (AVI: 1 / frame_rate); every audio and subtitle stream of `audio_source` is copied
  unchanged, with the source's content tags (`_copy_streams`); a
  non-zero `rotation` (degrees counter-clockwise) becomes the display matrix (PyAV >= 18;
  older versions log that it is lost); `stereo_mode` (a STEREO_MODES key) tags the video
  stream (Matroska writes it as StereoMode; other containers ignore the tag).

  Raises:
    ValueError: no parts, or parts encoded differently.
  """
  if not parts:
    raise ValueError(f'No video to write to {output}')
  if encoders.encoder_for(output).codec == 'mjpeg' or not time_base:
    time_base = 1 / Fraction(frame_rate)
  with av.open(parts[0].path) as first:
    template = first.streams.video[0]
    extradata = template.codec_context.extradata
    for part in parts[1:]:
      with av.open(part.path) as other:
        if other.streams.video[0].codec_context.extradata != extradata:
          raise ValueError(f'{part.path} is encoded unlike {parts[0].path}; cannot join.')
    with av.open(output, 'w') as out:
      video = out.add_stream_from_template(template)
      video.time_base, video.framerate = Fraction(time_base), Fraction(frame_rate)
      if stereo_mode:
        video.metadata['stereo_mode'] = stereo_mode
      if rotation and hasattr(video, 'set_display_rotation'):
        video.set_display_rotation(rotation)
      elif rotation:
        logging.warning('%s: the input is rotated by %d degrees; writing rotation needs '
                        'PyAV >= 18, so the output is shown unrotated.', output, rotation)
      source = av.open(audio_source) if audio_source else None
      try:
        copied = _copy_streams(source, out, output) if source is not None else {}
        merged = heapq.merge(_video_packets(parts, video), _source_packets(source, copied),
                             key=lambda item: item[0])
        for _, packet in merged:
          out.mux(packet)
      finally:
        if source is not None:
          source.close()
