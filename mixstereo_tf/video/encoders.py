"""How each video container is encoded (`encoder_for`): codec, pixel format, options, colour
tags, the stereo frame-packing tag of side-by-side and top-bottom outputs, and the encoder
of frames with more than 8 bits per sample (`DEEP`).
"""

import dataclasses
import os
from typing import Dict, Optional, Tuple


@dataclasses.dataclass(frozen=True)
class EncoderSettings:
  """How a container is encoded: codec, pixel format, codec options, and the RGB -> YUV
  matrix and range, both used and tagged (FFmpeg's AVColorSpace / AVColorRange numbers:
  1 BT.709 / limited, 5 BT.601 / full), and its name as players list it (`label`)."""
  codec: str
  pix_fmt: str
  options: Tuple[Tuple[str, str], ...] = ()
  matrix: int = 1
  color_range: int = 1
  label: str = ''

  @property
  def bits(self) -> int:
    """Bits per sample the encoder keeps."""
    return 10 if '10' in self.pix_fmt else 8


# H.264 at constant quality 18 (visually lossless for x264) in 4:2:0, which every player
# decodes; AVI gets Motion JPEG at the best quantiser (AVI holds no B-frame timing).
# Preset veryfast: on a 2560x720 side-by-side clip it encodes in 61 ms a frame on one core
# where medium took 166 ms, at the same PSNR (41.03 / 41.01 dB) and size (987 / 1036
# KiB); on a 2-core machine medium's encoding took a third of the CPU of a video job.
# x264's macroblock-tree rate control is off (mbtree=0): on CPUs with AVX-512 its AVX-512
# code encodes identical frames differently from run to run (seen with libx264 core 165
# whenever the width in macroblocks is not a multiple of 16, e.g. 96 or 1920 px), and a
# resumed video job must re-encode its segments exactly as an uninterrupted run does.
# Colour: BT.709 limited range, tagged (untagged 4:2:0 is read as BT.709 by most players
# at HD sizes, where FFmpeg's default conversion wrote BT.601: green 255 showed as 215);
# AVI's Motion JPEG is JFIF's full-range BT.601.
_H264 = EncoderSettings('libx264', 'yuv420p', (('crf', '18'), ('preset', 'veryfast'),
                                               ('x264-params', 'mbtree=0')),
                        label='H.264 High')
# Frames of more than 8 bits per sample (a 10-bit phone or HDR video's views) in MP4, MOV
# and MKV: the same H.264 at 10 bits (High 10). Measured on a 2560x720 photo frame, 8 frames
# on 2 cores: 39.3 dB PSNR at 375 KiB and 0.05 s a frame, where 8 bits gave 36.5 dB at 383
# KiB and 0.03 s. HEVC Main 10 (x265, what such phones record and more players decode) gave
# 39.4 dB at 317 KiB and 0.12 s, but PyAV's MP4 / MOV muxing of it failed ('Not yet
# implemented in FFmpeg') in 160 of 200 one-frame files of a ramp (x264: none), so it is
# not used. High 10 plays in FFmpeg-based players (VLC, mpv, Kodi), not QuickTime or browsers.
DEEP = dataclasses.replace(_H264, pix_fmt='yuv420p10le', label='H.264 High 10')
ENCODERS: Dict[str, EncoderSettings] = {
    '.mp4': _H264, '.mov': _H264, '.mkv': _H264,
    '.avi': EncoderSettings('mjpeg', 'yuvj420p', (('qmin', '1'), ('qmax', '2')), 5, 2,
                            'Motion JPEG'),
}


# Stereo tags (Matroska StereoMode names: the muxer reads the stream's `stereo_mode` tag) ->
# x264's frame-packing SEI type (any container; ffprobe: frames' "Stereo 3D" side data).
# MP4 / MOV get the SEI alone: FFmpeg's st3d box needs stream side data PyAV cannot set.
STEREO_MODES = {'left_right': 3, 'top_bottom': 4}


def encoder_for(path: str, stereo_mode: Optional[str] = None,
                bits: int = 8) -> EncoderSettings:
  """The encoder of a video path's extension (ENCODERS); ValueError naming the path.

  `stereo_mode` (a STEREO_MODES key) adds x264's frame-packing SEI (other codecs: none);
  `bits` > 8: frames of more bits per sample, encoded by DEEP where the container's
  encoder is H.264 (AVI's Motion JPEG has 8 bits)."""
  extension = os.path.splitext(path)[1].lower()
  if extension not in ENCODERS:
    raise ValueError(f'Cannot write video {path}: extension must be one of '
                     f'{" ".join(ENCODERS)}.')
  settings = ENCODERS[extension]
  if bits > 8 and settings.codec == 'libx264':
    settings = DEEP
  if stereo_mode is None or settings.codec != 'libx264':
    return settings
  options = tuple((key, f'{value}:frame-packing={STEREO_MODES[stereo_mode]}')
                  if key == 'x264-params' else (key, value) for key, value in settings.options)
  return dataclasses.replace(settings, options=options)
