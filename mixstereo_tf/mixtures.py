"""Image composition operators `I = f(I_L, I_R)` (paper section 2).

Every operator takes batched or unbatched float images in the network range [-1, 1]
(`[..., H, W, 3]`, RGB) and returns the mixture in the same range and shape.

Operators that are affine combinations whose weights sum to one per output channel (channel
selection, averaging, luminance) commute with the [0, 1] -> [-1, 1] normalisation, so they
are applied directly. The Dubois matrices do not sum to one and clip, so `dubois` maps to
[0, 1], applies them to the gamma-encoded values (as most anaglyph tools do) and maps back.

Each operator also states which channels of which view survive unchanged in the mixture
(`MixtureSpec.left_channels` / `right_channels`, as {view_channel: mixture_channel}); colour
restoration (`ops/colour_restore.py`) rebuilds a view's missing channels from the other view.
"""

import dataclasses
from typing import Callable, Dict, Mapping, Tuple

import tensorflow as tf

# ITU-R BT.601 luma weights, used by the gray and half-colour anaglyphs.
_LUMA = (0.299, 0.587, 0.114)

# Dubois (2009) least-squares red-cyan projection matrices; rows are output R, G, B.
DUBOIS_LEFT = ((0.437, 0.449, 0.164),
               (-0.062, -0.062, -0.024),
               (-0.048, -0.050, -0.017))
DUBOIS_RIGHT = ((-0.011, -0.032, -0.007),
                (0.377, 0.761, 0.009),
                (-0.026, -0.093, 1.234))


@dataclasses.dataclass(frozen=True)
class MixtureSpec:
  """A named composition operator and what of each view survives in it.

  Attributes:
    name: the operator's name, as given to `--mixture`.
    fn: `fn(left, right) -> mixture`, images in [-1, 1].
    left_channels: {left-view channel: mixture channel} copied unchanged.
    right_channels: {right-view channel: mixture channel} copied unchanged.
    description: one line for help texts.
  """
  name: str
  fn: Callable[[tf.Tensor, tf.Tensor], tf.Tensor]
  left_channels: Mapping[int, int]
  right_channels: Mapping[int, int]
  description: str

  @property
  def is_channel_anaglyph(self) -> bool:
    """True when each view keeps at least one exact channel (colour restoration applies)."""
    return bool(self.left_channels) and bool(self.right_channels)


def _channels(image: tf.Tensor) -> Tuple[tf.Tensor, tf.Tensor, tf.Tensor]:
  return image[..., 0:1], image[..., 1:2], image[..., 2:3]


def _luma(image: tf.Tensor) -> tf.Tensor:
  r, g, b = _channels(image)
  return _LUMA[0] * r + _LUMA[1] * g + _LUMA[2] * b


def anaglyph(left: tf.Tensor, right: tf.Tensor) -> tf.Tensor:
  """The paper's red-cyan anaglyph: R from the left view, G and B from the right."""
  return tf.concat([left[..., 0:1], right[..., 1:3]], axis=-1)


def diplopia(left: tf.Tensor, right: tf.Tensor) -> tf.Tensor:
  """The paper's double-vision model `I = (I_L + I_R) / 2`."""
  return 0.5 * (left + right)


def monocular(left: tf.Tensor, right: tf.Tensor) -> tf.Tensor:
  """Monocular depth as a mixture, `I = I_L` (paper section 5)."""
  del right  # The right view only supervises.
  return tf.identity(left)


def gray_anaglyph(left: tf.Tensor, right: tf.Tensor) -> tf.Tensor:
  """Gray anaglyph: R = Y(L), G = B = Y(R)."""
  y_right = _luma(right)
  return tf.concat([_luma(left), y_right, y_right], axis=-1)


def half_color_anaglyph(left: tf.Tensor, right: tf.Tensor) -> tf.Tensor:
  """Half-colour anaglyph: R = Y(L), G and B from the right view."""
  return tf.concat([_luma(left), right[..., 1:3]], axis=-1)


def optimized_anaglyph(left: tf.Tensor, right: tf.Tensor) -> tf.Tensor:
  """'Optimized' anaglyph: R = 0.7 G_L + 0.3 B_L, G and B from the right view."""
  _, g, b = _channels(left)
  return tf.concat([0.7 * g + 0.3 * b, right[..., 1:3]], axis=-1)


def dubois_anaglyph(left: tf.Tensor, right: tf.Tensor) -> tf.Tensor:
  """Dubois (2009) least-squares red-cyan anaglyph on gamma-encoded [0, 1] values, clipped."""
  left01 = (left + 1.0) * 0.5
  right01 = (right + 1.0) * 0.5
  a_left = tf.constant(DUBOIS_LEFT, dtype=left.dtype)
  a_right = tf.constant(DUBOIS_RIGHT, dtype=left.dtype)
  # Row-vector form: mixture_c = sum_k A[c, k] * view_k.
  mixed = (tf.linalg.matvec(a_left, left01[..., None, :]) +
           tf.linalg.matvec(a_right, right01[..., None, :]))[..., 0, :]
  return tf.clip_by_value(mixed, 0.0, 1.0) * 2.0 - 1.0


def green_magenta_anaglyph(left: tf.Tensor, right: tf.Tensor) -> tf.Tensor:
  """Colour green-magenta anaglyph: G from the left view, R and B from the right."""
  return tf.concat([right[..., 0:1], left[..., 1:2], right[..., 2:3]], axis=-1)


def amber_blue_anaglyph(left: tf.Tensor, right: tf.Tensor) -> tf.Tensor:
  """Colour amber-blue (ColorCode 3-D) anaglyph: R and G from the left view, B from the right."""
  return tf.concat([left[..., 0:2], right[..., 2:3]], axis=-1)


_SPECS: Dict[str, MixtureSpec] = {
    spec.name: spec for spec in (
        MixtureSpec('anaglyph', anaglyph, {0: 0}, {1: 1, 2: 2},
                    'red-cyan colour anaglyph (the paper): R from left, G, B from right'),
        MixtureSpec('diplopia', diplopia, {}, {},
                    'double vision (the paper): (left + right) / 2'),
        MixtureSpec('monocular', monocular, {0: 0, 1: 1, 2: 2}, {},
                    'monocular depth (the paper): the left image itself'),
        MixtureSpec('gray', gray_anaglyph, {}, {},
                    'gray anaglyph: R = Y(left), G = B = Y(right)'),
        MixtureSpec('half_color', half_color_anaglyph, {}, {1: 1, 2: 2},
                    'half-colour anaglyph: R = Y(left), G, B from right'),
        MixtureSpec('optimized', optimized_anaglyph, {}, {1: 1, 2: 2},
                    'optimized anaglyph: R = 0.7 G_L + 0.3 B_L, G, B from right'),
        MixtureSpec('dubois', dubois_anaglyph, {}, {},
                    'Dubois least-squares red-cyan anaglyph (gamma-encoded values)'),
        MixtureSpec('green_magenta', green_magenta_anaglyph, {1: 1}, {0: 0, 2: 2},
                    'green-magenta colour anaglyph: G from left, R, B from right'),
        MixtureSpec('amber_blue', amber_blue_anaglyph, {0: 0, 1: 1}, {2: 2},
                    'amber-blue colour anaglyph: R, G from left, B from right'),
    )
}

MIXTURE_NAMES = tuple(_SPECS)


def get_mixture(name: str) -> MixtureSpec:
  """Returns the operator called `name`; raises ValueError listing the valid names."""
  try:
    return _SPECS[name]
  except KeyError:
    raise ValueError(f'Unknown mixture {name!r}; valid mixtures are: '
                     f'{", ".join(MIXTURE_NAMES)}.') from None


def mix(name: str, left: tf.Tensor, right: tf.Tensor) -> tf.Tensor:
  """Applies the operator called `name` to images in [-1, 1]; returns a tensor."""
  return get_mixture(name).fn(tf.convert_to_tensor(left), tf.convert_to_tensor(right))
