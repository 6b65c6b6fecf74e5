"""A stereo pair as an MPO file (CIPA DC-007 Multi-Picture Format, multi-view disparity).

Pillow's MPO writer marks the second picture's type 'Undefined' and writes no MP
attribute IFDs, so 3D cameras, TVs and the 3DS may not take its files as stereo pairs.
Here each view is a baseline JPEG (Pillow) with an APP2 'MPF' segment inserted after its
APP0 / APP1 segments: a little-endian TIFF header, then
  * first picture: the MP index IFD (MPFVersion '0100', NumberOfImages, one 16-byte MP
    entry per picture: attribute, size, offset, two dependent-image numbers), then its MP
    attribute IFD;
  * every picture: an MP attribute IFD (MPFVersion, MPIndividualNum 1..n, BaseViewpointNum
    1: the left view; ConvergenceAngle 0/1 degrees: a rectified pair's axes are parallel;
    BaselineLength unknown: 0xFFFFFFFF over 0xFFFFFFFF, as DC-007 marks unknown values).
MP entries: type 0x020002 (multi-frame disparity), the first picture flagged
representative (bit 29); sizes in bytes of each picture, offsets from the first picture's
MP endian field (0 for the first picture); pictures left to right.
"""

import io
import struct
from typing import List, Optional, Sequence

import numpy as np
from PIL import Image

DISPARITY_TYPE = 0x020002
REPRESENTATIVE = 1 << 29
_UNDEFINED, _LONG, _RATIONAL, _SRATIONAL = 7, 4, 5, 10
_UNKNOWN = struct.pack('<II', 0xFFFFFFFF, 0xFFFFFFFF)
_TIFF_HEADER = b'II*\x00' + struct.pack('<I', 8)


def _ifd(entries, start: int, next_ifd: int = 0) -> bytes:
  """An IFD at TIFF offset `start`: entries (tag, type, count, value bytes), values over
  4 bytes stored after it."""
  table, data = b'', b''
  after = start + 2 + 12 * len(entries) + 4
  for tag, kind, count, value in entries:
    if len(value) <= 4:
      table += struct.pack('<HHI', tag, kind, count) + value.ljust(4, b'\x00')
    else:
      table += struct.pack('<HHII', tag, kind, count, after + len(data))
      data += value
  return struct.pack('<H', len(entries)) + table + struct.pack('<I', next_ifd) + data


def _attributes(number: int, start: int) -> bytes:
  """Picture `number`'s (1-based) MP attribute IFD at TIFF offset `start`."""
  return _ifd([(0xB000, _UNDEFINED, 4, b'0100'), (0xB101, _LONG, 1, struct.pack('<I', number)),
               (0xB204, _LONG, 1, struct.pack('<I', 1)),
               (0xB205, _SRATIONAL, 1, struct.pack('<iI', 0, 1)),
               (0xB206, _RATIONAL, 1, _UNKNOWN)], start)


def _index(sizes: Sequence[int], offsets: Sequence[int]) -> bytes:
  """The MP index IFD at TIFF offset 8, followed by the first picture's attributes."""
  entries = b''.join(
      struct.pack('<IIIHH', DISPARITY_TYPE | (REPRESENTATIVE if i == 0 else 0), size,
                  offset, 0, 0) for i, (size, offset) in enumerate(zip(sizes, offsets)))
  fields = [(0xB000, _UNDEFINED, 4, b'0100'),
            (0xB001, _LONG, 1, struct.pack('<I', len(sizes))),
            (0xB002, _UNDEFINED, len(entries), entries)]
  attributes_at = 8 + 2 + 12 * len(fields) + 4 + len(entries)
  return _ifd(fields, 8, attributes_at) + _attributes(1, attributes_at)


def _insert_app2(jpeg: bytes, payload: bytes) -> bytes:
  """`jpeg` with an APP2 segment of `payload` after SOI and its leading APP0 / APP1."""
  at = 2
  while jpeg[at:at + 2] in (b'\xff\xe0', b'\xff\xe1'):
    at += 2 + struct.unpack('>H', jpeg[at + 2:at + 4])[0]
  segment = b'\xff\xe2' + struct.pack('>H', 2 + len(payload)) + payload
  return jpeg[:at] + segment + jpeg[at:]


def encode(views: Sequence[np.ndarray], quality: int,
           icc_profile: Optional[bytes] = None) -> bytes:
  """The MPO bytes of uint8 RGB `views` [H, W, 3], left to right (module docstring), each
  picture with `icc_profile` embedded when given."""
  jpegs: List[bytes] = []
  for view in views:
    buffer = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(view, np.uint8), 'RGB').save(
        buffer, 'JPEG', quality=quality, icc_profile=icc_profile)
    jpegs.append(buffer.getvalue())
  rest = [_insert_app2(jpeg, b'MPF\x00' + _TIFF_HEADER + _attributes(number, 8))
          for number, jpeg in enumerate(jpegs[1:], 2)]
  # The index's length does not depend on its values: sizes and offsets are filled in
  # once the first picture's length is known.
  placeholder = _insert_app2(jpegs[0], b'MPF\x00' + _TIFF_HEADER + _index(
      [0] * len(jpegs), [0] * len(jpegs)))
  endian_at = placeholder.index(b'MPF\x00' + _TIFF_HEADER) + 4
  sizes = [len(placeholder)] + [len(picture) for picture in rest]
  offsets = [0] + [sum(sizes[:i]) - endian_at for i in range(1, len(sizes))]
  first = _insert_app2(jpegs[0], b'MPF\x00' + _TIFF_HEADER + _index(sizes, offsets))
  return first + b''.join(rest)
