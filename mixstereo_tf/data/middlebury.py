"""Middlebury stereo readers: the 2001/2003 classic scenes and the 2014/2021 scenes.

Layouts detected in each scene folder (first match wins):
  2014/2021: `im0.png` (left), `im1.png` (right), `disp0.pfm` or `disp0GT.pfm` (left GT),
    optional `disp1.pfm` (right GT), `mask0nocc.png`, `calib.txt`; PFM floats in pixels
    (scale 1), inf = unknown.
  2001 Tsukuba: `scene1.row3.col3.ppm` (left), `scene1.row3.col4.ppm` (right),
    `truedisp.row3.col3.pgm` (GT, value / 16).
  2001/2003 classic: `im2` (left), `im6` (right) as .ppm/.png/.pgm, `disp2`/`disp6` as
    .pgm/.png; value / scale with the scale chosen by the folder name.
Official evaluation masks `nonocc.png`, `all.png` and `disc.png` in a scene folder become
the `nonocc_left` / `all_left` / `disc_left` masks.
"""

import os
from typing import Dict, List, Mapping, Optional, Tuple

from mixstereo_tf.data import records

# Classic-scene GT scales by lower-cased folder name (stored value / scale = pixels);
# other classic scenes (barn1, barn2, bull, poster, map, ...) use the 2001 default of 8.
CLASSIC_SCALES = {'tsukuba': 16.0, 'venus': 8.0, 'sawtooth': 8.0, 'cones': 4.0, 'teddy': 4.0}
DEFAULT_CLASSIC_SCALE = 8.0
TSUKUBA_SCALE = 16.0

# The scenes of the paper's tables (Middlebury 2001/2003, and 2006 Aloe), plus Motorcycle
# (2014), the real pair of this project's held-out `sample` set: evaluation data that
# training must not read (`is_evaluation_scene`).
EVALUATION_SCENES = ('tsukuba', 'venus', 'sawtooth', 'map', 'cones', 'teddy', 'aloe',
                     'motorcycle')

LAYOUTS = ('2014/2021: im0.png + im1.png (+ disp0.pfm or disp0GT.pfm)',
           '2001 Tsukuba: scene1.row3.col3.ppm + scene1.row3.col4.ppm '
           '(+ truedisp.row3.col3.pgm)',
           '2001/2003: im2 + im6 as .ppm/.png/.pgm (+ disp2/disp6 as .pgm/.png)')

_CLASSIC_IMAGE_EXTENSIONS = ('.ppm', '.png', '.pgm')
_CLASSIC_DISPARITY_EXTENSIONS = ('.pgm', '.png')


def _first_file(folder: str, names) -> Optional[str]:
  for name in names:
    path = os.path.join(folder, name)
    if os.path.isfile(path):
      return path
  return None


def _with_extensions(stem: str, extensions) -> List[str]:
  return [stem + ext for ext in extensions]


def _detect(folder: str) -> Optional[Tuple[Dict[str, Optional[str]], Optional[float]]]:
  """Returns (StereoSample file fields, scale or None = by folder name), or None."""
  def find(*names):
    return _first_file(folder, names)

  scale = None
  if find('im0.png') and find('im1.png'):
    files = {'left': find('im0.png'), 'right': find('im1.png'),
             'disparity_left': find('disp0.pfm', 'disp0GT.pfm'),
             'disparity_right': find('disp1.pfm'), 'calib': find('calib.txt')}
    scale = 1.0
  elif find('scene1.row3.col3.ppm') and find('scene1.row3.col4.ppm'):
    files = {'left': find('scene1.row3.col3.ppm'), 'right': find('scene1.row3.col4.ppm'),
             'disparity_left': find('truedisp.row3.col3.pgm')}
    scale = TSUKUBA_SCALE
  else:
    files = {'left': find(*_with_extensions('im2', _CLASSIC_IMAGE_EXTENSIONS)),
             'right': find(*_with_extensions('im6', _CLASSIC_IMAGE_EXTENSIONS)),
             'disparity_left': find(*_with_extensions('disp2', _CLASSIC_DISPARITY_EXTENSIONS)),
             'disparity_right': find(*_with_extensions('disp6',
                                                       _CLASSIC_DISPARITY_EXTENSIONS))}
    if not (files['left'] and files['right']):
      return None
  files['nonocc_left'] = find('nonocc.png', 'mask0nocc.png')
  files['all_left'] = find('all.png')
  files['disc_left'] = find('disc.png')
  return files, scale


def _scene_folders(data_dir: str) -> List[str]:
  """data_dir itself if it is a scene, else scene folders one or two levels below it."""
  if _detect(data_dir):
    return [data_dir]
  found = []
  for child in sorted(os.listdir(data_dir)):
    child_path = os.path.join(data_dir, child)
    if not os.path.isdir(child_path):
      continue
    if _detect(child_path):
      found.append(child_path)
      continue
    for grandchild in sorted(os.listdir(child_path)):
      path = os.path.join(child_path, grandchild)
      if os.path.isdir(path) and _detect(path):
        found.append(path)
  return found


def middlebury_samples(data_dir: str, scale_overrides: Optional[Mapping[str, float]] = None
                       ) -> List[records.StereoSample]:
  """Lists the Middlebury scenes under `data_dir`.

  `data_dir` may be one scene folder or hold scene folders, possibly one level deeper
  (`2014/Motorcycle-perfect/`). Folders matching no layout are skipped. Samples are named by
  their folder name (the path relative to data_dir when two folders share a name).

  Args:
    data_dir: a scene folder or a folder of scene folders.
    scale_overrides: {scene name: GT scale}, case-insensitive, replacing the layout's scale.

  Raises:
    ValueError: data_dir is not a folder, no scene found (lists the layouts expected), or
      an override names no scene found or is not positive.
  """
  if not os.path.isdir(data_dir):
    raise ValueError(f'Middlebury data_dir is not a folder: {data_dir}')
  data_dir = os.path.normpath(data_dir)
  folders = _scene_folders(data_dir)
  if not folders:
    raise ValueError(f'No Middlebury scene in {data_dir} or its subfolders; expected one of: '
                     + '; '.join(LAYOUTS))
  overrides = {k.lower(): float(v) for k, v in (scale_overrides or {}).items()}
  bad = [k for k, v in overrides.items() if not v > 0]
  if bad:
    raise ValueError(f'scale_overrides must be positive, got {bad}')
  basenames = [os.path.basename(f) for f in folders]
  unknown = set(overrides) - {b.lower() for b in basenames}
  if unknown:
    raise ValueError(f'scale_overrides name scenes not found in {data_dir}: '
                     f'{sorted(unknown)}; found {basenames}')
  samples = []
  for folder, base in zip(folders, basenames):
    files, scale = _detect(folder)
    if scale is None:
      scale = CLASSIC_SCALES.get(base.lower(), DEFAULT_CLASSIC_SCALE)
    scale = overrides.get(base.lower(), scale)
    name = base
    if basenames.count(base) > 1:
      name = os.path.relpath(folder, data_dir).replace(os.sep, '/')
    samples.append(records.StereoSample(name=name, disparity_scale=scale, source=folder,
                                        **files))
  return samples


def scene_key(name: str) -> str:
  """A sample name's scene: its last folder, lower case, before any '-' ('Adirondack' for
  'Adirondack-perfect', '2014/Adirondack-imperfect' or 'adirondack')."""
  return name.replace('\\', '/').rsplit('/', 1)[-1].lower().split('-')[0]


def is_evaluation_scene(name: str) -> bool:
  """True for a folder of an EVALUATION_SCENES scene: 'Teddy', 'cones', 'Aloe',
  'Motorcycle-perfect', 'MotorcycleE-imperfect', '2003/teddy' (case-insensitive)."""
  base = scene_key(name)
  return base in EVALUATION_SCENES or base.startswith('motorcycle')


def read_scene_list(path: str) -> List[str]:
  """The scene names of a list file: one per line; blank lines and '#' comments skipped."""
  with open(path, encoding='utf-8') as f:
    names = [line.split('#', 1)[0].strip() for line in f]
  return [name for name in names if name]


def select_scenes(samples: List[records.StereoSample], names: List[str],
                  list_path: str) -> Tuple[List[records.StereoSample], List[str]]:
  """(the samples of the listed scenes, the listed names found in no sample).

  A name selects every folder of its scene (`scene_key`: 'Adirondack' selects
  Adirondack-perfect and Adirondack-imperfect).

  Raises:
    ValueError: no sample is of a listed scene (naming the list and the scenes found).
  """
  wanted = {scene_key(n): n for n in names}
  chosen = [s for s in samples if scene_key(s.name) in wanted]
  if not chosen:
    raise ValueError(f'None of the {len(wanted)} scenes of {list_path} is among the '
                     f'{len(samples)} found: {", ".join(s.name for s in samples)}.')
  found = {scene_key(s.name) for s in chosen}
  return chosen, [n for key, n in wanted.items() if key not in found]
