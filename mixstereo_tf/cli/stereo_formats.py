"""Stereo-photo formats of a recovered pair: MPO, JPS, wiggle GIF, RGBD, viewer page, anaglyphs.

`FORMATS` maps each `--output_format` name to a `StereoFormat`: how one image's result is
written (`write(result, stem) -> paths`, files named `<stem><suffix>`) and, where the format
makes sense for a video, how one frame of its video is drawn (`frame(result) -> uint8 RGB`);
the others carry the reason they are skipped for videos (`video_note`).

- `mpo`: CIPA DC-007 multi-picture JPEG, left then right, typed multi-view disparity
  (`mpo.py`; Pillow's writer leaves the second picture's type undefined).
- `jps`: one JPEG [H, 2W], cross-eyed order (the RIGHT view in the left half).
- `wiggle`: an animated GIF left -> right -> left with views synthesised between them
  from the disparity (`wiggle_frames`).
- `rgbd`: the left view beside its depth, [H, 2W, 3] PNG; depth is 8-bit gray, the
  disparity over `StereoResult.depth_range` with near (larger disparity) white.
- `html`: a self-contained viewer page (`viewer_page`).
- `anaglyph_dubois`, `anaglyph_optimized`, `anaglyph_gray`, `anaglyph_colour`: the pair
  re-encoded by the red-cyan operators of `core.mixtures` (`dubois`, `optimized`, `gray`,
  `anaglyph`).
"""

import dataclasses
import functools
import os
from typing import Callable, Dict, List, Optional, Tuple

import cv2
import numpy as np
from PIL import Image

from mixstereo_tf.cli import mpo
from mixstereo_tf.cli import viewer_page
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures

JPEG_QUALITY = 95
# Milliseconds each wiggle frame is shown (6 frames a cycle with 2 in-betweens).
WIGGLE_FRAME_MS = 110


@dataclasses.dataclass(frozen=True)
class StereoResult:
  """One recovered pair and what the formats draw from it.

  Attributes:
    left, right: uint8 RGB views [H, W, 3].
    disparity: float32 [H, W] signed pixels of the left view (left x matches right x - d).
    disparity_colour: uint8 RGB [H, W, 3], the colour-mapped disparity.
    depth_range: (low, high) disparity in pixels shown black .. white in depth images.
    mixture: the input image, uint8 RGB [H, W, 3] (the viewer page's before / after).
    icc_profile: the input's ICC profile, embedded in the formats that show the views'
      colours (MPO, JPS, anaglyphs, the viewer page's images); None: none (sRGB).
  """
  left: np.ndarray
  right: np.ndarray
  disparity: np.ndarray
  disparity_colour: np.ndarray
  depth_range: Tuple[float, float]
  mixture: Optional[np.ndarray] = None
  icc_profile: Optional[bytes] = None


@dataclasses.dataclass(frozen=True)
class StereoFormat:
  """How one `--output_format` is written.

  Attributes:
    write: (result, stem) -> the paths written; `stem` is `<output_dir>/<name>`.
    frame: result -> one video frame (uint8 RGB), None when the format makes no sense for
      a video.
    video_note: why the format is skipped for videos (frame is None).
    description: one line for help texts and the README.
  """
  write: Callable[[StereoResult, str], List[str]]
  frame: Optional[Callable[[StereoResult], np.ndarray]]
  video_note: str
  description: str


def depth_image(disparity: np.ndarray, low: float, high: float) -> np.ndarray:
  """uint8 [H, W] depth: disparity `low` (and below) black, `high` (and above, nearer)
  white, linear between; NaN black."""
  scaled = (np.nan_to_num(np.asarray(disparity, np.float32), nan=low) - low) / (high - low)
  return image_range.unit_to_u8(np.clip(scaled, 0.0, 1.0))


def rgbd(result: StereoResult) -> np.ndarray:
  """[H, 2W, 3] uint8: the left view, then its depth (`depth_image`) in gray."""
  depth = depth_image(result.disparity, *result.depth_range)
  return np.concatenate([result.left, np.repeat(depth[..., None], 3, axis=2)], axis=1)


def _background(disparity: np.ndarray, filled: np.ndarray) -> np.ndarray:
  """[H, W] per pixel, the smaller disparity of the nearest filled pixels left and right of
  it in its row (the one there is when one side has none; 0 in a row with none)."""
  height, width = disparity.shape
  columns = np.broadcast_to(np.arange(width), (height, width))
  before = np.maximum.accumulate(np.where(filled, columns, -1), axis=1)
  after = np.minimum.accumulate(np.where(filled, columns, width)[:, ::-1], axis=1)[:, ::-1]
  rows = np.arange(height)[:, None]
  inf = np.float32(np.inf)
  left = np.where(before >= 0, disparity[rows, np.maximum(before, 0)], inf)
  right = np.where(after < width, disparity[rows, np.minimum(after, width - 1)], inf)
  nearest = np.minimum(left, right)
  return np.where(np.isfinite(nearest), nearest, 0.0).astype(np.float32)


def synthesize_view(left: np.ndarray, right: np.ndarray, disparity: np.ndarray,
                    t: float) -> np.ndarray:
  """The view at viewpoint `t` (0 = left, 1 = right) of a pair.

  A scene point at left `x` with disparity `d` is seen there at `x - t d`: the left view
  is forward-warped there, the nearest point (largest disparity) winning where several
  land on one pixel; pixels nothing lands on (disoccluded background, cracks) take the
  right view warped by `(1 - t) d`, `d` the background's disparity beside the hole (the
  smaller of its row neighbours').

  Args:
    left, right: uint8 RGB views [H, W, 3].
    disparity: [H, W] signed pixels of the left view; NaN counts as 0.
    t: the viewpoint in [0, 1].

  Returns:
    uint8 RGB [H, W, 3].
  """
  height, width = disparity.shape
  d = np.nan_to_num(np.asarray(disparity, np.float32))
  rows, columns = np.mgrid[:height, :width]
  target = np.rint(columns - t * d).astype(np.int64)
  inside = (target >= 0) & (target < width)
  flat = (rows * width + target)[inside]
  source, depth = np.flatnonzero(inside), d[inside]
  order = np.lexsort((depth, flat))  # By target pixel, then nearest last.
  flat, source, depth = flat[order], source[order], depth[order]
  winner = np.append(flat[1:] != flat[:-1], True)
  out = np.zeros((height * width, 3), np.uint8)
  warped = np.zeros(height * width, np.float32)
  filled = np.zeros(height * width, bool)
  out[flat[winner]] = left.reshape(-1, 3)[source[winner]]
  warped[flat[winner]], filled[flat[winner]] = depth[winner], True
  filled, out = filled.reshape(height, width), out.reshape(height, width, 3)
  hole_disparity = _background(warped.reshape(height, width), filled)
  map_x = (columns - (1.0 - t) * hole_disparity).astype(np.float32)
  from_right = cv2.remap(right, map_x, rows.astype(np.float32), cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_REPLICATE)
  return np.where(filled[..., None], out, from_right)


def between_views(left: np.ndarray, right: np.ndarray, disparity: np.ndarray,
                  count: int = 2) -> List[np.ndarray]:
  """`count` views evenly spaced strictly between left and right (`synthesize_view`)."""
  return [synthesize_view(left, right, disparity, (k + 1) / (count + 1)) for k in range(count)]


def wiggle_frames(left: np.ndarray, right: np.ndarray, disparity: np.ndarray,
           between: int = 2) -> List[np.ndarray]:
  """One wiggle cycle: left, `between` synthesised views, right, the same views back
  (the next cycle starts at left again); uint8 RGB [H, W, 3] each."""
  steps = between_views(left, right, disparity, between)
  return [left] + steps + [right] + steps[::-1]


def reencode(mixture: str, left: np.ndarray, right: np.ndarray) -> np.ndarray:
  """The uint8 views encoded by the operator `mixture` of `core.mixtures`; uint8 RGB."""
  mixed = mixtures.mix(mixture, image_range.u8_to_signed(left),
                       image_range.u8_to_signed(right))
  return image_range.signed_to_u8(mixed.numpy())


def _anaglyph_frame(mixture: str, result: StereoResult) -> np.ndarray:
  return reencode(mixture, result.left, result.right)


def _pil(image: np.ndarray) -> Image.Image:
  return Image.fromarray(np.ascontiguousarray(image, np.uint8), 'RGB')


def _image_writer(suffix: str, draw: Callable[[StereoResult], np.ndarray],
                  views_colours: bool = False) -> Callable[[StereoResult, str], List[str]]:
  """A writer of one PNG `<stem><suffix>` holding `draw(result)`, with the views' colour
  profile when `views_colours` (the image shows only the views' colours)."""
  def write(result: StereoResult, stem: str) -> List[str]:
    path = stem + suffix
    _pil(draw(result)).save(path, 'PNG',
                            icc_profile=result.icc_profile if views_colours else None)
    return [path]
  return write


def _write_mpo(result: StereoResult, stem: str) -> List[str]:
  path = stem + '.mpo'
  with open(path, 'wb') as f:
    f.write(mpo.encode([result.left, result.right], JPEG_QUALITY, result.icc_profile))
  return [path]


def _write_jps(result: StereoResult, stem: str) -> List[str]:
  path = stem + '.jps'
  pair = np.concatenate([result.right, result.left], axis=1)  # Cross-eyed: right first.
  _pil(pair).save(path, 'JPEG', quality=JPEG_QUALITY, icc_profile=result.icc_profile)
  return [path]


def _write_wiggle(result: StereoResult, stem: str) -> List[str]:
  path = stem + '_wiggle.gif'
  images = [_pil(f) for f in wiggle_frames(result.left, result.right, result.disparity)]
  images[0].save(path, 'GIF', save_all=True, append_images=images[1:],
                 duration=WIGGLE_FRAME_MS, loop=0)
  return [path]


def _write_viewer(result: StereoResult, stem: str) -> List[str]:
  if result.mixture is None:
    raise ValueError(f'{stem}: the viewer page needs the input image (StereoResult.mixture).')
  path = stem + '_viewer.html'
  # A file name that is no UTF-8 (surrogates) is shown with replacement characters.
  title = os.fsencode(os.path.basename(stem)).decode('utf-8', 'replace')
  page = viewer_page.render(
      title=title, left=result.left,
      right=result.right, mixture=result.mixture, disparity=result.disparity_colour,
      anaglyph=reencode('dubois', result.left, result.right),
      between=between_views(result.left, result.right, result.disparity),
      frame_ms=WIGGLE_FRAME_MS, icc_profile=result.icc_profile)
  with open(path, 'w', encoding='utf-8') as f:
    f.write(page)
  return [path]


_NO_VIDEO = 'a still-image format'
# --output_format anaglyph_<name>: (operator of core.mixtures, description).
_ANAGLYPHS = {
    'dubois': ('dubois', 'Dubois least-squares red-cyan anaglyph: the least ghosting '
               'through real red-cyan glasses'),
    'optimized': ('optimized', "'optimized' red-cyan anaglyph (left red from 0.7 G + 0.3 B): "
                  'less retinal rivalry on red objects'),
    'gray': ('gray', 'gray red-cyan anaglyph: no colour, no rivalry'),
    'colour': ('anaglyph', 'full-colour red-cyan anaglyph (left R, right G and B)'),
    'red_blue': ('red_blue', 'gray red-blue anaglyph (left luma in R, right in B, G black): '
                 'for red-blue glasses'),
}


def _formats() -> Dict[str, StereoFormat]:
  formats = {
      'mpo': StereoFormat(_write_mpo, None, _NO_VIDEO,
                          'MPO (CIPA DC-007) left then right: 3D cameras, TVs, 3DS, '
                          'StereoPhoto Maker'),
      'jps': StereoFormat(_write_jps, None, _NO_VIDEO,
                          'JPS: one JPEG side by side, cross-eyed (right view on the left), '
                          'for JPS viewers'),
      'wiggle': StereoFormat(_write_wiggle, None, 'a wiggle of a moving video is not '
                             'viewable', 'animated GIF wiggling between the views (no '
                             'glasses; web pages, chats)'),
      'rgbd': StereoFormat(_image_writer('_rgbd.png', rgbd), rgbd, '',
                           'colour beside depth (near = white) in one PNG: depth-photo '
                           'viewers and 3D frames'),
      'html': StereoFormat(_write_viewer, None, 'the viewer page is made for one image',
                           'self-contained HTML viewer: views, disparity, wiggle, before / '
                           'after slider, cross / parallel / anaglyph'),
  }
  for name, (mixture, description) in _ANAGLYPHS.items():
    draw = functools.partial(_anaglyph_frame, mixture)
    formats[f'anaglyph_{name}'] = StereoFormat(
        _image_writer(f'_anaglyph_{name}.png', draw, views_colours=True), draw, '',
        description)
  return formats


FORMATS: Dict[str, StereoFormat] = _formats()
FORMAT_NAMES = tuple(FORMATS)


def check_formats(names) -> Tuple[str, ...]:
  """`names` as a tuple; ValueError naming an unknown or repeated format (and the field
  `OutputOptions.formats`, which `flags.flag_names` turns into --output_format)."""
  names = tuple(names)
  for name in names:
    if name not in FORMATS:
      raise ValueError(f'OutputOptions.formats: unknown output format {name!r}; valid: '
                       f'{", ".join(FORMAT_NAMES)}.')
    if names.count(name) > 1:
      raise ValueError(f'OutputOptions.formats: {name!r} is asked for more than once.')
  return names


def write_formats(result: StereoResult, stem: str, names) -> List[str]:
  """Writes each format of `names` for one image; returns every path written."""
  return [path for name in check_formats(names) for path in FORMATS[name].write(result, stem)]


def video_formats(names) -> Tuple[Tuple[str, ...], Dict[str, str]]:
  """(the formats of `names` drawn as videos, {skipped format: why})."""
  names = check_formats(names)
  drawn = tuple(name for name in names if FORMATS[name].frame is not None)
  return drawn, {name: f'not written for videos: {FORMATS[name].video_note}'
                 for name in names if name not in drawn}
