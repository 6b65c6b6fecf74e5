"""Training-free classical baselines for de-anaglyph and de-diplopia.

Stand-ins for the paper's classical comparisons (Joulin & Kang 2013, Williem et al. 2015),
which have no public code: `anaglyph.unmix_anaglyph` (census-SGM across colour channels
over a signed range, and the matrix-driven restoration of both views, for every anaglyph
encoding) and `diplopia.unmix_diplopia` (self-matching of the double image and
least-squares layer separation; disparities positive by convention).
"""

import dataclasses
from typing import Dict, Optional, Tuple

import numpy as np

from mixstereo_tf.classical import anaglyph
from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import sgm
from mixstereo_tf.core import mixtures

SUPPORTED_MIXTURES = anaglyph.SUPPORTED_MIXTURES + ('diplopia',)


def unmix_classical(mixture_u8, mixture_name: str,
                    disparity_range: Optional[Tuple[int, int]] = None,
                    prior: Optional[np.ndarray] = None,
                    prior_window: Optional[Tuple[int, int]] = None,
                    full_search_cells: Optional[int] = None) -> Dict[str, object]:
  """Separates a mixture image with the classical baseline for its operator.

  Args:
    mixture_u8: uint8 [H, W, 3] RGB mixture (float in [0, 1] is also accepted).
    mixture_name: a name from `mixtures.MIXTURE_NAMES`; supported: SUPPORTED_MIXTURES.
    disparity_range: (min, max) signed pixels (anaglyphs); None: estimated from the image
      for anaglyphs, the default positive range for diplopia.
    prior: optional [H, W] left disparity to search around (anaglyphs; a previous frame's).
    prior_window: (radius, spread) of that search (`search_windows.around_prior`); None:
      MatcherConfig's prior_radius and prior_spread.
    full_search_cells: above this many cells the anaglyph matcher goes coarse-to-fine
      (`MatcherConfig.full_search_cells`); None: its default.

  Returns:
    'left', 'right': uint8 [H, W, 3]; 'disparity_left', 'disparity_right': float32 [H, W],
    signed pixels (left x matches right x - d_L, right x matches left x + d_R);
    'disparity_range': the (min, max) searched.

  Raises:
    ValueError: unknown or unsupported mixture name, or a malformed image.
  """
  mixtures.get_mixture(mixture_name)  # ValueError listing the names if unknown.
  if mixture_name == 'monocular':
    raise ValueError("No classical method for mixture 'monocular': a single view carries "
                     'no second view to match; use a trained model.')
  if mixture_name == 'diplopia':
    return diplopia.unmix_diplopia(mixture_u8, disparity_range)
  config = anaglyph.AnaglyphConfig()
  matching = {}
  if prior_window is not None:
    matching.update(prior_radius=prior_window[0], prior_spread=prior_window[1])
  if full_search_cells is not None:
    matching.update(full_search_cells=full_search_cells)
  if matching:
    config = dataclasses.replace(config, matching=dataclasses.replace(config.matching,
                                                                      **matching))
  return anaglyph.unmix_anaglyph(mixture_u8, mixture_name, disparity_range, config, prior)


def max_disparity(mixture_name: str) -> int:
  """The default display range of the classical method for `mixture_name`, pixels."""
  if mixture_name == 'diplopia':
    return diplopia.DiplopiaConfig().matching.max_disparity
  return sgm.SgmConfig().max_disparity
