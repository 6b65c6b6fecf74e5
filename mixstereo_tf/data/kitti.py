"""KITTI readers: monodepth-style split lists (raw drives) and the stereo 2012/2015 sets.

A split list has one `left right` line per pair, paths relative to the dataset root. The
published lists name .jpg files (monodepth converted KITTI's PNGs); an unconverted download
holds .png files, so each entry also matches the same stem with the other extension.

Stereo 2012/2015 ground truth: uint16 PNG, disparity = value / 256, 0 = invalid. `disp_occ`
covers all pixels with ground truth and is the left disparity; `disp_noc` covers the
non-occluded ones and is recorded as the `nonocc_left` mask (`disparity_io.read_mask` reads a
16-bit file as "value > 0").
"""

import dataclasses
import glob
import os
import re
from typing import Dict, List, Optional

from absl import logging

from mixstereo_tf.data import image_io
from mixstereo_tf.data import records

KITTI_DISPARITY_SCALE = 256.0
# Pairs skipped for missing files that get a warning of their own (the rest: a count).
_WARNED_PAIRS = 5

# Raw-drive folders start with the recording date, which is also the calibration folder.
_DATE_FOLDER = re.compile(r'^\d{4}_\d{2}_\d{2}$')
# .../<drive>/image_02/data/<frame>.<ext> in the raw-drive layout.
_RAW_IMAGE = re.compile(r'^(?P<drive>.*)[/\\]image_0[23][/\\]data[/\\](?P<frame>[^/\\]+)\.\w+$')

# version -> (left images, right images, all-pixel GT, non-occluded GT).
_STEREO_FOLDERS = {
    '2015': ('image_2', 'image_3', 'disp_occ_0', 'disp_noc_0'),
    '2012': ('colored_0', 'colored_1', 'disp_occ', 'disp_noc'),
}


@dataclasses.dataclass
class SplitList:
  """The pairs of a split list.

  Attributes:
    samples: one StereoSample per usable line, in file order.
    skipped: one message per line dropped by `skip_bad_pairs`.
    skipped_lines: the (1-based) list line number of each entry of `skipped`.
  """
  samples: List[records.StereoSample]
  skipped: List[str]
  skipped_lines: List[int]


def sample_name(path: str) -> str:
  """A short name from an image path: `<drive>/<frame>` for raw drives, else the stem.

  E.g. `2011_09_26/2011_09_26_drive_0002_sync/image_02/data/0000000069.jpg` ->
  `2011_09_26_drive_0002_sync/0000000069`; `training/image_2/000000_10.jpg` -> `000000_10`.
  """
  match = _RAW_IMAGE.match(path)
  if match:
    return f'{os.path.basename(match.group("drive"))}/{match.group("frame")}'
  return os.path.splitext(os.path.basename(path))[0]


def velodyne_path(left_path: str) -> str:
  """The Velodyne scan of a raw-drive left image.

  `.../<drive>/image_02/data/0000000069.jpg` -> `.../<drive>/velodyne_points/data/0000000069.bin`.

  Raises:
    ValueError: the path is not in the raw-drive `image_02/data/` layout.
  """
  match = _RAW_IMAGE.match(left_path)
  if not match:
    raise ValueError(f'Not a KITTI raw image path (expected .../image_02/data/<frame>.<ext>): '
                     f'{left_path}')
  return os.path.join(match.group('drive'), 'velodyne_points', 'data',
                      match.group('frame') + '.bin')


def _calib_folder(data_dir: str, relative_left: str,
                  cache: Dict[str, Optional[str]]) -> Optional[str]:
  """The date folder holding calib_*.txt for a raw-drive entry, or None."""
  first = relative_left.replace('\\', '/').split('/', 1)[0]
  if first not in cache:
    folder = os.path.join(data_dir, first)
    cache[first] = folder if _DATE_FOLDER.match(first) and os.path.isdir(folder) else None
  return cache[first]


def read_split_list(list_path: str, data_dir: str, skip_bad_pairs: bool = False,
                    check_files: bool = True) -> SplitList:
  """Reads a `left right` split list into StereoSamples.

  Blank lines and lines starting with `#` are ignored. Samples get `source =
  'list_path:line'`, a name from `sample_name`, and for raw-drive entries `calib` = the
  date folder when it exists and `velodyne` = the frame's scan (for the Eigen evaluation).

  Args:
    list_path: the list file.
    data_dir: the root the list's paths are relative to.
    skip_bad_pairs: log and record entries whose files are missing instead of failing.
    check_files: resolve each path with `image_io.find_image` (.jpg <-> .png); when False
      the paths are kept as written and checked only on loading.

  Raises:
    ValueError: unreadable or empty list, a line without exactly two fields, or (without
      skip_bad_pairs) a missing file; messages name the list file, line and path.
  """
  if not os.path.isfile(list_path):
    raise ValueError(f'Split list not found: {list_path}')
  with open(list_path, encoding='utf-8') as f:
    lines = f.read().splitlines()
  samples, skipped, skipped_lines, calib_cache = [], [], [], {}
  for number, line in enumerate(lines, start=1):
    fields = line.split()
    if not fields or fields[0].startswith('#'):
      continue
    source = f'{list_path}:{number}'
    if len(fields) != 2:
      raise ValueError(f"{source}: expected 'left right', got {line.strip()!r}")
    left, right = (os.path.join(data_dir, field) for field in fields)
    if check_files:
      try:
        left, right = image_io.find_image(left), image_io.find_image(right)
      except ValueError as e:
        message = f'{source}: {e}'
        if not skip_bad_pairs:
          raise ValueError(message) from None
        if len(skipped) < _WARNED_PAIRS:
          logging.warning('Skipping pair: %s', message)
        skipped.append(message)
        skipped_lines.append(number)
        continue
    samples.append(records.StereoSample(
        name=sample_name(fields[0]), left=left, right=right,
        calib=_calib_folder(data_dir, fields[0], calib_cache),
        velodyne=velodyne_path(left) if _RAW_IMAGE.match(left) else None, source=source))
  if not samples:
    what = f' ({len(skipped)} skipped for missing files)' if skipped else ''
    raise ValueError(f"{list_path}: no pairs{what}; expected lines 'left right' with paths "
                     f'relative to {data_dir}')
  return SplitList(samples=samples, skipped=skipped, skipped_lines=skipped_lines)


def line_ranges(numbers: List[int]) -> str:
  """Increasing line numbers as ranges: [2, 3, 4, 7] -> '2-4, 7'."""
  spans = []
  for number in numbers:
    if spans and number == spans[-1][1] + 1:
      spans[-1][1] = number
    else:
      spans.append([number, number])
  return ', '.join(str(a) if a == b else f'{a}-{b}' for a, b in spans)


def _split_folder(data_dir: str, split: str, left_folder: str) -> str:
  """Accepts the dataset root (holding `split/`) or the split folder itself."""
  if os.path.isdir(os.path.join(data_dir, split, left_folder)):
    return os.path.join(data_dir, split)
  return data_dir


def kitti_stereo_samples(data_dir: str, version: str = '2015',
                         split: str = 'training') -> List[records.StereoSample]:
  """Lists the `_10` frames of KITTI stereo 2015 or 2012 with their ground truth.

  Only `_10` frames form the benchmark pairs (`_11` is the next frame in time). Ground
  truth is attached when its file exists (the testing split has none).

  Args:
    data_dir: the dataset root (holding `training/`) or the split folder itself.
    version: '2015' (image_2, image_3, disp_occ_0, disp_noc_0) or '2012' (colored_0,
      colored_1, disp_occ, disp_noc).
    split: the split folder name under the root.

  Raises:
    ValueError: unknown version, no frames found (names the folders expected), or a left
      frame without its right image.
  """
  if version not in _STEREO_FOLDERS:
    raise ValueError(f'Unknown KITTI stereo version {version!r}; valid: '
                     f'{", ".join(_STEREO_FOLDERS)}')
  left_dir, right_dir, occ_dir, noc_dir = _STEREO_FOLDERS[version]
  root = _split_folder(data_dir, split, left_dir)
  lefts = sorted(p for p in glob.glob(os.path.join(root, left_dir, '*_10.*'))
                 if os.path.splitext(p)[1].lower() in ('.png', '.jpg'))
  if not lefts:
    raise ValueError(f'No KITTI {version} frames in {data_dir}: expected '
                     f'{split}/{left_dir}/*_10.png (or {left_dir}/*_10.png) with '
                     f'{right_dir}/, {occ_dir}/ and {noc_dir}/ beside it')
  samples = []
  for left in lefts:
    name = os.path.splitext(os.path.basename(left))[0]
    right = image_io.find_image(os.path.join(root, right_dir, os.path.basename(left)))
    gt = {}
    for key, folder in (('disparity_left', occ_dir), ('nonocc_left', noc_dir)):
      path = os.path.join(root, folder, name + '.png')
      if os.path.isfile(path):
        gt[key] = path
    samples.append(records.StereoSample(
        name=name, left=left, right=right, disparity_scale=KITTI_DISPARITY_SCALE,
        source=left, **gt))
  return samples
