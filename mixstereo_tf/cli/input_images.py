"""Reading an input image file as viewers show it, and what its header says.

One look at the header (`header`: a single Pillow open) gives the EXIF orientation, the
colour profile, whether colour is stored at half resolution and how many images the file
holds. A file holding more than the one
picture the tools unmix is named, not read silently:
  * an animated GIF, WebP or PNG (APNG) is refused: only its first frame would be read;
  * an MPO stereo pair (a 3D camera's, typed `Multi-Frame Image: (Disparity)`) or a HEIF
    stereo pair (a phone's spatial photo: a 'ster' entity group) is refused: it holds the
    two views already, there is nothing to unmix. A camera's JPEG whose other image is a
    preview (typed 'Large Thumbnail') is an ordinary photo;
  * a TIFF with several full-resolution pages (a scanner's multi-page file) has its first
    page unmixed, with a warning giving the count (reduced-resolution pages, a TIFF's
    thumbnails, are not counted); a HEIF holding several images (a burst) its primary one.
"""

import contextlib
import dataclasses
import os
from typing import Dict, Iterator, Optional, Tuple

from absl import logging
import numpy as np
from PIL import Image

from mixstereo_tf.core import image_range
from mixstereo_tf.data import image_io

# EXIF orientation (tag 0x0112) -> the stored pixels as viewers show them (the TIFF / EXIF
# values; 1 is as stored).
_ORIENTATIONS = {2: lambda a: a[:, ::-1], 3: lambda a: a[::-1, ::-1], 4: lambda a: a[::-1],
                 5: lambda a: a.transpose(1, 0, 2), 6: lambda a: np.rot90(a, -1),
                 7: lambda a: np.rot90(a, 2).transpose(1, 0, 2), 8: lambda a: np.rot90(a, 1)}
_ANIMATED = ('GIF', 'WEBP', 'PNG')  # Pillow's formats that animate (APNG reads as PNG).
_MPO_STEREO = 'Multi-Frame Image: (Disparity)'  # Pillow's name of MP type 0x020002.
_TIFF_REDUCED = 1  # NewSubfileType (tag 254) bit 0: a reduced-resolution copy.


@dataclasses.dataclass(frozen=True)
class ImageHeader:
  """What an image file's header says (the defaults: a file Pillow cannot read).

  Attributes:
    orientation: EXIF orientation 1-8 (1: as stored).
    icc_profile: the embedded RGB ICC profile (a phone's Display P3, Adobe RGB), None for
      none (sRGB, as viewers assume) and for profiles of other colour spaces (gray, CMYK),
      which RGB outputs cannot carry (PNG forbids it, colour managers refuse it). The views
      keep the input's pixel values, so they are in its colour space and carry its profile.
    frames: images the file holds (an animation's frames, an MPO's images, TIFF pages).
    stereo_views: images of an MPO marked as views of a stereo pair, or of a HEIF stereo
      pair group (`image_io.heif_stereo_views`); 0 for other files.
    pages: a TIFF's full-resolution pages, a HEIF's images (1 for other files).
    chroma_halved: colour stored at half the width or less (`image_io.chroma_halved`).
    format: Pillow's name of the file's format ('JPEG', 'MPO', 'HEIF', ...), whatever
      its extension says; '' for a file Pillow cannot read.
  """
  orientation: int = 1
  icc_profile: Optional[bytes] = None
  frames: int = 1
  stereo_views: int = 0
  pages: int = 1
  chroma_halved: bool = False
  format: str = ''


def _tiff_pages(image: Image.Image, frames: int) -> int:
  pages = 0
  for index in range(frames):
    image.seek(index)
    pages += not int(image.tag_v2.get(254, 0)) & _TIFF_REDUCED
  image.seek(0)
  return max(1, pages)


def _stereo_views(image: Image.Image, frames: int) -> int:
  """The views of a stereo MPO: its pictures typed as views (`_MPO_STEREO`, as 3D cameras
  write), or, where none is typed a preview, all of them when the second has the first's
  size (Pillow writes 'Undefined'); 0 for other files."""
  entries = (getattr(image, 'mpinfo', None) or {}).get(0xB002, ())
  types = [entry.get('Attribute', {}).get('MPType', '') for entry in entries]
  if types.count(_MPO_STEREO) > 1:
    return types.count(_MPO_STEREO)
  if image.format != 'MPO' or frames < 2 or any('Thumbnail' in kind for kind in types):
    return 0
  size = image.size
  image.seek(1)
  same = image.size == size
  image.seek(0)
  return frames if same else 0


def header(path: str) -> ImageHeader:
  """The `ImageHeader` of an image file, from one Pillow open."""
  try:
    with Image.open(path) as image:
      orientation = image.getexif().get(0x0112, 1)
      profile = image.info.get('icc_profile') or None
      halved = image_io.chroma_halved_of(image, path)
      frames = int(getattr(image, 'n_frames', 1))
      stereo = (image_io.heif_stereo_views(path) if image.format == 'HEIF' and frames > 1
                else _stereo_views(image, frames))
      pages = (_tiff_pages(image, frames) if image.format == 'TIFF' and frames > 1 else
               frames if image.format == 'HEIF' else 1)
  except (OSError, ValueError, SyntaxError, EOFError):
    return ImageHeader()
  return ImageHeader(orientation if orientation in _ORIENTATIONS else 1,
                     profile if profile and profile[16:20] == b'RGB ' else None,
                     frames, stereo, pages, halved, image.format or '')


def _refuse_other_images(path: str, found: ImageHeader) -> None:
  """ValueError naming a file whose other images would be lost (see the module's text)."""
  if found.stereo_views > 1:
    views = found.stereo_views
    kind = (f'a HEIF stereo pair (a spatial photo of {views} views)'
            if found.format == 'HEIF' else f'an MPO stereo pair ({views} views)')
    raise ValueError(f'{path} is {kind}: it holds the two views already, not a mixture of '
                     'them; there is nothing to unmix.')
  if found.frames > 1 and found.format in _ANIMATED:
    raise ValueError(f'{path} is an animated image ({found.frames} frames); only its first '
                     'frame would be read. Convert it to a video to unmix every frame, e.g. '
                     f'ffmpeg -i {path} -pix_fmt yuv420p out.mp4')
  if found.pages > 1 and found.format == 'HEIF':
    logging.warning('%s holds %d images: only its primary image is unmixed. Convert each '
                    'to a PNG to unmix the others.', path, found.pages)
  elif found.pages > 1:
    logging.warning('%s holds %d pages: only the first is unmixed. Split the file (e.g. '
                    'tiffsplit, or convert to one PNG per page) to unmix the others.',
                    path, found.pages)


def read_upright(path: str, found: Optional[ImageHeader] = None, deep: bool = False,
                 alpha: bool = False) -> Tuple[np.ndarray, int, Tuple[str, ...]]:
  """(uint8 RGB [H, W, 3] as viewers show the file, its EXIF orientation, what reading it
  at 8 bits in RGB dropped: `image_io.dropped`'s 'bit_depth', 'alpha'): a phone's
  portrait photo of an anaglyph has its eyes side by side only once turned. Gray and
  alpha images are converted (`image_io.as_rgb8`); ValueError naming bad files, animated
  images and stereo pairs. `found`: the file's `header`, when already read. `deep`: a
  16-bit file is read as uint16 RGB (`image_io.as_rgb`), and 'bit_depth' is not lost;
  `alpha`: an alpha channel less than opaque somewhere is kept, last (RGBA), and 'alpha'
  is not lost."""
  found = found or header(path)
  _refuse_other_images(path, found)
  raw = image_io.read_raw(path)
  kept = ('bit_depth',) * deep + ('alpha',) * alpha
  lost = tuple(key for key in image_io.dropped(raw) if key not in kept)
  image = image_io.as_rgb(raw, path, alpha)
  image = image if deep else image_range.eight_bits(image)
  del raw
  if found.orientation == 1 or found.format == 'TIFF':
    return image, found.orientation, lost  # TIFF decoders apply the tag (`read_raw`).
  return (np.ascontiguousarray(_ORIENTATIONS[found.orientation](image)), found.orientation,
          lost)


def read_image(path: str, deep: bool = False) -> np.ndarray:
  """The image of `read_upright`."""
  return read_upright(path, deep=deep)[0]


def truncated_jpeg(path: str) -> bool:
  """Whether `path` is a JPEG without its end marker (FF D9, trailing zeros allowed): a file
  cut short, whose missing rows the decoder fills with gray and only reports on stderr."""
  with open(path, 'rb') as f:
    if f.read(2) != b'\xff\xd8':
      return False
    f.seek(max(0, os.path.getsize(path) - 4096))
    return not f.read().rstrip(b'\x00').endswith(b'\xff\xd9')


_CUT_SHORT = 'the JPEG file ends before its end marker'  # `truncated_jpeg`'s note.


@contextlib.contextmanager
def blaming_truncation(path: str) -> Iterator[None]:
  """ValueErrors raised inside (e.g. unmixing the image) say so when `path` is a JPEG cut
  short (`truncated_jpeg`): its missing rows are gray, which detection crops as a border."""
  try:
    yield
  except ValueError as error:
    if not truncated_jpeg(path):
      raise
    raise ValueError(f'{error} {path} may be the cause: {_CUT_SHORT} (a file cut short; '
                     'its missing rows are gray).') from error


# What reading an image at 8 bits in RGB dropped (`image_io.dropped`) -> its info note.
_DROPPED = {'bit_depth': ('stores 16-bit samples: its views were made and written at 8 '
                          'bits (only anaglyph and double-image views are made at 16)'),
            'alpha': ('has an alpha channel: it was dropped, the transparent pixels were '
                      'unmixed as stored and the views are opaque')}


def depth_lost(image: np.ndarray, view: np.ndarray) -> Tuple[str, ...]:
  """('bit_depth',) when a 16-bit `image` (`read_upright(deep=True)`) gave 8-bit views (a
  single view's: only anaglyph and double-image views are made at 16 bits), else ()."""
  return ('bit_depth',) if image.dtype == np.uint16 and view.dtype != np.uint16 else ()


def reading_notes(path: str, found: ImageHeader, lost: Tuple[str, ...]) -> Dict[str, str]:
  """Info notes (logged as warnings) of what the input file held that the outputs do not:
  rows past a cut JPEG's end, pages after the first, and `read_upright`'s `lost`: 16-bit
  samples, transparency."""
  notes = {}
  for key in lost:
    notes[key] = f'{path} {_DROPPED[key]}'
    logging.warning('%s.', notes[key])
  if truncated_jpeg(path):
    notes['warning'] = f'{_CUT_SHORT}: rows may be missing'
    logging.warning('%s: %s.', path, notes['warning'])
  if found.pages > 1:  # Logged by read_upright.
    notes['warning'] = f'the file holds {found.pages} pages: only the first was unmixed'
  return notes
