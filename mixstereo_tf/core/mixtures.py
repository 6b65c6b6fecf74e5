"""Image composition operators `I = f(I_L, I_R)` (paper section 2) and anaglyph encodings.

Every operator is linear in the two views: on [0, 1] values, `I = A_L L + A_R R` per pixel
(3x3 matrices, rows = mixture channels R, G, B; columns = the view's R, G, B), clipped to
[0, 1] for the Dubois matrices, whose rows do not sum to one. The paper's three operators are
`anaglyph` (red-cyan colour), `diplopia` and `monocular`; the others are the anaglyph
encodings found in published images: gray, half-colour, 'optimized' and Dubois red-cyan,
and FFmpeg's `stereo3d` variants of green-magenta and amber-blue glasses (FACTS.md; FFmpeg's
integer coefficients equal these to 1/65536 and floor instead of round).

Operators take batched or unbatched float images in the network range [-1, 1]
(`[..., H, W, 3]`, RGB) and return the mixture in that range. Where every row of
[A_L | A_R] sums to one (all but Dubois and the two-channel anaglyphs) the map commutes
with the [0, 1] -> [-1, 1] normalisation and is applied directly, so channel copies are
exact; Dubois is applied to the gamma-encoded [0, 1] values (as anaglyph tools do) and
clipped, and the red-blue and red-green anaglyphs (FFmpeg arbg, argg) to [0, 1] values,
their empty channel black.

`MixtureSpec.left_channels` / `right_channels` ({view channel: mixture channel}) are the
channels copied unchanged, derived from the matrices; `eye_channels` says which mixture
channels mostly carry which view (what the classical matcher compares).
"""

import dataclasses
from typing import Callable, Dict, Mapping, Optional, Tuple

import numpy as np
import tensorflow as tf

from mixstereo_tf.core import image_range

Matrix = Tuple[Tuple[float, float, float], ...]

# ITU-R BT.601 luma weights, used by the gray and half-colour anaglyphs.
LUMA = (0.299, 0.587, 0.114)
_ZERO = ((0.0, 0.0, 0.0),) * 3
_I = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))

# Dubois (2009) least-squares red-cyan projection matrices; rows are output R, G, B.
DUBOIS_LEFT = ((0.437, 0.449, 0.164),
               (-0.062, -0.062, -0.024),
               (-0.048, -0.050, -0.017))
DUBOIS_RIGHT = ((-0.011, -0.032, -0.007),
                (0.377, 0.761, 0.009),
                (-0.026, -0.093, 1.234))

# FFmpeg stereo3d's Dubois matrices (integers / 65536 in its source): red-cyan `arcd` (its
# default output), green-magenta `agmd`, amber-blue `aybd` (amber over the left eye).
_FFMPEG_DUBOIS = {
    'red_cyan': (((29884, 32768, 11534), (-2621, -2490, -1049), (-983, -1376, -328)),
                 ((-2818, -5767, -131), (24773, 48103, -1180), (-4719, -7406, 80347))),
    'green_magenta': (((-4063, -10354, -2556), (18612, 43778, 9372), (-983, -1769, 1376)),
                      ((34669, 46203, 1573), (-1049, -983, -4260), (590, 4915, 61407))),
    'amber_blue': (((69599, -13435, 19595), (-1704, 59507, 4456), (-2490, -11338, 1442)),
                   ((-1048, -8061, -1114), (393, 4063, -1114), (6160, 12124, 59703))),
}


def _scaled(matrix) -> Matrix:
  return tuple(tuple(v / 65536.0 for v in row) for row in matrix)


def _rows(*rows) -> Matrix:
  """A matrix from per-mixture-channel rows: 'R'/'G'/'B' = that channel, 'Y' = luma,
  None = nothing of this view."""
  named = {'R': _I[0], 'G': _I[1], 'B': _I[2], 'Y': LUMA, None: (0.0, 0.0, 0.0)}
  return tuple(tuple(named[r]) if isinstance(r, (str, type(None))) else tuple(r)
               for r in rows)


@dataclasses.dataclass(frozen=True)
class MixtureSpec:
  """A named composition operator I = clip?(A_L L + A_R R) on [0, 1] values.

  Attributes:
    name: the operator's name, as given to `--mixture`.
    left_matrix, right_matrix: A_L, A_R (rows: mixture R, G, B; columns: view R, G, B).
    clip: clip the [0, 1] result (Dubois).
    family: glasses / kind: 'red_cyan', 'green_magenta', 'amber_blue', 'red_blue',
      'red_green', 'diplopia', 'monocular'.
    description: one line for help texts.
    served_as: the encoding an image of this one is unmixed as once `served` has filled
      its empty channel (red-blue, red-green: 'gray', the same two lumas), or None.
  """
  name: str
  left_matrix: Matrix
  right_matrix: Matrix
  clip: bool
  family: str
  description: str
  served_as: Optional[str] = None

  @property
  def fn(self) -> Callable[[tf.Tensor, tf.Tensor], tf.Tensor]:
    """`fn(left, right) -> mixture`, images in [-1, 1]."""
    return lambda left, right: _apply(self, left, right)

  def _copied(self, own: Matrix, other: Matrix) -> Dict[int, int]:
    return {list(row).index(1.0): c for c, (row, other_row) in enumerate(zip(own, other))
            if sorted(row) == [0.0, 0.0, 1.0] and not any(other_row)}

  @property
  def left_channels(self) -> Mapping[int, int]:
    """{left-view channel: mixture channel} copied unchanged."""
    return self._copied(self.left_matrix, self.right_matrix)

  @property
  def right_channels(self) -> Mapping[int, int]:
    """{right-view channel: mixture channel} copied unchanged."""
    return self._copied(self.right_matrix, self.left_matrix)

  @property
  def transmits_colour(self) -> bool:
    """False when the mixture holds only one colour combination of each view (gray
    anaglyphs: luminance only), so no view's colour can be recovered."""
    rows = np.concatenate([self.left_matrix, self.right_matrix])
    return bool(np.linalg.matrix_rank(rows[np.abs(rows).sum(1) > 0], tol=1e-6) > 1)

  @property
  def empty_channels(self) -> Tuple[int, ...]:
    """Mixture channels neither view fills (a red-blue anaglyph's G), black."""
    return tuple(c for c in range(3)
                 if not any(self.left_matrix[c]) and not any(self.right_matrix[c]))

  @property
  def is_anaglyph(self) -> bool:
    """True for the colour-filter encodings (each mixture channel mostly one view)."""
    return self.family not in ('diplopia', 'monocular')

  @property
  def eye_channels(self) -> Tuple[Tuple[int, ...], Tuple[int, ...]]:
    """(mixture channels mostly of the left view, those mostly of the right view), by the
    absolute weight of each row; anaglyphs only."""
    left = np.abs(np.asarray(self.left_matrix)).sum(axis=1)
    right = np.abs(np.asarray(self.right_matrix)).sum(axis=1)
    return (tuple(int(c) for c in np.flatnonzero(left > right)),
            tuple(int(c) for c in np.flatnonzero((right >= left) & (right > 0))))


def _apply(spec: MixtureSpec, left, right) -> tf.Tensor:
  left, right = tf.convert_to_tensor(left), tf.convert_to_tensor(right)
  a_left = tf.constant(spec.left_matrix, dtype=left.dtype)
  a_right = tf.constant(spec.right_matrix, dtype=left.dtype)
  rows = np.sum(spec.left_matrix, axis=1) + np.sum(spec.right_matrix, axis=1)
  unit = spec.clip or not np.allclose(rows, 1.0)  # The map needs [0, 1] values.
  if unit:
    left, right = image_range.signed_to_unit(left), image_range.signed_to_unit(right)
  # Row-vector form: mixture_c = sum_k A[c, k] * view_k.
  mixed = (tf.linalg.matvec(a_left, left[..., None, :]) +
           tf.linalg.matvec(a_right, right[..., None, :]))[..., 0, :]
  if unit:
    return image_range.unit_to_signed(tf.clip_by_value(mixed, 0.0, 1.0))
  return mixed


def _specs():
  half = ((0.5, 0.0, 0.0), (0.0, 0.5, 0.0), (0.0, 0.0, 0.5))
  yield MixtureSpec('anaglyph', _rows('R', None, None), _rows(None, 'G', 'B'), False,
                    'red_cyan', 'red-cyan colour anaglyph (the paper): R from left, G, B '
                    'from right (FFmpeg arcc)')
  yield MixtureSpec('diplopia', half, half, False, 'diplopia',
                    'double vision (the paper): (left + right) / 2')
  yield MixtureSpec('monocular', _I, _ZERO, False, 'monocular',
                    'monocular depth (the paper): the left image itself')
  yield MixtureSpec('gray', _rows('Y', None, None), _rows(None, 'Y', 'Y'), False, 'red_cyan',
                    'gray red-cyan anaglyph: R = Y(left), G = B = Y(right) (FFmpeg arcg)')
  yield MixtureSpec('half_color', _rows('Y', None, None), _rows(None, 'G', 'B'), False,
                    'red_cyan', 'half-colour red-cyan anaglyph: R = Y(left), G, B from right '
                    '(FFmpeg arch)')
  yield MixtureSpec('optimized', _rows((0.0, 0.7, 0.3), None, None), _rows(None, 'G', 'B'),
                    False, 'red_cyan', "'optimized' red-cyan anaglyph: R = 0.7 G_L + 0.3 B_L, "
                    'G, B from right')
  yield MixtureSpec('dubois', DUBOIS_LEFT, DUBOIS_RIGHT, True, 'red_cyan',
                    'Dubois (2009) least-squares red-cyan anaglyph (gamma-encoded values)')
  yield MixtureSpec('dubois_ffmpeg', *map(_scaled, _FFMPEG_DUBOIS['red_cyan']), True,
                    'red_cyan', "red-cyan Dubois anaglyph with FFmpeg's matrices (its "
                    'default output, arcd)')
  yield MixtureSpec('green_magenta', _rows(None, 'G', None), _rows('R', None, 'B'), False,
                    'green_magenta', 'green-magenta colour anaglyph: G from left, R, B from '
                    'right (FFmpeg agmc)')
  yield MixtureSpec('green_magenta_gray', _rows(None, 'Y', None), _rows('Y', None, 'Y'),
                    False, 'green_magenta', 'gray green-magenta anaglyph: G = Y(left), '
                    'R = B = Y(right) (FFmpeg agmg)')
  yield MixtureSpec('green_magenta_half', _rows(None, 'Y', None), _rows('R', None, 'B'),
                    False, 'green_magenta', 'half-colour green-magenta anaglyph: '
                    'G = Y(left), R, B from right (FFmpeg agmh)')
  yield MixtureSpec('green_magenta_dubois', *map(_scaled, _FFMPEG_DUBOIS['green_magenta']),
                    True, 'green_magenta', 'Dubois green-magenta anaglyph (FFmpeg agmd)')
  yield MixtureSpec('amber_blue', _rows('R', 'G', None), _rows(None, None, 'B'), False,
                    'amber_blue', 'amber-blue colour anaglyph (ColorCode 3-D): R, G from '
                    'left, B from right (FFmpeg aybc with the views exchanged)')
  yield MixtureSpec('amber_blue_gray', _rows('Y', 'Y', None), _rows(None, None, 'Y'), False,
                    'amber_blue', 'gray amber-blue anaglyph: R = G = Y(left), B = Y(right) '
                    '(FFmpeg aybg with the views exchanged)')
  yield MixtureSpec('amber_blue_half', _rows('R', 'G', None), _rows(None, None, 'Y'), False,
                    'amber_blue', 'half-colour amber-blue anaglyph: R, G from left, '
                    'B = Y(right) (FFmpeg aybh with the views exchanged)')
  yield MixtureSpec('red_blue', _rows('Y', None, None), _rows(None, None, 'Y'), False,
                    'red_blue', 'gray red-blue anaglyph: R = Y(left), B = Y(right), G empty '
                    '(FFmpeg arbg)', served_as='gray')
  yield MixtureSpec('red_green', _rows('Y', None, None), _rows(None, 'Y', None), False,
                    'red_green', 'gray red-green anaglyph: R = Y(left), G = Y(right), B empty '
                    '(FFmpeg argg)', served_as='gray')
  yield MixtureSpec('amber_blue_dubois', *map(_scaled, _FFMPEG_DUBOIS['amber_blue']), True,
                    'amber_blue', 'Dubois amber-blue anaglyph, amber over the left eye '
                    '(FFmpeg aybd)')


_SPECS: Dict[str, MixtureSpec] = {spec.name: spec for spec in _specs()}

MIXTURE_NAMES = tuple(_SPECS)
ANAGLYPH_NAMES = tuple(name for name, spec in _SPECS.items() if spec.is_anaglyph)
SERVED_ANAGLYPH_NAMES = tuple(name for name in ANAGLYPH_NAMES if not _SPECS[name].served_as)


def get_mixture(name: str) -> MixtureSpec:
  """Returns the operator called `name`; raises ValueError listing the valid names."""
  try:
    return _SPECS[name]
  except KeyError:
    raise ValueError(f'Unknown mixture {name!r}; valid mixtures are: '
                     f'{", ".join(MIXTURE_NAMES)}.') from None


def served_name(name: str) -> str:
  """The encoding an image of encoding `name` is unmixed as (`MixtureSpec.served_as`)."""
  return get_mixture(name).served_as or name


def served(image: np.ndarray, name: str) -> np.ndarray:
  """[..., 3] `image` of encoding `name` as its `served_name` encoding: each channel that
  neither view fills takes the right eye's channel (a red-blue anaglyph's G its B: the
  gray red-cyan anaglyph's G = B = Y(right)); `image` itself where nothing is empty."""
  spec = get_mixture(name)
  if not spec.served_as:
    return image
  image = np.array(image)
  image[..., list(spec.empty_channels)] = image[..., spec.eye_channels[1][:1]]
  return image


def mix(name: str, left, right) -> tf.Tensor:
  """Applies the operator called `name` to images in [-1, 1]; returns a tensor."""
  return get_mixture(name).fn(left, right)


def mix_double(left, right, weight: float) -> tf.Tensor:
  """A double image a L + (1 - a) R of images in [-1, 1], a = `weight` the left eye's
  share (the 'diplopia' operator is a = 1/2); returns a float32 tensor."""
  left, right = (tf.convert_to_tensor(image, tf.float32) for image in (left, right))
  return float(weight) * left + (1.0 - float(weight)) * right


def parse_names(text: str) -> Tuple[str, ...]:
  """'anaglyph' or a comma-separated list ('anaglyph,gray,dubois'); 'anaglyphs' stands for
  every anaglyph encoding unmixed as itself (not the two-channel ones, which are served as
  another: `served`; the recipes and shipped models that say 'anaglyphs' mean these).
  Raises ValueError naming an unknown name."""
  names = []
  for name in (n.strip() for n in text.split(',')):
    names.extend(SERVED_ANAGLYPH_NAMES if name == 'anaglyphs' else (get_mixture(name).name,))
  if not names:
    raise ValueError('Expected at least one mixture name.')
  return tuple(dict.fromkeys(names))


def mix_one_of(names: Tuple[str, ...], index: tf.Tensor, left, right) -> tf.Tensor:
  """Applies `names[index]` (a scalar int tensor) to images in [-1, 1].

  The operators are applied on [0, 1] values and clipped (the clip changes nothing for the
  non-Dubois ones), so one graph serves every element of a mixed-encoding batch.
  """
  specs = [get_mixture(name) for name in names]
  left, right = tf.convert_to_tensor(left), tf.convert_to_tensor(right)
  a_left = tf.gather(tf.constant([s.left_matrix for s in specs], left.dtype), index)
  a_right = tf.gather(tf.constant([s.right_matrix for s in specs], left.dtype), index)
  mixed = (tf.linalg.matvec(a_left, image_range.signed_to_unit(left)[..., None, :]) +
           tf.linalg.matvec(a_right, image_range.signed_to_unit(right)[..., None, :]))
  return image_range.unit_to_signed(tf.clip_by_value(mixed[..., 0, :], 0.0, 1.0))
