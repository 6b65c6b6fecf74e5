"""One strategy per mixture family: what the unmixing steps do differently for anaglyphs,
double images and single views.

    family = families.of('gray')           # the Anaglyph family
    family.estimate_range(image, 'gray', default)
    family.classical(image, 'gray', search, hint)

A family answers, for each of its encodings (`names`):
  * detection: `detectable` families are found in an image by `detection` (anaglyphs);
    the others must be named (diplopia, monocular);
  * range planning: `estimate_range` from the image (an anaglyph's eye channels, a double
    image's self-matching) or the method's default (monocular);
  * the classical stage: `classical` runs the training-free method of `classical/` (a
    `hints.FrameHint` rides down to the matcher's configuration), `classical_range` and
    `display_range` are its own range and display range;
  * the views: `restore` from the encoding's matrices (`restores_views`: anaglyphs);
    `views_at_depth`: a 16-bit mixture's views are made from its 16-bit samples (the
    hint's stored_image; matching runs on its 8-bit copy); `settle_views`: a refiner's
    views made to agree with the mixture;
  * the network plan: `signed` families may have disparities of either sign, so the plan
    may shift their `right_eye` channels (`disparity_range.plan`, `to_network`);
  * learned stages: `learned_stages` names the networks built on its classical stage
    ('refiner', 'features': the learned matching stage);
  * `input_is_left`: a network's input is the left view itself (monocular);
  * `weighted`: the encoding may mix the eyes with unequal weights a L + (1 - a) R that
    the classical stage takes from `hints.FrameHint.mixing_weight` (double images).
A registry maps each mixture name to its family (`of`); a new family is one `Family`
subclass and one `register` call.
"""

import dataclasses
from typing import Dict, Optional, Tuple

import numpy as np

from mixstereo_tf.classical import anaglyph
from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import diplopia_layers
from mixstereo_tf.classical import diplopia_range
from mixstereo_tf.classical import matcher
from mixstereo_tf.classical import sgm
from mixstereo_tf.core import hints
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.restoration import views

Range = Tuple[int, int]
# A double image's refined views onto its equation (`Diplopia.settle_views`): the right
# view takes 3 times the left's share of the residual (k of `onto_mixture`). Chosen on
# validation double images (2026-11-29), the default's views, k = 1 / 3 / inf, left and
# right, dB: a = 1/2 +0.02 / +0.07 / 0.00, +0.50 / +0.61 / +0.57; a = 0.7 +0.54 / +0.52 /
# 0.00, +0.06 / +0.04 / -0.27; a = 0.3 -0.12 / -0.03 / 0.00, +1.99 / +2.13 / +2.16.
REFINED_RIGHT_SHARE = 3.0
# The refined views' share of a refiner's anaglyph restoration prior (`Anaglyph.settle_views`;
# the rest: the colour transfer); chosen on validation examples (pretrained_ablations.md).
REFINED_VIEW_WEIGHT = 0.25


class Family:
  """A family of encodings and how the unmixing steps treat it (module docstring); the
  defaults suit a family that is named, has no classical method and restores nothing."""
  names: Tuple[str, ...] = ()
  detectable = False
  signed = False
  restores_views = False
  views_at_depth = False
  has_classical = False
  input_is_left = False
  weighted = False
  learned_stages: Tuple[str, ...] = ()

  def estimate_range(self, image: np.ndarray, name: str, default: Range,
                     hint: Optional[hints.FrameHint] = None) -> Range:
    """The disparity range of uint8 `image` [H, W, 3] made with encoding `name`; `default`:
    the method's own range; `hint`: options of the matcher (`hints.FrameHint`)."""
    del image, name, hint
    return default

  def settle_views(self, mixture: np.ndarray, name: str, refined: Dict[str, np.ndarray],
                   info: Dict[str, object]) -> Dict[str, np.ndarray]:
    """A refiner's views made to agree with their `mixture` (uint8 or uint16 [H, W, 3],
    encoding `name`): `refined` holds its 'left' and 'right' (uint8, or a double image's
    at the mixture's depth) and 'disparity_left' / 'disparity_right' (float32 [H, W],
    signed px); `info`: its base stage's. Returns 'left' and 'right' at the mixture's
    depth and what the family adds. Here: the views as they are."""
    del mixture, name, info
    return {key: refined[key] for key in ('left', 'right')}

  def classical(self, image: np.ndarray, name: str, search: Optional[Range] = None,
                hint: Optional[hints.FrameHint] = None) -> Dict[str, object]:
    """The training-free method on a mixture (uint8 [H, W, 3], or float in [0, 1]) over
    `search` (None: the method's own); returns 'left', 'right' uint8 [H, W, 3],
    'disparity_left', 'disparity_right' float32 [H, W] signed pixels, 'disparity_range',
    and what the method adds (anaglyphs: 'consistent_left').

    Raises:
      ValueError: the family has no classical method, or a malformed image or range.
    """
    del image, search, hint
    raise ValueError(f'No classical method for mixture {name!r}; use a trained model.')

  def display_range(self) -> int:
    """The largest disparity the classical method shows, pixels."""
    return sgm.SgmConfig().max_disparity

  def classical_range(self) -> Range:
    """The classical method's own (min, max) disparity range, pixels."""
    return 0, self.display_range() - 1

  def right_eye(self, name: str) -> Tuple[int, ...]:
    """The mixture channels of the right view that the network plan may shift."""
    del name
    return ()

  def restore(self, mixture01: np.ndarray, name: str, d_left: np.ndarray,
              d_right: np.ndarray, prior_left: Optional[np.ndarray] = None,
              prior_right: Optional[np.ndarray] = None,
              consistent: Optional[Tuple[np.ndarray, np.ndarray]] = None,
              colour_line: Optional[bool] = None) -> Dict[str, np.ndarray]:
    """Both views from the mixture and disparities (`views.restore_views`'s arguments and
    outputs); only for families that restore views."""
    del mixture01, d_left, d_right, prior_left, prior_right, consistent, colour_line
    raise ValueError(f'Mixture {name!r} has no view restoration.')


class Anaglyph(Family):
  """Colour-filter encodings: each mixture channel mostly one view; detected, matched
  across the eyes' channels over a signed range, views restored from the matrices."""
  names = mixtures.ANAGLYPH_NAMES
  detectable = True
  signed = True
  restores_views = True
  views_at_depth = True
  has_classical = True
  learned_stages = ('refiner', 'features')

  def matching(self, hint: Optional[hints.FrameHint] = None) -> matcher.MatcherConfig:
    """The matcher's configuration for a frame: the defaults, with a hint's prior window
    (when it has a prior), coarse-to-fine threshold and SGM strips."""
    hint = hint or hints.FrameHint()
    fields = {key: value for key, value in (('full_search_cells', hint.full_search_cells),
                                            ('strips', hint.matcher_strips)) if value is not None}
    if hint.prior is not None and hint.prior_window is not None:
      fields.update(prior_radius=hint.prior_window[0], prior_spread=hint.prior_window[1])
    return dataclasses.replace(matcher.MatcherConfig(), **fields)

  def estimate_range(self, image, name, default, hint=None):
    """The eye channels matched on a small copy (`matcher.estimate_range`)."""
    del default
    left_eye, right_eye = anaglyph.eye_images(image_range.u8_to_unit(image), name)
    return matcher.estimate_range(left_eye, right_eye, self.matching(hint))

  def classical(self, image, name, search=None, hint=None):
    """`anaglyph.unmix_anaglyph` with the hint's matcher options, prior, on_disparity and
    stored_image."""
    config = anaglyph.AnaglyphConfig(matching=self.matching(hint))
    hint = hint or hints.FrameHint()
    return anaglyph.unmix_anaglyph(image, name, search, config=config, prior=hint.prior,
                                   on_disparity=hint.on_disparity,
                                   views_from=hint.stored_image)

  def settle_views(self, mixture, name, refined, info):
    """Restored from the refined disparities (`restore`, colour-line pass on), the prior
    REFINED_VIEW_WEIGHT of the refined views and the rest of the colour transfer (+0.1 to
    +0.8 dB on validation); and its left-right check 'consistent_left' (a video's prior)."""
    del info
    mixture01 = image_range.to_unit(mixture)
    disparities = refined['disparity_left'], refined['disparity_right']
    transfer = self.restore(mixture01, name, *disparities)
    prior = [REFINED_VIEW_WEIGHT * image_range.u8_to_unit(refined[key])
             + (1 - REFINED_VIEW_WEIGHT) * transfer[key] for key in ('left', 'right')]
    checked = transfer['consistent_left'], transfer['consistent_right']
    restored = self.restore(mixture01, name, *disparities, *prior, consistent=checked,
                            colour_line=True)
    return dict(views.at_depth(restored, mixture.dtype),
                consistent_left=restored['consistent_left'])

  def right_eye(self, name):
    """`MixtureSpec.eye_channels`' right eye."""
    return mixtures.get_mixture(name).eye_channels[1]

  def restore(self, mixture01, name, d_left, d_right, prior_left=None, prior_right=None,
              consistent=None, colour_line=None):
    """`views.restore_views`."""
    return views.restore_views(mixture01, name, d_left, d_right, prior_left, prior_right,
                               consistent=consistent, colour_line=colour_line)


class Diplopia(Family):
  """Double images (left + right) / 2: named, never detected; self-matched over positive
  disparities (the average is symmetric in the views), layers by least squares."""
  names = ('diplopia',)
  has_classical = True
  weighted = True
  views_at_depth = True
  learned_stages = ('refiner', 'echo_features')

  def estimate_range(self, image, name, default, hint=None):
    """The double image's self-matching on a small copy (`diplopia_range.estimate_range`)."""
    del name, default, hint  # Its SGM runs in one strip: no matcher options.
    return diplopia_range.estimate_range(image)

  def classical(self, image, name, search=None, hint=None):
    """`diplopia.unmix_diplopia` over `search` (None: its configured range) with the
    hint's mixing weight (None: 1/2), its prior (a video frame's), in its window,
    on_disparity, and its stored_image (a 16-bit mixture: the layers at 16 bits)."""
    del name
    hint = hint or hints.FrameHint()
    return diplopia.unmix_diplopia(image, search, weight=hint.mixing_weight,
                                   prior=hint.prior, prior_window=hint.prior_window,
                                   on_disparity=hint.on_disparity,
                                   views_image=hint.stored_image)

  def settle_views(self, mixture, name, refined, info):
    """The views projected onto I = a L + (1 - a) R at the base's weight a
    (`diplopia_layers.onto_mixture`, the right view taking REFINED_RIGHT_SHARE)."""
    del name
    unit = [image_range.to_unit(image) for image in (mixture, refined['left'],
                                                      refined['right'])]
    settled = diplopia_layers.onto_mixture(*unit, info.get('mixing_weight', 0.5),
                                           REFINED_RIGHT_SHARE)
    return {key: image_range.unit_to(view, refined[key].dtype)
            for key, view in zip(('left', 'right'), settled)}

  def display_range(self):
    """The self-matching's largest configured lag."""
    return diplopia.DiplopiaConfig().matching.max_disparity

  def classical_range(self):
    """From lag 1 to the display range."""
    return 1, self.display_range()  # No zero shift: lag 0 matches the image to itself.


class Monocular(Family):
  """A single view (the left image itself): named, no second view to match; trained
  models only, their input the left view."""
  names = ('monocular',)
  input_is_left = True

  def classical(self, image, name, search=None, hint=None):
    """Refused: nothing to match."""
    del image, search, hint
    raise ValueError(f'No classical method for mixture {name!r}: a single view carries no '
                     'second view to match; use a trained model.')


_REGISTRY: Dict[str, Family] = {}


def register(family: Family) -> Family:
  """Adds `family` for each of its names (mixture names of `mixtures`); returns it.

  Raises:
    ValueError: a name that is no mixture, or one another family holds.
  """
  for name in family.names:
    mixtures.get_mixture(name)  # ValueError listing the valid names.
    if name in _REGISTRY:
      raise ValueError(f'Mixture {name!r} belongs to {type(_REGISTRY[name]).__name__} '
                       f'already; {type(family).__name__} cannot take it.')
  _REGISTRY.update({name: family for name in family.names})
  return family


for _family in (Anaglyph(), Diplopia(), Monocular()):
  register(_family)


def of(name: str) -> Family:
  """The family of mixture `name`.

  Raises:
    ValueError: an unknown mixture (listing the valid names), or one no family holds.
  """
  mixtures.get_mixture(name)
  if name not in _REGISTRY:
    raise ValueError(f'Mixture {name!r} belongs to no registered family.')
  return _REGISTRY[name]


def detected() -> Family:
  """The family whose encodings `detection` finds in an image (the anaglyphs): the one a
  mixture asked as 'auto' belongs to."""
  return next(family for family in _REGISTRY.values() if family.detectable)


def classical_names() -> Tuple[str, ...]:
  """The mixtures with a classical method, in `mixtures.MIXTURE_NAMES` order within each
  family, families in registration order (anaglyphs, then diplopia)."""
  families = list(dict.fromkeys(_REGISTRY.values()))
  return tuple(name for family in families if family.has_classical
               for name in family.names)


def input_is_left(text: str) -> bool:
  """Whether a network's input is the left view itself (`ModelConfig.input_is_left`):
  every encoding of `text` (`mixtures.parse_names`) belongs to such a family."""
  return all(of(name).input_is_left for name in mixtures.parse_names(text))
