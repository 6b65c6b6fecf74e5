"""Step 1 of unmixing (`steps`): the encoding an image is unmixed with, the one asked for or
the one detected (`detection`), and what the detection found (`info`).

'auto' takes the detected encoding (or a fallback where none is found: a double image
predictor's 'diplopia', a video's encoding for its black frames); a named encoding the
detector confidently contradicts is logged as a warning; a detection that is doubtful or
that another encoding fits as well is recorded in `info` and warned about.
"""

from typing import Dict, Optional, Sequence, Tuple

from absl import logging
import numpy as np

from mixstereo_tf.core import mixtures
from mixstereo_tf.unmixing import detection
from mixstereo_tf.unmixing import families

AUTO = 'auto'
# A named encoding the detector contradicts with at least this confidence is warned about;
# one of other glasses (family), at this confidence.
WARN_CONFIDENCE = 0.9
FAMILY_WARN_CONFIDENCE = 0.85
# Views' RGB PSNR lost (dB) when a colour anaglyph is read as the smaller encoding that also
# explains it, and the reverse: means over photo warps stored as png and JPEG (DESIGN.md,
# unmixing: what detection misreads cost). Said in the warning of such a tie.
TIE_COST_DB = {'half_color': (13.0, 6.0), 'green_magenta_half': (7.0, 5.5),
               'amber_blue_half': (11.0, 1.0)}


def settle(image: np.ndarray, name: str, info: Dict[str, object],
           may_be: str) -> Tuple[str, Dict[str, object]]:
  """(encoding, detection info) of a frame of a shot read as `name` that may be `may_be`:
  `may_be` where the frame's detection gives it (its colours are more than `name` can
  explain), else the shot's."""
  found = detection.detect(image)
  return (may_be, _detection_info(found)) if found.name == may_be else (name, info)


def _detection_info(found: detection.Detection) -> Dict[str, object]:
  """The info a frame records of its detection: {'detected', 'confidence'}, and where it
  finds no anaglyph {'detection': why} (the confidence is then that there is none)."""
  info = {'detected': found.name, 'confidence': round(found.confidence, 3)}
  if found.name is None:
    info['detection'] = f'no anaglyph ({found.reason})'
  return info


class NoAnaglyphError(ValueError):
  """'auto' found no anaglyph in an image (or it is too small to tell) and has no fallback."""


def resolve_mixture(image: np.ndarray, requested: str, allowed: Sequence[str],
                    weighted: bool = False, fallback: Optional[str] = None
                    ) -> Tuple[str, Dict[str, object]]:
  """(encoding to unmix with, detection info) for an image.

  Args:
    image: uint8 [H, W, 3] mixture.
    requested: a mixture name, or 'auto' to detect it; an image 'auto' finds no anaglyph
      in is read as the one encoding of `allowed` detection cannot tell, if there is one
      (`_undetectable`: a double image model's 'diplopia').
    allowed: the encodings the predictor can unmix.
    weighted: a mixing weight was given (only weighted encodings take one).
    fallback: for 'auto', the encoding an image with no anaglyph found (or too small or
      dark to tell) is read as: a video's (`hints.FrameHint.fallback_mixture`: black
      frames, fades); its info then says 'undecided' (a shot is not decided by it).

  Raises:
    NoAnaglyphError: 'auto' on an image that is not an anaglyph or too small to tell.
    ValueError: an encoding outside `allowed`.
  """
  try:
    found = detection.detect(image)
  except ValueError as e:  # Too small or thin to detect: a named mixture needs no check.
    if requested == AUTO and not fallback:
      raise NoAnaglyphError(f'{e} The encoding cannot be detected on it: name its mixture '
                            '(e.g. PredictorConfig.mixture=anaglyph).') from None
    if requested == AUTO:
      return fallback, {'detected': None, 'detection': str(e), 'read_as': fallback,
                        'undecided': True}
    return _allowed_name(requested, allowed), {'detected': None, 'detection': str(e)}
  info = _detection_info(found)
  if requested == AUTO:
    only = _undetectable(allowed, weighted)
    if found.name is None and (only or fallback):
      why = ('a mixing weight given' if weighted else 'the only encoding this predictor '
             'takes') if only else "the video's encoding"
      return only or fallback, dict(info, read_as=f'{only or fallback}: no anaglyph found, '
                                    f'{why}', **({} if only else {'undecided': True}))
    if found.name is None:
      raise NoAnaglyphError(f'This image does not look like an anaglyph ({found.reason}); '
                            'if it is a double image, name it (PredictorConfig.mixture='
                            'diplopia); a single photo or a side-by-side pair is no mixture.')
    name = found.name
    if found.doubt:
      info['detection_doubt'] = found.doubt
      logging.warning('Detected %s, but %s: if the image is no anaglyph, its results mean '
                      'nothing.', name, found.doubt)
    if found.also_fits:
      info['also_fits'] = found.also_fits
      logging.warning('Detected %s, the smallest encoding that explains the image; %s fits '
                      'it as well. Name the mixture if you know it%s', name, found.also_fits,
                      _tie_cost(name, found.also_fits))
  else:
    name = requested
    if _contradicts(found, name):
      logging.warning('The image was given as %r, but the detector %s (confidence %.2f).',
                      name, f'reads it as {found.name!r}' if found.name else
                      'finds no anaglyph in it', found.confidence)
  return _allowed_name(name, allowed), info


def _allowed_name(name: str, allowed: Sequence[str]) -> str:
  """`name`, or a ValueError when a predictor that unmixes `allowed` cannot unmix it (the
  encoding it is served as: `mixtures.served_name`)."""
  if mixtures.served_name(name) not in allowed:
    raise ValueError(f'The image is read as mixture {name!r}; this predictor unmixes '
                     f'{", ".join(allowed)}: choose one that unmixes {name!r} '
                     '(PredictorConfig.pretrained, PredictorConfig.checkpoint or '
                     'PredictorConfig.method) or name the mixture (PredictorConfig.mixture).')
  return name


def _undetectable(allowed: Sequence[str], weighted: bool = False) -> Optional[str]:
  """What 'auto' reads an image without an anaglyph as, or None (refused): the one
  encoding of `allowed` when detection can tell none of them (a double image model's
  'diplopia'), or with `weighted` (a mixing weight given) the one that takes a weight."""
  if not weighted and any(families.of(name).detectable for name in allowed):
    return None
  names = [name for name in allowed if not families.of(name).detectable
           and (families.of(name).weighted or not weighted)]
  return names[0] if len(names) == 1 else None


def _tie_cost(name: str, colour: str) -> str:
  """The end of the tie warning: what each misread costs (`TIE_COST_DB`), where measured."""
  if name not in TIE_COST_DB:
    return '.'
  to_smaller, to_colour = TIE_COST_DB[name]
  return (f': on photo warps, reading {colour} as {name} lost about {to_smaller:g} dB of the '
          f"views' PSNR, reading {name} as {colour} about {to_colour:g} dB.")


def _contradicts(found: detection.Detection, name: str) -> bool:
  """Whether a detection is sure enough that the named encoding `name` is wrong: another
  encoding at WARN_CONFIDENCE, or one of other glasses at FAMILY_WARN_CONFIDENCE (a family
  is read more surely than the encoding within it: a clean red-cyan anaglyph reads at
  0.89, a random-noise test image as green-magenta at 0.77)."""
  if found.name == name or (found.name is None and not families.of(name).detectable):
    return False
  other_glasses = (found.name is not None and mixtures.get_mixture(found.name).family
                   != mixtures.get_mixture(name).family)
  return found.confidence >= WARN_CONFIDENCE or (
      other_glasses and found.confidence >= FAMILY_WARN_CONFIDENCE)
