"""One mixture image through a predictor: its encoding, its disparity range, the network's
plan around that range, the restoration of both views, and what was done (`info`).

Steps, shared by the model and the classical method:
  1. the encoding: the one asked for, or detected from the image (`mixture_choice`);
  2. the disparity range: the one asked for, or planned by the encoding's family
     (`families`: an anaglyph's eye channels, a double image's self-matching);
  3. the model: the mixture's right-eye channels shifted and the image reduced so the
     range fits the network's levels (`disparity_range.plan`), the outputs brought back to
     the input's pixels, then both views restored from the encoding's matrices with the
     network's views as the prior (`restoration`); the classical method: the family's
     `classical` stage (`classical_unmix`, the one route of inference and of the
     refiner's training examples); the 'sgbm' baseline: OpenCV's SGBM on the eye
     channels, views restored likewise (`sgbm_unmix`).
Outputs: 'left', 'right' uint8 [H, W, 3] (uint16 where made from a 16-bit image),
'disparity_left', 'disparity_right' float32 [H, W] signed pixels, 'info' (JSON-able).

Eye order (`eye_order`), after step 1: the eyes as given, swapped (cyan-red glasses, mirrored
scans) or detected ('auto', anaglyphs); swapped images go through steps 2-3 mirrored and
come back mapped (left view's disparity, positive for near).

A video frame may come with a `hints.FrameHint`: its shot's encoding, eye order and range
replace steps 1 and 2, its prior (the previous frame's left disparity) goes to the solver
(the classical matcher searches around it) and its matcher options to the matchers.
"""

import dataclasses
import time
from typing import Callable, Dict, Optional, Sequence, Tuple, Union

from absl import logging
import numpy as np
import tensorflow as tf

from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import halftone
from mixstereo_tf.classical import sgbm
from mixstereo_tf.core import hints
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.restoration import views
from mixstereo_tf.unmixing import chroma
from mixstereo_tf.unmixing import disparity_range
from mixstereo_tf.unmixing import eye_order
from mixstereo_tf.unmixing import families
from mixstereo_tf.unmixing import mixture_choice
from mixstereo_tf.unmixing import tilt

Range = Union[None, str, Tuple[int, int]]  # disparity_range.parse's values.
# A method's own range planning: plan(uint8 image, encoding, hint) -> (min, max) pixels.
Planner = Callable[[np.ndarray, str, Optional[hints.FrameHint]], Tuple[int, int]]


def within_image(requested: Tuple[int, int], width: int) -> Tuple[int, int]:
  """A requested (low, high) range clipped to the disparities an image `width` px wide can
  hold (|d| <= width - 1), with a warning when that changes it: the info then records the
  range searched, not the one asked for.

  Raises:
    ValueError: no disparity of the range fits the image.
  """
  low, high = max(int(requested[0]), 1 - width), min(int(requested[1]), width - 1)
  if low > high:
    raise ValueError(f'The disparity range {list(requested)} holds no disparity of an image '
                     f'{width} px wide (at most {width - 1} px either way).')
  if (low, high) != tuple(requested):
    logging.warning('The disparity range %s reaches beyond the image (%d px wide): '
                    'searching [%d, %d].', list(requested), width, low, high)
  return low, high


def estimate_range(image: np.ndarray, name: str, requested: Range,
                   default: Tuple[int, int],
                   hint: Optional[hints.FrameHint] = None,
                   plan: Optional[Planner] = None) -> Tuple[int, int]:
  """The range asked for; the method's `default` for disparity_range.NETWORK; else the
  method's own `plan(image, name, hint)` when it has one (the learned matching stage's),
  or the family's (`Family.estimate_range`: an anaglyph's eye channels matched with the
  `hint`'s matcher options, a double image's self-matching, a monocular's `default`)."""
  if requested == disparity_range.NETWORK:
    return default
  if requested is not None:
    return within_image(requested, image.shape[1])
  if plan is not None:
    return plan(image, name, hint)
  return families.of(name).estimate_range(image, name, default, hint)


def model_unmix(graph: Callable[[tf.Tensor], Dict[str, tf.Tensor]], image: np.ndarray,
                name: str, search: Tuple[int, int], levels: int,
                max_pixels: Optional[int], restore: bool, views_from: np.ndarray
                ) -> Dict[str, object]:
  """The network around a disparity range, then the restoration (module docstring) from
  `views_from` (`hints.views_image`: `image`, or the stored image of its colour-resolution
  copy)."""
  family = families.of(name)
  height, width = image.shape[:2]
  chosen = disparity_range.plan(search, levels, height, width, max_pixels,
                                can_shift=family.signed)
  network_input = disparity_range.to_network(image, family.right_eye(name), chosen)
  raw = graph(tf.constant(network_input))
  outputs = disparity_range.from_network(
      {'left': raw['left'].numpy(), 'right': raw['right'].numpy(),
       'disparity_left': raw['disparity'].numpy(),
       'disparity_right': raw['disparity_right'].numpy()}, chosen, height, width)
  if restore and family.restores_views:
    restored = family.restore(
        image_range.to_unit(views_from), name,
        outputs['disparity_left'], outputs['disparity_right'],
        image_range.u8_to_unit(outputs['left']),
        image_range.u8_to_unit(outputs['right']))
    outputs.update(views.at_depth(restored, views_from.dtype))
  outputs['info'] = {'shift': chosen.shift, 'scale': round(chosen.scale, 4)}
  return outputs


def classical_unmix(image: np.ndarray, name: str, search: Range,
                    hint: Optional[hints.FrameHint] = None) -> Dict[str, object]:
  """The training-free method, the family's `classical` stage: the route of inference and
  of the refiner's training examples. A `hint`'s prior: a left disparity to search around
  in its prior_window (anaglyphs; double images penalise lags outside that window; NaN:
  no prior there); its full_search_cells: the matcher's coarse-to-fine threshold (a
  shot's first frame); its matcher_strips: the matcher's SGM strips. Anaglyphs also give
  'consistent_left', the matcher's left-right check (`temporal.VideoState` drops the prior
  where it failed)."""
  out = families.of(name).classical(image, name, search, hint)
  keys = ('left', 'right', 'right_warped', 'disparity_left', 'disparity_right', 'consistent_left')
  outputs = {key: out[key] for key in keys if key in out}
  if 'mixing_weight' in out:  # Double images: the weight a the layers were separated with.
    outputs['info'] = diplopia.weight_record(out)
  return outputs


def sgbm_unmix(image: np.ndarray, name: str, search: Tuple[int, int],
               hint: Optional[hints.FrameHint] = None) -> Dict[str, object]:
  """The 'sgbm' method's step 3 (`steps.run`'s `solve`): SGBM's left disparity and its
  right one from the mirrored, swapped pair (`sgbm.match_anaglyph`) over `search`, then
  both views restored from the encoding's matrices (`Family.restore`, as the classical
  method's, from the hint's stored_image where it has one); a video hint's prior is not
  used."""
  d_left, d_right = sgbm.match_anaglyph(image, name, *search)
  views_from = hints.views_image(image, hint)
  restored = families.of(name).restore(image_range.to_unit(views_from), name, d_left, d_right)
  return {**views.at_depth(restored, views_from.dtype),
          'disparity_left': d_left, 'disparity_right': d_right,
          'consistent_left': restored['consistent_left'],
          'info': {'matcher': 'opencv_stereo_sgbm'}}


def _eye_order(image: np.ndarray, name: str, swap_eyes,
               hint: hints.FrameHint) -> Tuple[bool, Dict[str, object]]:
  """`eye_order.decide` for the family of `name` (detected: anaglyphs).

  Raises:
    ValueError: swapped eyes for a single view (monocular).
  """
  family = families.of(name)
  swapped, info = eye_order.decide(image, name, swap_eyes, family.detectable, hint.swap_eyes,
                                   hint.chroma_halved)
  if swapped and family.input_is_left:
    raise ValueError(f'PredictorConfig.swap_eyes: a {name!r} input is one view; it has no '
                     'eyes to swap.')
  return swapped, info


def _warn_at_limits(disparity: np.ndarray, search: Tuple[int, int]) -> None:
  """Warns when a given range cuts the scene off: many disparities at one of its limits."""
  for side, share in disparity_range.at_limits(disparity, search).items():
    logging.warning('%.0f%% of the disparities sit at the %s limit of the range given, %s: '
                    'the scene reaches past it; widen it (PredictorConfig.disparity_range) '
                    'or let it be estimated.', 100 * share, side, list(search))


def _encoding(image: np.ndarray, requested_mixture: str, allowed: Sequence[str],
              hint: hints.FrameHint) -> Tuple[str, Dict[str, object]]:
  """Step 1: (encoding, info): the hint's (a video shot's, settled where it may be a
  larger one), else the one asked for or detected (`mixture_choice`)."""
  if hint.mixture is not None:
    name, info = hint.mixture, dict(hint.detection or {})
    if hint.may_be is not None:
      name, info = mixture_choice.settle(image, name, info, hint.may_be)
    return name, info
  name, info = mixture_choice.resolve_mixture(image, requested_mixture, allowed,
                                              hint.mixing_weight is not None,
                                              hint.fallback_mixture)
  if hint.mixing_weight is not None and not families.of(name).weighted:
    info['mixing_weight_unused'] = hint.mixing_weight
    logging.warning('The mixing weight %s is not used: mixture %r has none (double '
                    'images do).', hint.mixing_weight, name)
  return name, info


def _served(image: np.ndarray, deep: Optional[np.ndarray], name: str):
  """(image, deep, the encoding they are unmixed as): a two-channel anaglyph's (and its
  16-bit samples') empty channel filled (`mixtures.served`), else as they are."""
  served = mixtures.served_name(name)
  if served == name:
    return image, deep, name
  return (mixtures.served(image, name),
          None if deep is None else mixtures.served(deep, name), served)


def run(image: np.ndarray, requested_mixture: str, allowed: Sequence[str],
        requested_range: Range, default_range: Callable[[str], Tuple[int, int]], method: str,
        solve: Callable[..., Dict[str, object]],
        hint: Optional[hints.FrameHint] = None, swap_eyes=False,
        mixing_weight=None, plan: Optional[Planner] = None,
        descreen=halftone.OFF, rectify=tilt.OFF) -> Dict[str, object]:
  """Steps 1-3 for one image; `default_range(encoding)` is the method's own range, `plan`
  its own range planning (`estimate_range`);
  `solve(image, name, range, hint)` is the method's step 3; `swap_eyes`: one of
  `eye_order.SWAP_EYES`. A `hint`'s mixture, eye order and range (a video shot's) replace
  steps 1 and 2; `solve` may use its prior; `mixing_weight` (double images) goes to the
  hint unless it has its own. A uint16 `image` (a 16-bit file) is detected and matched at
  8 bits (`image_range.eight_bits`); where the family makes its views from the mixture's
  samples (`Family.views_at_depth`) they come from it, as uint16 (the hint's
  stored_image), else at 8 bits. A printed image's halftone screen is smoothed first
  (`descreen`, the hint's where it has one: `halftone.resolve`); a tilted anaglyph is
  turned level once its encoding is known (`rectify`, the hint's first: `tilt.level`) and
  its outputs turned back last."""
  start = time.perf_counter()
  hint = hint or hints.FrameHint()
  image, screen = halftone.resolve(image, descreen if hint.descreen is None else hint.descreen)
  deep = image if image.dtype == np.uint16 else None  # 16 bits: views restored from it.
  image = image_range.eight_bits(image)
  if hint.mixing_weight is None and mixing_weight is not None:
    hint = dataclasses.replace(hint, mixing_weight=mixing_weight)
  encoded, info = _encoding(image, requested_mixture, allowed, hint)
  image, deep, name = _served(image, deep, encoded)
  image, deep, hint, turn_back, turned = tilt.level(
      image, deep, name, rectify if hint.rectify is None else hint.rectify, hint)
  swapped, eyes = _eye_order(image, name, swap_eyes, hint)
  if swapped:
    image, hint = eye_order.mirror(image), eye_order.mirror_hint(hint)
    deep = None if deep is None else eye_order.mirror(deep)
  family = families.of(name)
  halved = hint.chroma_halved and family.restores_views
  matched = chroma.colour_resolution_copy(image) if halved else image
  search = hint.disparity_range
  if search is None:
    search = estimate_range(matched, name, requested_range, default_range(name), hint, plan)
  stored = deep if deep is not None and family.views_at_depth else image if halved else None
  outputs = solve(matched, name, search,
                  hint if stored is None else dataclasses.replace(hint, stored_image=stored))
  if isinstance(requested_range, tuple) and hint.disparity_range is None:
    _warn_at_limits(outputs['disparity_left'], search)  # Before the eyes are turned back.
  if swapped:
    outputs = eye_order.unmirror(outputs)
  outputs = turn_back(outputs, swapped)
  info = dict(info, method=method, mixture=encoded, disparity_range=list(search),
              prior=hint.prior is not None, **eyes, **screen, **turned,
              **outputs.get('info', {}))
  if halved:
    info['matched_at_colour_resolution'] = True  # Stored with half-resolution colour.
  if name != encoded:
    info['unmixed_as'] = name  # A red-blue or red-green anaglyph: as the gray one.
  info['seconds'] = round(time.perf_counter() - start, 3)
  outputs['info'] = info
  return outputs
