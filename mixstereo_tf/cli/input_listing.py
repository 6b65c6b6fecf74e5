"""Listing the inputs of the tools: an image, a video, a folder or a glob pattern, each
input named for its outputs, and the output folder checked before anything is written.
"""

import collections
import dataclasses
import glob
import os
import tempfile
from typing import Collection, Dict, Iterable, Iterator, List, Optional, Sequence

from absl import logging

IMAGE_EXTENSIONS = ('.png', '.jpg', '.jpeg', '.jfif', '.bmp', '.ppm', '.pgm', '.pnm',
                    '.tif', '.tiff', '.webp', '.gif', '.heic', '.heif', '.hif', '.avif')
VIDEO_EXTENSIONS = ('.mp4', '.m4v', '.avi', '.mov', '.mkv', '.webm', '.ts', '.m2ts', '.mts',
                    '.mpg', '.mpeg', '.wmv', '.flv')


@dataclasses.dataclass(frozen=True)
class MediaItem:
  """One input: an image or a video file; `name` prefixes its outputs, unique in a run."""
  path: str
  is_video: bool
  name: str


def _extension(path: str) -> str:
  return os.path.splitext(path)[1].lower()


def output_names(paths: Sequence[str],
                 earlier: Optional[Dict[str, str]] = None) -> List[str]:
  """Output-name prefixes for input paths, distinct so no input overwrites another's files.

  The file stem, unless several inputs share it (`a.png` and `a.jpg`): then stem + '_' +
  extension (`a_png`, `a_jpg`). A name still taken (the same file name in two folders of a
  glob, or another input's stem) gets '_2', '_3', ... in input order. Names are compared
  case-insensitively, so outputs also stay apart on case-insensitive file systems.
  `earlier` ({real path: name}, `info_file.Earlier.names`): the names an earlier run into
  the output folder gave; an input keeps its own, and no other input takes one, so that a
  rerun over a grown archive neither renames nor overwrites earlier results.
  """
  earlier = earlier or {}
  kept = [earlier.get(os.path.realpath(path)) for path in paths]
  stems = [os.path.splitext(os.path.basename(path))[0] for path in paths]
  shared = collections.Counter(stem.casefold() for stem in stems)
  wanted = [stem if shared[stem.casefold()] == 1 else f'{stem}_{os.path.splitext(path)[1][1:]}'
            for stem, path in zip(stems, paths)]
  reserved = {name.casefold() for name in wanted}
  taken = {name.casefold() for name in earlier.values()}
  names = []
  for name, keep in zip(wanted, kept):
    if keep is not None:
      names.append(keep)
      continue
    unique, number = name, 1
    # A numbered name must not take a name another input wants as it is.
    while unique.casefold() in taken or (number > 1 and unique.casefold() in reserved):
      number += 1
      unique = f'{name}_{number}'
    taken.add(unique.casefold())
    names.append(unique)
  return names


def iter_inputs(spec: str, earlier: Optional[Dict[str, str]] = None,
                skip: Collection[str] = ()) -> Iterator[MediaItem]:
  """Expands an input specification into items, without reading them.

  Args:
    spec: an image path, a video path (`VIDEO_EXTENSIONS`), a folder (its images and
      videos, sorted by name; other files and subfolders ignored, with a note) or a glob
      pattern (matching images and videos, sorted; `**` matches any depth of folders).
      Items are named by `output_names` (with `earlier`, the names an earlier run gave).
    skip: real paths never taken from a folder or pattern (`info_file.Earlier.outputs`:
      what earlier runs wrote into an output folder inside the input tree), with a note.

  Raises:
    ValueError: nothing exists at `spec`, or the folder / pattern holds no usable file.
  """
  if os.path.isdir(spec):
    paths = _folder_media(spec)
  elif os.path.isfile(spec):
    paths = [spec]
  elif glob.has_magic(spec):
    paths = _matching(spec)
    if not paths and '[' in spec:  # 'Box [1998]/**/*': brackets of a folder's name.
      paths = _matching(spec.replace('[', '[[]'))
    if not paths:
      raise ValueError(f'No images or videos match the pattern {spec}')
  else:
    raise ValueError(f'Input not found: {spec}')
  kept = [path for path in paths if path == spec or os.path.realpath(path) not in skip]
  if len(kept) < len(paths):
    logging.info('%s: %d file(s) that earlier runs wrote into the output folder are not '
                 'inputs.', spec, len(paths) - len(kept))
  if not kept:
    raise ValueError(f'{spec} holds only results of earlier runs, no input.')
  for path, name in zip(kept, output_names(kept, earlier)):
    yield MediaItem(path, _extension(path) in VIDEO_EXTENSIONS, name)


def _matching(pattern: str) -> List[str]:
  """The images and videos `pattern` matches (`**`: any depth), each file once (`_once`)."""
  return _once(p for p in glob.glob(pattern, recursive=True) if os.path.isfile(p)
               and _extension(p) in IMAGE_EXTENSIONS + VIDEO_EXTENSIONS)


def _once(paths: Iterable[str]) -> List[str]:
  """`paths` sorted, each real file once, under its shortest path: `**` follows links to
  folders, and a link to a parent made every file an input dozens of times (renaming the
  real files' results), with a note."""
  paths = sorted(paths, key=lambda path: (path.count(os.sep), path))
  unique = {}
  for path in paths:
    unique.setdefault(os.path.realpath(path), path)
  if len(unique) < len(paths):
    logging.info('%d path(s) reach files already listed (through links): each file is one '
                 'input.', len(paths) - len(unique))
  return sorted(unique.values())


def _folder_media(folder: str) -> List[str]:
  """A folder's images and videos, sorted by name; subfolders are not searched (noted)."""
  names = sorted(os.listdir(folder))
  paths = [os.path.join(folder, name) for name in names
           if _extension(name) in IMAGE_EXTENSIONS + VIDEO_EXTENSIONS
           and os.path.isfile(os.path.join(folder, name))]
  subfolders = sum(os.path.isdir(os.path.join(folder, name)) for name in names)
  hint = (f"; {subfolders} subfolder(s) not searched: give '{os.path.join(folder, '**', '*')}'"
          ' to include them') if subfolders else ''
  if not paths:
    raise ValueError(f'No images or videos ({" ".join(IMAGE_EXTENSIONS + VIDEO_EXTENSIONS)}) '
                     f'in folder {folder}{hint}')
  if subfolders:
    logging.info('%s: %d image(s) and video(s)%s.', folder, len(paths), hint)
  return paths


def prepare_output_dir(items: Sequence[MediaItem], output_dir: str) -> None:
  """Creates `output_dir` once nothing of the run can be lost by writing into it.

  Every output of an item named n is `n_*` or `n.*` in `output_dir`
  (`media.write_image_outputs`, `stereo_formats`, the video jobs), so an input file in that
  folder whose name starts with another item's `n_` could be overwritten before it is read
  (`pic_left.png` by `pic.png`'s left view): refused, naming both.

  Raises:
    ValueError: `output_dir` is an existing file, cannot be created or written into, or
      holds such an input.
  """
  if os.path.exists(output_dir) and not os.path.isdir(output_dir):
    raise ValueError(f'The output folder --output_dir={output_dir} is an existing file, '
                     'not a folder.')
  folder = os.path.realpath(output_dir)
  inside = [item for item in items if os.path.dirname(os.path.realpath(item.path)) == folder]
  for item in inside:
    file_name = os.path.basename(item.path).casefold()
    for other in items:
      if file_name.startswith(other.name.casefold() + '_'):
        raise ValueError(
            f'--output_dir={output_dir} holds the input {item.path}, which the outputs of '
            f'{other.path} (named {other.name}_*) could overwrite before it is read; write '
            'the results to another folder (or, if it is a result of a run stopped before '
            f'its end, remove {os.path.join(output_dir, other.name)}_* not listed by an '
            'info file).')
  try:
    os.makedirs(output_dir, exist_ok=True)
  except OSError as e:  # Read-only, a file on the way, '' ...
    raise ValueError(f'Cannot create the output folder --output_dir={output_dir!r}: '
                     f'{e.strerror or e}.') from None
  try:  # Before any input is unmixed: a folder nothing can be written into fails now.
    with tempfile.TemporaryFile(dir=output_dir):
      pass
  except OSError as e:
    raise ValueError(f'Cannot write into the output folder --output_dir={output_dir!r}: '
                     f'{e.strerror or e}.') from None
