"""Writing the results of the unmix tool: images, videos, disparity files (inputs are
listed by `input_listing` and read by `input_images`).

Images are uint8 RGB `[H, W, 3]` (docs/DESIGN.md reader convention); disparities float32
`[H, W]` in pixels, positive. Video files are read and written by `video.streams` (PyAV).
"""

import dataclasses
import os
from typing import Dict, List, Optional, Sequence, Tuple, Union

import cv2
import numpy as np
from PIL import Image

from mixstereo_tf.cli import stereo_formats
from mixstereo_tf.core import colormap
from mixstereo_tf.core import image_range
from mixstereo_tf.data import image_io
from mixstereo_tf.video import jobs
from mixstereo_tf.video import temporal

LAYOUTS = ('separate', 'sbs', 'sbs_half', 'tb')
# The stereo mode a layout's video is tagged with (`encoders.STEREO_MODES`).
STEREO_MODES = {'sbs': 'left_right', 'sbs_half': 'left_right', 'tb': 'top_bottom'}
# Video inputs whose results go in another container: WebM holds only VP8 / VP9 / AV1,
# and the outputs are H.264 (`encoders.ENCODERS`), so Matroska, WebM's parent format; an
# .m4v (Apple's name for MP4) gives .mp4 files. MPEG transport streams (broadcasts,
# camcorders' AVCHD .mts / .m2ts), MPEG program streams, WMV and FLV carry no stereo
# layout tag and audio (MP2, AC-3, WMA) that MP4 may refuse: Matroska takes both.
OUTPUT_CONTAINERS = {'.webm': '.mkv', '.m4v': '.mp4', '.ts': '.mkv', '.m2ts': '.mkv',
                     '.mts': '.mkv', '.mpg': '.mkv', '.mpeg': '.mkv', '.wmv': '.mkv',
                     '.flv': '.mkv'}


def write_disparity_png16(path: str, disparity: np.ndarray) -> None:
  """Writes disparity KITTI-style: uint16 PNG holding round(d * 256), 0 = invalid.

  NaN and negative values are stored as 0 (invalid); others, 0 included (a point at
  infinity), as at least 1 so that a valid estimate never reads back as invalid; values are
  clipped to 65535 (255.996 px).

  Args:
    path: output .png path.
    disparity: [H, W] (or [H, W, 1]) float pixels.
  """
  disparity = np.asarray(disparity, np.float64)
  disparity = disparity.reshape(disparity.shape[:2])
  valid = disparity >= 0  # NaN compares False.
  disparity = np.nan_to_num(disparity, nan=0.0, posinf=65535.0 / 256.0, neginf=0.0)
  stored = np.clip(np.round(disparity * 256.0), 0, 65535)
  stored = np.where(valid, np.maximum(stored, 1), 0).astype(np.uint16)
  if not image_io.write_with_opencv(path, stored):
    raise ValueError(f'Cannot write PNG file: {path}')


def write_image(path: str, image: np.ndarray, icc_profile: Optional[bytes] = None) -> None:
  """Writes a uint8 RGB or RGBA image (format from the extension; uint16: a 16-bit PNG),
  with `icc_profile` (the input's colour space, `icc_profile_of`) embedded when given."""
  if icc_profile and image.dtype != np.uint16:
    try:
      Image.fromarray(np.ascontiguousarray(image, np.uint8),
                      'RGBA' if image.shape[2] == 4 else 'RGB').save(path, icc_profile=icc_profile)
    except (OSError, ValueError, KeyError) as e:
      raise ValueError(f'Cannot write image file: {path} ({e})') from None
    return
  bgr = np.ascontiguousarray(image[:, :, [2, 1, 0, 3][:image.shape[2]]])  # OpenCV's order.
  if not image_io.write_with_opencv(path, bgr):
    raise ValueError(f'Cannot write image file: {path}')
  if icc_profile:  # Pillow writes no 16-bit RGB: OpenCV's PNG, then the profile.
    image_io.add_png_icc(path, icc_profile)


def with_alpha(view: np.ndarray, alpha: np.ndarray) -> np.ndarray:
  """An RGB view [H, W, 3] as RGBA with `alpha` [H, W] (uint8 or uint16) at the view's
  depth: the input's transparency, pixel for pixel, in both views."""
  if view.dtype != np.uint16:
    alpha = image_range.eight_bits(alpha)  # A 16-bit double image's 8-bit views.
  elif alpha.dtype != np.uint16:
    alpha = alpha.astype(np.uint16) * 257
  return np.concatenate([view, alpha[..., None]], axis=2)


def compose(left: np.ndarray, right: np.ndarray,
            layout: str) -> Union[np.ndarray, Tuple[np.ndarray, np.ndarray]]:
  """Arranges two equally sized views [H, W, C].

  Layouts: 'separate' returns (left, right); 'sbs' [H, 2W, C] left then right; 'sbs_half'
  [H, W, C], each view squeezed to half width (left (W + 1) // 2 columns, right W // 2;
  area interpolation), the frame keeping the input size; 'tb' [2H, W, C] left on top.
  """
  if left.shape != right.shape:
    raise ValueError(f'Views differ in shape: {left.shape} vs {right.shape}.')
  if layout == 'separate':
    return left, right
  if layout == 'sbs':
    return np.concatenate([left, right], axis=1)
  if layout == 'tb':
    return np.concatenate([left, right], axis=0)
  if layout == 'sbs_half':
    height, width = left.shape[:2]
    halves = [cv2.resize(view, (w, height), interpolation=cv2.INTER_AREA).reshape(
        height, w, *view.shape[2:]) for view, w in ((left, (width + 1) // 2),
                                                     (right, width // 2)) if w > 0]
    return np.concatenate(halves, axis=1)
  raise ValueError(f'Unknown layout {layout!r}; valid: {", ".join(LAYOUTS)}.')


def layout_images(left: np.ndarray, right: np.ndarray, layout: str) -> List[Tuple[str, np.ndarray]]:
  """`compose` as (file-name suffix, image) pairs: left/right for 'separate', else layout."""
  composed = compose(left, right, layout)
  if layout == 'separate':
    return [('left', composed[0]), ('right', composed[1])]
  return [(layout, composed)]


PNG16_LIMIT = 65535.0 / 256.0  # The largest disparity a KITTI-style uint16 PNG holds.


def display_range(disparity: np.ndarray,
                  max_display_disparity: Optional[float] = None) -> Tuple[float, float]:
  """The colour map's (low, high): (0, max_display_disparity) when given, else the range
  the disparity map actually covers (its 0.5 and 99.5 percentiles, at least 1 px wide)."""
  if max_display_disparity:
    return 0.0, float(max_display_disparity)
  finite = np.asarray(disparity, np.float32)
  finite = finite[np.isfinite(finite)]
  if not finite.size:
    return 0.0, 1.0
  low, high = (float(v) for v in np.percentile(finite, [0.5, 99.5]))
  return low, max(high, low + 1.0)


def write_image_outputs(outputs: Dict[str, np.ndarray], output_dir: str, name: str,
                        layout: str, max_display_disparity: Optional[float] = None,
                        formats: Sequence[str] = (), mixture: Optional[np.ndarray] = None,
                        icc_profile: Optional[bytes] = None) -> Dict[str, object]:
  """Writes one image's results (mixstereo_tf/cli/unmix_files.py).

  Args:
    outputs: {'left', 'right': uint8 [H, W, 3] (uint16: written as 16-bit PNGs; RGBA
      [H, W, 4]: with transparency; the formats from their 8-bit RGB copies),
      'disparity_left': [H, W] signed pixels}.
    output_dir: existing folder.
    name: the file-name prefix.
    layout: one of LAYOUTS.
    max_display_disparity: a fixed colour-map range 0..this; None: the range found.
    formats: `stereo_formats.FORMATS` names also written (depth images span the colour
      map's range).
    mixture: the input image, uint8 (or uint16) RGB [H, W, 3] (or RGBA; the 'html'
      viewer page needs it).
    icc_profile: the input's ICC profile (`icc_profile_of`), embedded in the views and the
      formats drawn from them; the disparity maps carry none.

  Returns:
    {'files': the paths written, 'display_range': the colour map's (low, high),
    'disparity16': why no uint16 PNG was written, when none was (it holds 0..255.996 px:
    negative or larger disparities are not representable; the .npy holds them).}
  """
  paths = []  # The views at their depth (16-bit PNG from a 16-bit input), the rest at 8.
  for suffix, image in layout_images(outputs['left'], outputs['right'], layout):
    paths.append(os.path.join(output_dir, f'{name}_{suffix}.png'))
    write_image(paths[-1], image, icc_profile)
  disparity = np.asarray(outputs['disparity_left'], np.float32)
  low, high = display_range(disparity, max_display_disparity)
  paths.append(os.path.join(output_dir, f'{name}_disparity.png'))
  colour = colormap.colorize(disparity, high, low)
  write_image(paths[-1], colour)
  written = {'display_range': [round(low, 3), round(high, 3)]}
  smallest, largest = float(np.nanmin(disparity)), float(np.nanmax(disparity))
  if smallest >= 0.0 and largest <= PNG16_LIMIT:
    paths.append(os.path.join(output_dir, f'{name}_disparity16.png'))
    write_disparity_png16(paths[-1], disparity)
  else:
    written['disparity16'] = (f'not written: the disparities span {smallest:.1f}..'
                              f'{largest:.1f} px, outside the 0..{PNG16_LIMIT:.3f} px a '
                              'KITTI-style uint16 PNG holds; see the .npy')
  paths.append(os.path.join(output_dir, f'{name}_disparity.npy'))
  np.save(paths[-1], disparity)
  left, right = (image_range.eight_bits(outputs[key][..., :3]) for key in ('left', 'right'))
  mixture = None if mixture is None else image_range.eight_bits(mixture[..., :3])
  paths.extend(stereo_formats.write_formats(stereo_formats.StereoResult(
      left, right, disparity, colour, (low, high), mixture, icc_profile),
      os.path.join(output_dir, name), formats))
  written['files'] = [os.path.basename(p) for p in paths]
  return written


@dataclasses.dataclass(frozen=True)
class OutputOptions:
  """How each input's results are written (`unmix_files.unmix_item`; flags of `mixstereo-unmix`).

  layout: one of `LAYOUTS`. max_display_disparity: the colour maps span 0..this many
  pixels (None: each image's disparities found; videos: the range searched on the first
  frame).
  video_config: resumable segments (`video.jobs`). settings: a JSON-serialisable
  description of the unmixer for a video job's manifest (None: its method, mixture and
  range). temporal_config: a video's per-shot decisions and disparity prior (`temporal`).
  formats: `stereo_formats.FORMATS` names written besides the layout (default none).
  """
  layout: str = 'separate'
  max_display_disparity: Optional[float] = None
  video_config: jobs.VideoConfig = jobs.VideoConfig()
  settings: Optional[Dict[str, object]] = None
  temporal_config: temporal.TemporalConfig = temporal.TemporalConfig()
  formats: Tuple[str, ...] = ()

  def __post_init__(self):
    object.__setattr__(self, 'formats', stereo_formats.check_formats(self.formats))
    if self.layout not in LAYOUTS:
      raise ValueError(f'Unknown layout {self.layout!r}; valid: {", ".join(LAYOUTS)}.')
    if self.max_display_disparity is not None and not (
        0 < self.max_display_disparity < float('inf')):
      raise ValueError('OutputOptions.max_display_disparity must be positive and finite, '
                       f'got {self.max_display_disparity}.')
