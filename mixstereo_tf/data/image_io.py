"""Readers for the image, disparity and mask files of the stereo datasets.

Everything returns NumPy arrays in the project's reader conventions: images uint8 RGB
`[H, W, 3]`; ground-truth disparity float32 `[H, W]` in pixels with 0 = unknown, plus a
boolean validity mask. Bad input raises `ValueError` naming the file.
"""

import os
import re
from typing import Dict, Optional, Tuple

import cv2
import numpy as np
from PIL import Image
from PIL import JpegImagePlugin

from mixstereo_tf.data import records

# Extensions `find_image` swaps: monodepth's KITTI lists name .jpg files, downloads hold .png.
_SWAP_EXTENSIONS = ('.jpg', '.png')


def _check_file(path: str) -> None:
  """A ValueError naming `path` when it is a folder or no file (a relative path: with the
  folder it was looked for in)."""
  if os.path.isdir(path):
    raise ValueError(f'{path} is a folder, not an image file.')
  if not os.path.isfile(path):
    where = '' if os.path.isabs(path) else f' (relative to the current folder {os.getcwd()})'
    raise ValueError(f'File not found: {path}{where}')


# Pillow modes -> the mode whose pixels `_read_raw` returns (8/16-bit gray, RGB, RGBA).
_PILLOW_MODES = {'L': 'L', 'LA': 'LA', 'I;16': 'I;16', 'RGB': 'RGB', 'RGBA': 'RGBA'}
TIFF_EXTENSIONS = ('.tif', '.tiff')


def _read_with_pillow(path: str) -> Optional[np.ndarray]:
  """The pixels in OpenCV's channel order, or None when Pillow cannot decode the file."""
  try:
    with Image.open(path) as image:
      image = image.convert(_PILLOW_MODES.get(image.mode, 'RGB'))
      array = np.asarray(image)
  except (OSError, ValueError, SyntaxError):
    return None
  if array.ndim == 3 and array.shape[2] >= 3:  # RGB(A) -> BGR(A), as cv2.imread.
    array = np.concatenate([array[..., 2::-1], array[..., 3:]], axis=2)
  return np.ascontiguousarray(array)


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


def _read_raw(path: str) -> np.ndarray:
  """cv2.imread(IMREAD_UNCHANGED), else Pillow, with a ValueError naming a missing or
  unreadable file. Both decoders apply a TIFF's orientation tag themselves (OpenCV 5.0
  fails on the tags that transpose, 5-8: Pillow reads those); other formats' EXIF
  orientation is left to the caller (`cli/media.py`)."""
  _check_file(path)
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
    raise ValueError(f'Cannot decode image file: {path}')
  return array


def eight_bits(array: np.ndarray) -> np.ndarray:
  """16-bit samples as uint8: round(v / 257) (65535 -> 255, 257 k -> k)."""
  return ((array.astype(np.uint32) + 128) // 257).astype(np.uint8)


def read_image(path: str) -> np.ndarray:
  """Reads any 8/16-bit gray, gray+alpha, BGR or BGRA image as uint8 RGB `[H, W, 3]`.

  16-bit values v become round(v / 257) (65535 -> 255, 257 k -> k).

  Raises:
    ValueError: missing or undecodable file, or an unsupported sample type (e.g. float).
  """
  array = _read_raw(path)
  if array.dtype == np.uint16:
    array = eight_bits(array)
  elif array.dtype != np.uint8:
    raise ValueError(f'Unsupported image sample type {array.dtype} in {path}')
  if array.ndim == 2:
    array = array[:, :, None]
  channels = array.shape[2]
  if channels in (1, 2):  # Gray (+ alpha): replicate the gray channel.
    return np.repeat(array[:, :, :1], 3, axis=2)
  if channels in (3, 4):  # BGR (+ alpha): drop alpha, reorder to RGB.
    return np.ascontiguousarray(array[:, :, 2::-1])
  raise ValueError(f'Unsupported channel count {channels} in {path}')


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
  return _lossy_webp(path)


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


def read_pfm(path: str) -> np.ndarray:
  """Reads a PFM file as float32 `[H, W]` ('Pf') or `[H, W, 3]` ('PF'), top row first.

  PFM stores rows bottom-to-top; a negative header scale means little-endian samples.
  Values are returned unchanged (inf/NaN included).

  Raises:
    ValueError: missing file, malformed header or truncated data.
  """
  _check_file(path)
  with open(path, 'rb') as f:
    data = f.read()
  # The header is three whitespace-separated fields after the magic: width, height, scale,
  # ended by exactly one whitespace byte before the binary samples.
  match = re.match(rb'(P[Ff])\s+(\d+)\s+(\d+)\s+([-+0-9.eE]+)\s', data)
  if match is None:
    raise ValueError(f'Malformed PFM header in {path}')
  channels = 3 if match.group(1) == b'PF' else 1
  width, height = int(match.group(2)), int(match.group(3))
  try:
    scale = float(match.group(4))
  except ValueError:
    raise ValueError(f'Malformed PFM scale {match.group(4)!r} in {path}') from None
  count = width * height * channels
  body = data[match.end():]
  if len(body) < 4 * count:
    raise ValueError(f'Truncated PFM data in {path}: expected {count} floats for '
                     f'{width}x{height}x{channels}, found {len(body) // 4}')
  dtype = '<f4' if scale < 0 else '>f4'
  array = np.frombuffer(body, dtype=dtype, count=count).astype(np.float32)
  shape = (height, width) if channels == 1 else (height, width, 3)
  return np.ascontiguousarray(np.flipud(array.reshape(shape)))


def _single_channel(array: np.ndarray, path: str) -> np.ndarray:
  """Returns a 2-D map; 3/4-channel files are accepted only when their colours are equal."""
  if array.ndim == 2:
    return array
  if array.ndim == 3 and array.shape[2] == 1:
    return array[:, :, 0]
  if array.ndim == 3 and np.all(array[:, :, :3] == array[:, :, :1]):
    return array[:, :, 0]
  raise ValueError(f'Expected a single-channel map in {path}, got shape {array.shape}')


def read_disparity(path: str, scale: float = 1.0) -> Tuple[np.ndarray, np.ndarray]:
  """Reads ground-truth disparity in pixels: stored value / `scale`.

  Formats: .pfm floats (Middlebury 2014, Scene Flow; scale normally 1); 16-bit PNG (KITTI,
  scale 256); 8-bit PNG/PGM (Middlebury 2001/2003, scale 16/8/4). Stored 0, negative, inf
  and NaN values are unknown.

  Returns:
    (disparity float32 [H, W] with unknown pixels set to 0, valid bool [H, W]).

  Raises:
    ValueError: missing/unreadable file, more than one channel, scale <= 0, or an 8-bit
      file with a scale above 16 (a KITTI map saved as 8 bits).
  """
  if not scale > 0:
    raise ValueError(f'Disparity scale must be positive for {path}, got {scale}')
  if path.lower().endswith('.pfm'):
    stored = read_pfm(path)
  else:
    stored = _read_raw(path)
    if stored.dtype not in (np.uint8, np.uint16):
      raise ValueError(f'Unsupported disparity sample type {stored.dtype} in {path}')
    if stored.dtype == np.uint8 and scale > 16:  # Middlebury's 8-bit maps use 4, 8 or 16.
      raise ValueError(f'{path} is an 8-bit image, but disparities stored as {scale:g} d '
                       'need 16 bits (KITTI PNGs are uint16): it would read as at most '
                       f'{255 / scale:.2f} px.')
  stored = _single_channel(stored, path).astype(np.float32)
  valid = np.isfinite(stored) & (stored > 0)
  disparity = np.where(valid, stored / np.float32(scale), 0).astype(np.float32)
  return disparity, valid


def read_mask(path: str) -> np.ndarray:
  """Reads an evaluation mask as bool `[H, W]`.

  8-bit masks: True only where white (255). This matches the Middlebury 2001/2003 masks
  (`nonocc.png`, `all.png`: 255 = evaluated) and Middlebury 2014 `mask0nocc.png` (255 =
  non-occluded, 128 = occluded, 0 = invalid). 16-bit files are KITTI disparity maps used as
  masks (`disp_noc` as the non-occluded mask): True where the value is > 0. Colour masks are
  white only where all colour channels are 255.
  """
  array = _read_raw(path)
  if array.ndim == 3:
    array = array[:, :, :3].min(axis=2)
  if array.dtype == np.uint16:
    return array > 0
  if array.dtype == np.uint8:
    return array == 255
  raise ValueError(f'Unsupported mask sample type {array.dtype} in {path}')


def _check_shape(array: np.ndarray, shape: Tuple[int, int], path: str, what: str) -> None:
  if array.shape[:2] != shape:
    raise ValueError(f'{what} {path} is {array.shape[1]}x{array.shape[0]} but the left '
                     f'image is {shape[1]}x{shape[0]}')


def _read_gt(path: Optional[str], scale: float,
             shape: Tuple[int, int]) -> Tuple[np.ndarray, np.ndarray]:
  if path is None:
    return np.zeros(shape, np.float32), np.zeros(shape, bool)
  disparity, valid = read_disparity(path, scale)
  _check_shape(disparity, shape, path, 'disparity')
  return disparity, valid


def _read_optional_mask(path: Optional[str], shape: Tuple[int, int]) -> np.ndarray:
  if path is None:
    return np.ones(shape, bool)
  mask = read_mask(path)
  _check_shape(mask, shape, path, 'mask')
  return mask


def _load(sample: records.StereoSample) -> Dict[str, np.ndarray]:
  left_path, right_path = find_image(sample.left), find_image(sample.right)
  left, right = read_image(left_path), read_image(right_path)
  if left.shape != right.shape:
    raise ValueError(f'left {left_path} is {left.shape[1]}x{left.shape[0]} but right '
                     f'{right_path} is {right.shape[1]}x{right.shape[0]}')
  shape = left.shape[:2]
  disparity_left, valid_left = _read_gt(sample.disparity_left, sample.disparity_scale, shape)
  disparity_right, valid_right = _read_gt(sample.disparity_right, sample.disparity_scale,
                                          shape)
  valid_left &= _read_optional_mask(sample.all_left, shape)
  nonocc_left = valid_left & _read_optional_mask(sample.nonocc_left, shape)
  # Unlike the other masks, a missing discontinuity mask selects no pixel: treating every
  # pixel as 'near a discontinuity' would make a disc column repeat the all-pixel one.
  disc_left = (valid_left & _read_optional_mask(sample.disc_left, shape)
               if sample.disc_left else np.zeros(shape, bool))
  disparity_left = np.where(valid_left, disparity_left, 0).astype(np.float32)
  return {
      'left': left,
      'right': right,
      'disparity_left': disparity_left,
      'disparity_right': disparity_right,
      'valid_left': valid_left,
      'valid_right': valid_right,
      'nonocc_left': nonocc_left,
      'disc_left': disc_left,
  }


def fit_factor(largest: float, max_disparity: int) -> int:
  """The smallest integer k >= 1 with largest / k <= max_disparity - 1."""
  if max_disparity < 2:
    raise ValueError(f'fit_disparity must be >= 2, got {max_disparity}.')
  return max(1, int(np.ceil(largest / (max_disparity - 1.0))))


def _block(array: np.ndarray, factor: int, reduce) -> np.ndarray:
  """`reduce` over k x k blocks of [H, W, ...] (the last H % k rows, W % k columns go)."""
  h, w = array.shape[0] // factor, array.shape[1] // factor
  blocks = array[:h * factor, :w * factor].reshape(h, factor, w, factor, *array.shape[2:])
  return reduce(blocks, axis=(1, 3))


def shrink(loaded: Dict[str, np.ndarray], factor: int) -> Dict[str, np.ndarray]:
  """A loaded pair `factor` times smaller: views by k x k means; ground truth / k where the
  whole block is known (else 0, unknown); masks true where the whole block is."""
  if factor == 1:
    return loaded
  out = {key: np.rint(_block(loaded[key], factor, np.mean)).astype(np.uint8)
         for key in ('left', 'right')}
  for view in ('left', 'right'):
    valid = _block(loaded[f'valid_{view}'], factor, np.all)
    mean = _block(loaded[f'disparity_{view}'].astype(np.float64), factor, np.mean)
    out[f'valid_{view}'] = valid
    out[f'disparity_{view}'] = np.where(valid, mean / factor, 0).astype(np.float32)
  out['nonocc_left'] = _block(loaded['nonocc_left'], factor, np.all) & out['valid_left']
  out['disc_left'] = _block(loaded['disc_left'], factor, np.any) & out['valid_left']
  return out


def load_file_sample(sample: records.StereoSample) -> Dict[str, np.ndarray]:
  """Loads a file-backed sample into arrays with exactly the keys of `records.LOADED_KEYS`.

  valid_left = GT known AND inside `all_left` (when given); nonocc_left = valid_left AND
  `nonocc_left` (when given), else valid_left; disc_left = valid_left AND `disc_left` (when
  given), else all False. Disparity outside the validity masks is 0. With
  `sample.fit_disparity`, the pair is then shrunk to fit that many levels (`shrink`).
  Missing ground truth gives zero disparity and all-False masks. Image paths go through
  `find_image`, so a .jpg entry also finds a .png file.

  Raises:
    ValueError: a file is missing or unreadable, or sizes differ; the message names the
      file(s) and `sample.source`.
  """
  try:
    loaded = _load(sample)
    if sample.fit_disparity:
      largest = max(float(loaded['disparity_left'].max()),
                    float(loaded['disparity_right'].max()))
      loaded = shrink(loaded, fit_factor(largest, sample.fit_disparity))
    return loaded
  except ValueError as e:
    raise ValueError(f'{sample.source or sample.name}: {e}') from None
