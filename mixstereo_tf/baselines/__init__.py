"""Training-free classical baselines for de-anaglyph and de-diplopia.

Stand-ins for the paper's classical comparisons (Joulin & Kang 2013, Williem et al. 2015),
which have no public code: `anaglyph.unmix_anaglyph` (census-SGM across colour channels and
warping-based colour restoration) and `diplopia.unmix_diplopia` (self-matching of the
double image and least-squares layer separation).
"""

from typing import Dict

import numpy as np

from mixstereo_tf import mixtures
from mixstereo_tf.baselines import anaglyph
from mixstereo_tf.baselines import diplopia

SUPPORTED_MIXTURES = anaglyph.SUPPORTED_MIXTURES + ('diplopia',)


def unmix_classical(mixture_u8, mixture_name: str) -> Dict[str, np.ndarray]:
  """Separates a mixture image with the classical baseline for its operator.

  Args:
    mixture_u8: uint8 [H, W, 3] RGB mixture (float in [0, 1] is also accepted).
    mixture_name: a name from `mixtures.MIXTURE_NAMES`; supported: SUPPORTED_MIXTURES.

  Returns:
    'left', 'right': uint8 [H, W, 3]; 'disparity_left', 'disparity_right': float32 [H, W],
    pixels, positive (left x matches right x - d_L, right x matches left x + d_R).

  Raises:
    ValueError: unknown or unsupported mixture name, or a malformed image.
  """
  mixtures.get_mixture(mixture_name)  # ValueError listing the names if unknown.
  if mixture_name == 'monocular':
    raise ValueError("No classical method for mixture 'monocular': a single view carries "
                     'no second view to match; use a trained model.')
  if mixture_name == 'diplopia':
    out = diplopia.unmix_diplopia(mixture_u8)
  elif mixture_name in anaglyph.SUPPORTED_MIXTURES:
    out = anaglyph.unmix_anaglyph(mixture_u8, mixture_name)
  else:
    raise ValueError(f'No classical method for mixture {mixture_name!r}: it keeps no '
                     'unchanged channel of both views; supported: '
                     f'{", ".join(SUPPORTED_MIXTURES)}.')
  return {key: out[key] for key in ('left', 'right', 'disparity_left', 'disparity_right')}
