"""The refiner stage (`models/refiner.py`, the shipped kind 'refiner'): a base stage's
result (the classical method, or another stage with its outputs) refined by the network,
then the views restored (anaglyphs) or settled onto the mixture (double images)."""

import dataclasses
from typing import Callable, Dict, Optional, Tuple

import numpy as np

from mixstereo_tf.core import hints
from mixstereo_tf.core import image_range
from mixstereo_tf.models import refiner
from mixstereo_tf.unmixing import families
from mixstereo_tf.unmixing import steps
from mixstereo_tf.unmixing import tiling


def refiner_unmix(network: Callable[[Tuple[str, ...]], tiling.Network], multiple: int,
                  image: np.ndarray, name: str, search: steps.Range,
                  hint: Optional[hints.FrameHint] = None,
                  base_stage: Optional[Callable[..., Dict[str, object]]] = None
                  ) -> Dict[str, object]:
  """The hybrid (`models/refiner.py`): the base stage (`steps.classical_unmix`, or another with
  its signature and outputs, e.g. the learned matching stage), the refiner on its result
  (`network(())`, in tiles; `network(keys)`: without the disparity outputs `keys`, where
  the family does not restore its views from them and the hint's `unread` names one or
  its `base_disparities` asks for both: the base's are returned there), then the views
  made to agree with the mixture by the family's `settle_views`
  (anaglyphs: restored from the refined disparities, double images: projected onto
  their equation). The hint's on_disparity is the base stage's: a video's next
  frame searches around the base's disparities and starts while these are refined
  (docs/DESIGN.md). Views from the hint's stored_image where it has one (`_deep_views`
  for double images); a gray image gets gray views, the refined views' channel mean."""
  family = families.of(name)
  deep = hint is not None and hint.stored_image is not None and (
      hint.stored_image.dtype == np.uint16)  # Anaglyphs: the base at 8 bits, views below.
  base = (base_stage or steps.classical_unmix)(image, name, search, dataclasses.replace(
      hint, stored_image=None) if deep and family.restores_views else hint)
  skipped = _skipped(family, hint)
  keys = ('left', 'right_warped' if 'right_warped' in base else 'right')  # As trained.
  base_views = [image_range.eight_bits(base[key]) for key in keys]
  refined = tiling.apply(network(skipped), refiner.network_input(
      image, *base_views, base['disparity_left'], base['disparity_right']), multiple)
  gray = bool(np.all(image == image[..., :1]))  # Gray input, gray views: the net tints them.
  signed = {key: np.repeat(refined[key].mean(-1, keepdims=True), 3, -1) if gray
            else refined[key] for key in ('left', 'right')}
  outputs = (_deep_views([base[key] for key in keys], base_views, signed)
             if deep and not family.restores_views  # Double images: 16-bit base layers.
             else {key: image_range.signed_to_u8(view) for key, view in signed.items()})
  for key in ('disparity_left', 'disparity_right'):
    outputs[key] = refined[key][..., 0] if key not in skipped else base[key]
  outputs.update(family.settle_views(hints.views_image(image, hint), name, outputs,
                                     base.get('info', {})))
  if 'info' in base:  # The base's record: a double image's mixing weight.
    outputs['info'] = base['info']
  return outputs


def _skipped(family, hint: Optional[hints.FrameHint]) -> Tuple[str, ...]:
  """The disparity outputs the refiner leaves to its base (`refiner_unmix`)."""
  if hint is None or family.restores_views:
    return ()
  return tuple(key for key in ('disparity_left', 'disparity_right')
               if hint.base_disparities or key == hint.unread)


def _deep_views(base, base_views, signed) -> Dict[str, np.ndarray]:
  """16-bit views: the base's uint16 layers [left, right] plus the refiner's change of
  their 8-bit copies `base_views` (`signed`: its views, signed units, half a [0, 1] unit
  each; a gray image's base layers are gray, so gray views stay gray)."""
  outputs = {}
  for key, deep, eight in zip(('left', 'right'), base, base_views):
    view = image_range.to_unit(deep) + (signed[key] - image_range.u8_to_signed(eight)) / 2
    outputs[key] = image_range.unit_to(np.clip(view, 0.0, 1.0), np.uint16)
  return outputs
