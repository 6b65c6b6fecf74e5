"""The split lists shipped with the package (`data_lists/` of the repository).

`pip install .` installs the repository's top-level `data_lists/` as package data
`mixstereo_tf/data_lists/` (setup.py); a source checkout reads the repository's copy. Both
hold e.g. `kitti/eigen_test_files.txt`.
"""

import os

_PACKAGE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Installed package data first, then the source checkout's top-level folder.
_ROOTS = (os.path.join(_PACKAGE, 'data_lists'),
          os.path.join(os.path.dirname(_PACKAGE), 'data_lists'))


def resolve(path: str) -> str:
  """A split list path as given when it exists, else a list shipped with the package.

  Args:
    path: a file path, or a name relative to `data_lists/` such as
      'kitti/eigen_test_files.txt' (a leading 'data_lists/' is accepted).

  Raises:
    ValueError: neither exists; the message names the places tried.
  """
  if os.path.isfile(path):
    return path
  relative = path[len('data_lists/'):] if path.startswith('data_lists/') else path
  tried = [path]
  if not os.path.isabs(relative):
    for root in _ROOTS:
      candidate = os.path.join(root, relative)
      if os.path.isfile(candidate):
        return candidate
      tried.append(candidate)
  raise ValueError(f'Split list not found: {path} (tried {", ".join(tried)}).')
