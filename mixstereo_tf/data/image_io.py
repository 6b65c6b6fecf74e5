"""Readers and writers of image files: the stereo datasets' views and the inputs of the CLIs.

Images are NumPy arrays, uint8 RGB `[H, W, 3]` (`read_image`); `read_raw` keeps a file's
own depth and channels for the ground-truth readers (`disparity_io`). Bad input raises
`ValueError` naming the file.
"""

import os
import zlib
from typing import Optional, Tuple

import cv2
import numpy as np
from PIL import features
from PIL import Image
from PIL import JpegImagePlugin
import pillow_heif

from mixstereo_tf.core import image_range

# HEIF / HEIC (phones' default photo format) through Pillow: pillow-heif decodes them and
# turns them upright by their own transforms (the EXIF orientation it leaves says 1).
pillow_heif.register_heif_opener()

# Extensions `find_image` swaps: monodepth's KITTI lists name .jpg files, downloads hold .png.
_SWAP_EXTENSIONS = ('.jpg', '.png')


def check_file(path: str) -> None:
  """A ValueError naming `path` when it is a folder or no file (a relative path: with the
  folder it was looked for in)."""
  if os.path.isdir(path):
    raise ValueError(f'{path} is a folder, not an image file.')
  if not os.path.isfile(path):
    where = '' if os.path.isabs(path) else f' (relative to the current folder {os.getcwd()})'
    raise ValueError(f'File not found: {path}{where}')


# Pillow modes -> the mode whose pixels `read_raw` returns (8/16-bit gray, RGB, RGBA).
_PILLOW_MODES = {'L': 'L', 'LA': 'LA', 'I;16': 'I;16', 'RGB': 'RGB', 'RGBA': 'RGBA'}


def _read_with_pillow(path: str) -> Optional[np.ndarray]:
  """The pixels in OpenCV's channel order, or None when Pillow cannot decode the file; a
  HEIF of more than 8 bits at 16 (`_deep_heif`)."""
  try:
    with Image.open(path) as image:
      if image.format == 'HEIF' and image.info.get('bit_depth', 8) > 8:
        array = _deep_heif(path)
      else:
        array = np.asarray(image.convert(_PILLOW_MODES.get(image.mode, 'RGB')))
  except (OSError, ValueError, SyntaxError):
    return None
  if array.ndim == 3 and array.shape[2] >= 3:  # RGB(A) -> BGR(A), as cv2.imread.
    array = np.concatenate([array[..., 2::-1], array[..., 3:]], axis=2)
  return np.ascontiguousarray(array)


def _deep_heif(path: str) -> np.ndarray:
  """A HEIF of 10 or 12 bits as uint16 RGB(A), its samples scaled to 0-65535 (pillow-heif
  gives them shifted left, 1023 -> 65472)."""
  heif = pillow_heif.open_heif(path, convert_hdr_to_8bit=False)
  bits = heif.info.get('bit_depth', 10)
  samples = np.asarray(heif).astype(np.uint32) >> (16 - bits)
  return ((samples * 65535 + (2 ** bits - 1) // 2) // (2 ** bits - 1)).astype(np.uint16)


def _utf8(path: str) -> bool:
  """Whether OpenCV may be given `path`: a name that is no UTF-8 (Latin-1 from an old share,
  held as surrogates) crashed cv2.imread and cv2.imwrite with a segmentation fault; such
  files are read and written as bytes."""
  try:
    path.encode('utf-8')
  except UnicodeEncodeError:
    return False
  return True


def write_with_opencv(path: str, array: np.ndarray) -> bool:
  """cv2.imwrite(path, array) (BGR; the format from the extension), also for names that are
  no UTF-8 (`_utf8`); whether it was written."""
  if _utf8(path):
    return cv2.imwrite(path, array)
  encoded, data = cv2.imencode(os.path.splitext(path)[1] or '.png', array)
  if not encoded:
    return False
  try:
    data.tofile(path)
  except OSError:
    return False
  return True


def add_png_icc(path: str, icc_profile: bytes) -> None:
  """Embeds `icc_profile` in the PNG file at `path` as its iCCP chunk (after IHDR; PNG 1.2,
  section 4.2.2.4: name, NUL, method 0, zlib data), for PNGs that OpenCV wrote (16-bit RGB,
  which Pillow cannot write); ValueError naming a file that is no PNG."""
  with open(path, 'rb') as f:
    data = f.read()
  if data[:8] != b'\x89PNG\r\n\x1a\n' or data[12:16] != b'IHDR':
    raise ValueError(f'Cannot embed a colour profile: {path} is no PNG file')
  end = 8 + 12 + int.from_bytes(data[8:12], 'big')  # Length, type, data, CRC.
  body = b'iCCP' + b'ICC profile\0\0' + zlib.compress(icc_profile)
  chunk = (len(body) - 4).to_bytes(4, 'big') + body + zlib.crc32(body).to_bytes(4, 'big')
  with open(path, 'wb') as f:
    f.write(data[:end] + chunk + data[end:])


def read_raw(path: str) -> np.ndarray:
  """cv2.imread(IMREAD_UNCHANGED), else Pillow, with a ValueError naming a missing or
  unreadable file. Both decoders apply a TIFF's orientation tag themselves (OpenCV 5.0
  fails on the tags that transpose, 5-8: Pillow reads those); other formats' EXIF
  orientation is left to the caller (`cli/media.py`)."""
  check_file(path)
  # IMREAD_UNCHANGED keeps 16-bit depth and ignores EXIF rotation (which would break the
  # stereo geometry); palette PNGs are still expanded to BGR by the decoder. OpenCV's own
  # log is silenced meanwhile: its "can't read data" ERROR for a file Pillow then reads
  # (such a TIFF) looked like a failure.
  level = cv2.utils.logging.getLogLevel()
  cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
  try:
    array = cv2.imread(path, cv2.IMREAD_UNCHANGED) if _utf8(path) else cv2.imdecode(
        np.fromfile(path, np.uint8), cv2.IMREAD_UNCHANGED)
  finally:
    cv2.utils.logging.setLogLevel(level)
  if array is None:
    array = _read_with_pillow(path)
  if array is None:
    why = (' (neither this OpenCV nor this Pillow reads AVIF: newer versions of both do)'
           if path.lower().endswith('.avif') and not features.check('avif') else '')
    raise ValueError(f'Cannot decode image file: {path}{why}')
  return array


def read_image(path: str) -> np.ndarray:
  """Reads any 8/16-bit gray, gray+alpha, BGR or BGRA image as uint8 RGB `[H, W, 3]`
  (`as_rgb8` of `read_raw`).

  Raises:
    ValueError: missing or undecodable file, or an unsupported sample type (e.g. float).
  """
  return as_rgb8(read_raw(path), path)


def as_rgb8(array: np.ndarray, path: str) -> np.ndarray:
  """A `read_raw` array as uint8 RGB `[H, W, 3]`: 16-bit values v become round(v / 257)
  (65535 -> 255, 257 k -> k), gray is replicated, alpha dropped (`dropped` names what
  went); ValueError naming `path` for other sample types and channel counts."""
  return image_range.eight_bits(as_rgb(array, path))


def as_rgb(array: np.ndarray, path: str, alpha: bool = False) -> np.ndarray:
  """`as_rgb8` at the array's own depth: uint8 or uint16 RGB `[H, W, 3]`; with `alpha`, an
  image whose alpha `dropped` would name is RGBA `[H, W, 4]` (its alpha last)."""
  if array.dtype not in (np.uint8, np.uint16):
    raise ValueError(f'Unsupported image sample type {array.dtype} in {path}')
  if array.ndim == 2:
    array = array[:, :, None]
  channels = array.shape[2]
  if channels not in (1, 2, 3, 4):
    raise ValueError(f'Unsupported channel count {channels} in {path}')
  # Gray (+ alpha): the gray channel replicated; BGR (+ alpha): reordered to RGB.
  order = [0, 0, 0] if channels < 3 else [2, 1, 0]
  if alpha and 'alpha' in dropped(array):
    order.append(channels - 1)
  return np.ascontiguousarray(array[:, :, order])


def dropped(array: np.ndarray) -> Tuple[str, ...]:
  """What `as_rgb8` loses of a `read_raw` array: 'bit_depth' (16-bit samples kept at 8
  bits) and 'alpha' (the transparency of a gray+alpha or BGRA image with any pixel less
  than opaque; an alpha channel that is opaque everywhere loses nothing)."""
  lost = ('bit_depth',) if array.dtype == np.uint16 else ()
  channels = array.shape[2] if array.ndim == 3 else 1
  if channels in (2, 4) and array[..., -1].min() < np.iinfo(array.dtype).max:
    lost += ('alpha',)
  return lost


def chroma_halved(path: str) -> bool:
  """Whether an image file stores its colour at half the width or less: a YCbCr JPEG with
  4:2:0 or 4:2:2 sampling (Pillow's, OpenCV's, phones' and browsers' default), or a lossy
  WebP (always 4:2:0). False for other files and for files that do not open."""
  try:
    with Image.open(path) as image:
      return chroma_halved_of(image, path)
  except (OSError, ValueError, SyntaxError):
    return False


def chroma_halved_of(image: Image.Image, path: str) -> bool:
  """`chroma_halved` of the file at `path`, already open as `image`."""
  if image.format == 'JPEG':
    return JpegImagePlugin.get_sampling(image) in (1, 2)
  if image.format == 'HEIF':
    return image.info.get('chroma') in (420, 422)
  if image.format == 'AVIF':
    return _av1_halved(path)
  return _lossy_webp(path)


def heif_stereo_views(path: str) -> int:
  """The images of a HEIF stereo pair (an iPhone spatial photo: a left and a right eye's
  picture linked by a 'ster' entity group, HEIF 23008-12 6.8.2, in the 'grpl' box of the
  first 1 MiB); 0 where the file has no such group."""
  with open(path, 'rb') as f:
    head = f.read(1 << 20)
  at = head.find(b'grpl')
  if at < 4:
    return 0
  end = min(len(head), at - 4 + int.from_bytes(head[at - 4:at], 'big'))
  child = at + 4
  while child + 20 <= end:  # EntityToGroupBox: size, type, version and flags, id, count.
    size = int.from_bytes(head[child:child + 4], 'big')
    if head[child + 4:child + 8] == b'ster':
      return int.from_bytes(head[child + 16:child + 20], 'big')
    if size < 8:
      return 0
    child += size
  return 0


def _av1_halved(path: str) -> bool:
  """Whether an AVIF's AV1 sequence (its 'av1C' box, AV1-ISOBMFF 2.3.3) stores colour at
  half the width (chroma_subsampling_x); False where the box is not in the first 64 KiB."""
  with open(path, 'rb') as f:
    head = f.read(1 << 16)
  at = head.find(b'av1C')
  return at >= 0 and len(head) > at + 6 and bool(head[at + 6] & 0x08)


def _lossy_webp(path: str) -> bool:
  """Whether a RIFF/WEBP file's image chunk is lossy VP8 (not lossless VP8L)."""
  with open(path, 'rb') as f:
    head = f.read(12)
    if head[:4] != b'RIFF' or head[8:12] != b'WEBP':
      return False
    while True:
      chunk = f.read(8)
      if len(chunk) < 8:
        return False
      if chunk[:4] in (b'VP8 ', b'VP8L'):
        return chunk[:4] == b'VP8 '
      size = int.from_bytes(chunk[4:], 'little')
      f.seek(size + (size & 1), os.SEEK_CUR)


def find_image(path: str) -> str:
  """Returns `path` if it exists, else the same stem with the other of .jpg / .png.

  Raises:
    ValueError: neither exists; the message names the path and the alternative tried.
  """
  if os.path.isfile(path):
    return path
  stem, ext = os.path.splitext(path)
  tried = [path]
  if ext.lower() in _SWAP_EXTENSIONS:
    for other in _SWAP_EXTENSIONS:
      if other != ext.lower():
        candidate = stem + other
        tried.append(candidate)
        if os.path.isfile(candidate):
          return candidate
  raise ValueError(f'Image not found: {path} (tried {", ".join(tried)})')
