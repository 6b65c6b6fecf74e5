"""Anaglyphs made by an independent encoder: FFmpeg's `stereo3d` filter.

    image = encode(left_u8, right_u8, 'half_color')   # FFmpeg's arch from the pair
    stored = round_trip(image, 'h264')                 # as a video stores it

FFmpeg comes from imageio-ffmpeg's static binary (the 'eval' and 'test' extras of
setup.py; PyAV's wheels are built without stereo3d). The pair goes in side by side, left
first (`sbsl`); the output mode per encoding is FFMPEG_MODES. FFmpeg's amber-blue colour,
gray and half-colour modes (aybc, aybg, aybh) put the amber filter over the right eye, the
mirror of `mixtures.amber_blue*`, so those are fed the views exchanged. `round_trip` stores
an image as published anaglyphs are stored (JPEG, H.264 video: both with 4:2:0 chroma).
"""

import os
import subprocess
import tempfile
from typing import Dict, Tuple

import cv2
import numpy as np

# Our encoding -> (FFmpeg stereo3d output mode, views exchanged).
FFMPEG_MODES: Dict[str, Tuple[str, bool]] = {
    'anaglyph': ('arcc', False), 'gray': ('arcg', False), 'half_color': ('arch', False),
    'dubois_ffmpeg': ('arcd', False), 'green_magenta': ('agmc', False),
    'green_magenta_gray': ('agmg', False), 'green_magenta_half': ('agmh', False),
    'green_magenta_dubois': ('agmd', False), 'amber_blue': ('aybc', True),
    'amber_blue_gray': ('aybg', True), 'amber_blue_half': ('aybh', True),
    'amber_blue_dubois': ('aybd', False), 'red_blue': ('arbg', False),
    'red_green': ('argg', False),
}
# Lossy storage -> FFmpeg output options: a JPEG of quality about 90 and an H.264 video
# frame at x264's default quality, both with chroma at half resolution (4:2:0).
CODECS: Dict[str, Tuple[str, ...]] = {
    'jpeg': ('-q:v', '3', '-pix_fmt', 'yuvj420p'),
    'h264': ('-c:v', 'libx264', '-pix_fmt', 'yuv420p', '-crf', '23'),
}
_SUFFIX = {'jpeg': '.jpg', 'h264': '.mkv'}


def ffmpeg_binary() -> str:
  """The path of imageio-ffmpeg's FFmpeg; ImportError naming the package when missing."""
  try:
    import imageio_ffmpeg  # pylint: disable=g-import-not-at-top
  except ImportError as error:
    raise ImportError("FFmpeg encoding needs imageio-ffmpeg: pip install "
                      "'mixstereo_tf[eval]' (or imageio-ffmpeg).") from error
  return imageio_ffmpeg.get_ffmpeg_exe()


def encode(left: np.ndarray, right: np.ndarray, name: str) -> np.ndarray:
  """The anaglyph FFmpeg makes of a pair.

  Args:
    left, right: uint8 [H, W, 3] RGB views of one size.
    name: an encoding of FFMPEG_MODES.

  Returns:
    uint8 [H, W, 3] RGB.

  Raises:
    ValueError: an encoding FFmpeg does not make, or views of different sizes.
    RuntimeError: FFmpeg failed (its message included).
  """
  if name not in FFMPEG_MODES:
    raise ValueError(f'FFmpeg stereo3d makes no {name!r} anaglyph; it makes '
                     f'{", ".join(FFMPEG_MODES)}.')
  if left.shape != right.shape or left.ndim != 3 or left.dtype != np.uint8:
    raise ValueError(f'encode needs two uint8 [H, W, 3] views of one size, got '
                     f'{left.shape} {left.dtype} and {right.shape} {right.dtype}.')
  mode, exchanged = FFMPEG_MODES[name]
  first, second = (right, left) if exchanged else (left, right)
  with tempfile.TemporaryDirectory() as folder:
    source, target = os.path.join(folder, 'sbs.png'), os.path.join(folder, 'out.png')
    cv2.imwrite(source, cv2.cvtColor(np.concatenate([first, second], 1), cv2.COLOR_RGB2BGR))
    _run(['-i', source, '-vf', f'stereo3d=sbsl:{mode}', target])
    return cv2.cvtColor(cv2.imread(target), cv2.COLOR_BGR2RGB)


def _run(arguments) -> None:
  done = subprocess.run([ffmpeg_binary(), '-y', '-loglevel', 'error', *arguments],
                        capture_output=True, text=True, check=False)
  if done.returncode != 0:
    raise RuntimeError(f'FFmpeg {" ".join(arguments)} failed: {done.stderr.strip()}')


def round_trip(image: np.ndarray, codec: str) -> np.ndarray:
  """`image` stored with a lossy codec of CODECS by FFmpeg and decoded again.

  Args:
    image: uint8 [H, W, 3] RGB (H.264 4:2:0 needs even H and W).
    codec: a key of CODECS; 'png' returns the image itself.

  Returns:
    uint8 [H, W, 3] RGB.

  Raises:
    ValueError: an unknown codec, or odd sizes for h264.
    RuntimeError: FFmpeg failed (its message included).
  """
  if codec == 'png':
    return image
  if codec not in CODECS:
    raise ValueError(f'Unknown codec {codec!r}; known: png, {", ".join(CODECS)}.')
  if codec == 'h264' and (image.shape[0] % 2 or image.shape[1] % 2):
    raise ValueError(f'H.264 4:2:0 needs even sizes, got {image.shape[1]}x{image.shape[0]}.')
  with tempfile.TemporaryDirectory() as folder:
    source, stored, target = (os.path.join(folder, name) for name in
                              ('in.png', 'stored' + _SUFFIX[codec], 'out.png'))
    cv2.imwrite(source, cv2.cvtColor(image, cv2.COLOR_RGB2BGR))
    _run(['-i', source, *CODECS[codec], stored])
    _run(['-i', stored, target])
    return cv2.cvtColor(cv2.imread(target), cv2.COLOR_BGR2RGB)
