"""Training-free de-anaglyph for every anaglyph encoding: census-SGM, then views.

A stand-in for the paper's classical comparisons (Joulin & Kang 2013, Williem et al. 2015,
no public code). For an encoding of `mixtures.ANAGLYPH_NAMES`:
  1. the mixture channels carrying mostly the left view are matched against those carrying
     mostly the right one (`MixtureSpec.eye_channels`: red against green and blue for the
     red-cyan family) with `matcher.match` (census compares each pixel only with its own
     neighbourhood, so the different responses of different channels matter little) over a
     signed disparity range, given or estimated from the image (`matcher.estimate_range`);
  2. both views are restored from the encoding's matrices and the disparities
     (`views.restore_views`, colour transfer where the views do not match).
"""

import dataclasses
from typing import Callable, Dict, Optional, Tuple

import numpy as np

from mixstereo_tf.classical import matcher
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.restoration import views

SUPPORTED_MIXTURES = mixtures.ANAGLYPH_NAMES


@dataclasses.dataclass(frozen=True)
class AnaglyphConfig:
  """Parameters of the classical de-anaglyph: matching and views."""
  matching: matcher.MatcherConfig = matcher.MatcherConfig()
  restore: views.RestoreConfig = views.RestoreConfig()


def eye_images(mixture01: np.ndarray, mixture_name: str) -> Tuple[np.ndarray, np.ndarray]:
  """(left-eye channels, right-eye channels) of a [0, 1] mixture, on the 0..255 scale."""
  left, right = mixtures.get_mixture(mixture_name).eye_channels
  return mixture01[..., list(left)] * 255.0, mixture01[..., list(right)] * 255.0


def unmix_anaglyph(mixture, mixture_name: str,
                   disparity_range: Optional[Tuple[int, int]] = None,
                   config: AnaglyphConfig = AnaglyphConfig(),
                   prior: Optional[np.ndarray] = None,
                   on_disparity: Optional[Callable[[Dict[str, np.ndarray]], None]] = None,
                   views_from: Optional[np.ndarray] = None) -> Dict[str, object]:
  """Separates an anaglyph into two views and disparities.

  Args:
    mixture: uint8 [H, W, 3] RGB, or float in [0, 1].
    mixture_name: one of SUPPORTED_MIXTURES.
    disparity_range: (min, max) signed pixels to search; None: estimated from the image.
    config: matching and restoration parameters.
    prior: optional [H, W] left disparity to search around (a previous video frame's;
      NaN: no prior there, `search_windows.around_prior`).
    on_disparity: called with the disparities and 'consistent_left' once they are
      matched, before the views are restored (`hints.FrameHint.on_disparity`).
    views_from: the image the views are restored from, as `mixture` (the stored image of
      a colour-resolution copy or a 16-bit image, `hints.FrameHint.stored_image`); None:
      `mixture`.

  Returns:
    'left', 'right': uint8 [H, W, 3] (uint16 from a uint16 `views_from` or `mixture`);
    'disparity_left', 'disparity_right': float32 [H, W], signed pixels (left x matches
    right x - d_L; right x matches left x + d_R);
    'consistent_left': bool [H, W], the left-right check before filling;
    'disparity_range': the (min, max) searched.

  Raises:
    ValueError: unknown or unsupported mixture, a malformed image, or a bad range.
  """
  if mixture_name not in SUPPORTED_MIXTURES:
    raise ValueError(f'The classical de-anaglyph needs an anaglyph encoding '
                     f'({", ".join(SUPPORTED_MIXTURES)}); got {mixture_name!r}.')
  image = image_range.as_unit_float(mixture, 'mixture')
  left_eye, right_eye = eye_images(image, mixture_name)
  if disparity_range is None:
    disparity_range = matcher.estimate_range(left_eye, right_eye, config.matching)
  matched = matcher.match(left_eye, right_eye, *disparity_range, config.matching, prior)
  if on_disparity is not None:
    on_disparity({key: matched[key] for key in ('disparity_left', 'disparity_right',
                                                 'consistent_left')})
  depth = np.asarray(mixture if views_from is None else views_from).dtype
  if views_from is not None:
    image = image_range.as_unit_float(views_from, 'views_from')
  restored = views.restore_views(image, mixture_name, matched['disparity_left'],
                                 matched['disparity_right'], config=config.restore)
  return {**views.at_depth(restored, depth),
          'disparity_left': matched['disparity_left'],
          'disparity_right': matched['disparity_right'],
          'consistent_left': matched['consistent_left'],
          'disparity_range': tuple(int(d) for d in disparity_range)}
