"""The predictor's common parts: `PredictorConfig`, the `Unmixer` every tool calls, and how a
method's step 3 (`solve`) becomes an Unmixer of mixture images (`image_unmixer`, around
`steps.run`). The methods themselves are registered in `predictors`; the shipped models'
Unmixers are made in `shipped`.
"""

import dataclasses
from typing import Callable, Dict, Optional, Sequence, Tuple, Union

from absl import logging
import numpy as np
import tensorflow as tf

from mixstereo_tf.artifacts import runs
from mixstereo_tf.classical import diplopia_weight
from mixstereo_tf.classical import halftone
from mixstereo_tf.core import hints
from mixstereo_tf.core import mixtures
from mixstereo_tf.unmixing import families
from mixstereo_tf.unmixing import mixture_choice
from mixstereo_tf.unmixing import steps
from mixstereo_tf.unmixing import tilt

Outputs = Dict[str, np.ndarray]

# OpenCV's remap takes sides below SHRT_MAX (32767) px only.
MAX_SIDE = 32767


def as_rgb(image) -> np.ndarray:
  """A uint8 (or 16-bit uint16) mixture as [H, W, 3]; gray [H, W] / [H, W, 1] is replicated
  to RGB and an alpha channel dropped (gray + alpha [H, W, 2], RGBA [H, W, 4]), as image
  files are read."""
  image = np.asarray(image)
  if image.dtype not in (np.uint8, np.uint16):
    raise ValueError(f'Unmixer expects a uint8 (or uint16) image, got {image.dtype}.')
  if image.ndim == 2:
    image = image[:, :, None]
  if image.ndim != 3 or image.shape[2] not in (1, 2, 3, 4):
    raise ValueError(f'Unmixer expects [H, W, 3] (RGB), [H, W, 4] (RGBA) or gray [H, W], '
                     f'got {image.shape}.')
  if image.shape[2] in (1, 2):
    return np.repeat(image[:, :, :1], 3, axis=2)
  return image[:, :, :3]


@dataclasses.dataclass(frozen=True)
class PredictorConfig:
  """Which unmixer to build (the tools' predictor flags).

  Attributes:
    method: a name of METHODS.
    checkpoint: run directory or checkpoint prefix ('model', 'oracle').
    saved_model: SavedModel directory ('model'); exclusive with checkpoint.
    mixture: the inputs' mixture operator; 'auto': detected per image (anaglyphs); None:
      the model's own (required for 'classical'). A model refuses encodings it was not
      trained on.
    restore_colour: restore both views from the encoding and the disparities with the
      network's views as the prior (paper 4.2; None: on for anaglyphs); 'model' only.
    disparity_range: (min, max) signed pixels of the input; None: estimated per image;
      disparity_range.NETWORK: the method's own (a network's [0, D - 1], input as is).
    max_network_pixels: a model's input is reduced to at most this many pixels.
    pretrained: a shipped model's name or folder ('model' without checkpoint and
      saved_model; None: the first shipped model for the mixture, `pretrained.choose`).
    swap_eyes: False: the left eye in the first filter's channels (red of red-cyan); True:
      swapped (cyan-red glasses, mirrored scans), unmixed mirrored; 'auto': detected per
      image, a video per shot (`eye_order`; anaglyphs, others keep the order given).
    mixing_weight: double images: the left view's weight a of I = a L + (1 - a) R; None:
      1/2 (`--mixture=diplopia` exactly), 'auto': estimated per image, or a number in (0, 1)
      (`hints.FrameHint.mixing_weight`).
    descreen: a printed image's halftone screen, smoothed before anything else
      (`classical.halftone`): 'off' (the paper's inputs), 'auto' (found per image, a
      video per shot; the tools' default) or its period in pixels.
    rectify: a tilted anaglyph or double image turned level (`unmixing.tilt`): 'off' (the
      paper's inputs) or 'auto' (estimated and checked per image, a video per shot; the
      tools' default).
  """
  method: str = 'model'
  checkpoint: Optional[str] = None
  saved_model: Optional[str] = None
  mixture: Optional[str] = None
  restore_colour: Optional[bool] = None
  disparity_range: Union[None, str, Tuple[int, int]] = None
  max_network_pixels: Optional[int] = 2_000_000
  pretrained: Optional[str] = None
  swap_eyes: Union[bool, str] = False
  mixing_weight: Union[None, float, str] = None
  descreen: Union[str, float] = halftone.OFF
  rectify: str = tilt.OFF

  def __post_init__(self):
    if self.rectify not in (tilt.AUTO, tilt.OFF):
      raise ValueError(f"PredictorConfig.rectify must be 'auto' or 'off', got "
                       f'{self.rectify!r}.')
    if self.descreen not in (halftone.AUTO, halftone.OFF):
      try:
        halftone.check_period(self.descreen)
      except (TypeError, ValueError) as e:
        raise ValueError(f'PredictorConfig.descreen: {e}') from None
    if self.restore_colour not in (None, True, False):
      raise ValueError('PredictorConfig.restore_colour must be None, True or False, got '
                       f'{self.restore_colour!r}.')
    if self.max_network_pixels is not None and not (
        isinstance(self.max_network_pixels, int) and self.max_network_pixels >= 1):
      raise ValueError('PredictorConfig.max_network_pixels must be a whole number of at '
                       f'least 1 (or None: no limit), got {self.max_network_pixels!r}.')
    weight = self.mixing_weight
    if weight is None or weight == diplopia_weight.AUTO:
      return
    try:
      if isinstance(weight, (bool, str)):  # Not a number ('auto' returned above).
        raise TypeError(weight)
      diplopia_weight.check_weight(weight)
    except (TypeError, ValueError):
      raise ValueError(f"PredictorConfig.mixing_weight must be None, 'auto' or a number in "
                       f'(0, 1), got {weight!r}.') from None


@dataclasses.dataclass(frozen=True)
class Unmixer:
  """A predictor: `unmixer(mixture_u8)`, or `unmixer(left_u8, right_u8)` when takes_pair.

  Called on a uint8 mixture [H, W, 3] it returns {'left', 'right': uint8 [H, W, 3] (a
  uint16 mixture is matched at 8 bits, its views made from it and returned as uint16
  where the encoding's views come from its samples: anaglyphs, double images; `steps.run`),
  'disparity_left', 'disparity_right': float32 [H, W] signed pixels, 'info': what was done
  (`steps`)}; an 'oracle' returns the disparities of the clean pair. A video frame
  may be given a `hints.FrameHint` (`unmixer(frame, hint=hint)`: its shot's encoding,
  range and prior); `fn` is then called with `hint=` as well.

  Attributes:
    fn: the function behind the call.
    method: the METHODS name that built it.
    mixture: the mixture its inputs are made with ('auto': detected per image).
    max_disparity: the largest disparity of its default range, pixels (display range).
    restore_colour: whether it restores the views from the encoding (paper 4.2).
    takes_pair: True for 'oracle' (inputs are the clean views).
  """
  fn: Callable[..., Outputs]
  method: str
  mixture: str
  max_disparity: float
  restore_colour: bool = False
  takes_pair: bool = False

  def __call__(self, *images: np.ndarray, hint=None) -> Outputs:
    for image in images:
      if max(np.shape(image)[:2]) >= MAX_SIDE:
        raise ValueError(f'A {image.shape[0]}x{image.shape[1]} image: sides of {MAX_SIDE} px '
                         "or more are beyond OpenCV's image warps; unmix it in parts.")
    return self.fn(*images) if hint is None else self.fn(*images, hint=hint)


def check_mixture(config: PredictorConfig, trained: Sequence[str]) -> str:
  """The mixture asked for (default: the model's first).

  Raises:
    ValueError: an encoding the model was not trained on.
  """
  requested = config.mixture or trained[0]
  if requested != mixture_choice.AUTO and mixtures.served_name(requested) not in trained:
    raise ValueError(f'PredictorConfig.mixture={requested} but the model was trained on '
                     f'{", ".join(repr(m) for m in trained)} mixtures '
                     f'({config.saved_model or config.checkpoint or "this model"}).')
  return requested


# Training modes that leave a network at its initial weights -> what that does to a mixture.
_UNTRAINED_PART = {
    'separation_only': 'its disparities come from a stereo network at its initial weights',
    'stereo_only': ('it learned disparities of clean pairs only; its views and the pair its '
                    'stereo network sees come from a separation network at its initial '
                    "weights (its own test is method 'oracle', on the clean pair)"),
}


def warn_if_untrained(run_info: runs.RunInfo, source: str) -> None:
  """Logs what a run trained with a mode that leaves a network untrained does to mixtures."""
  if run_info.mode in _UNTRAINED_PART:
    logging.warning('%s was trained with mode %s: %s.', source, run_info.mode,
                    _UNTRAINED_PART[run_info.mode])


def model_unmixer(graph: Callable[[tf.Tensor], Dict[str, tf.Tensor]], run_info: runs.RunInfo,
                  config: PredictorConfig = PredictorConfig()) -> Unmixer:
  """The 'model' Unmixer around a uint8 serving graph (`graphs.serving_function`) of a run."""
  trained = run_info.mixtures
  requested = check_mixture(config, trained)
  warn_if_untrained(run_info, config.checkpoint or config.saved_model)
  levels = run_info.model_config.max_disparity
  restore = config.restore_colour
  named = [requested] if requested != mixture_choice.AUTO else list(trained)
  if restore and not any(families.of(m).restores_views for m in named):
    raise ValueError(f'PredictorConfig.restore_colour=True restores anaglyph views; '
                     f'{", ".join(repr(m) for m in named)} mixtures have no channels to '
                     f'restore them from.')
  if restore is None:
    restore = any(families.of(m).restores_views for m in trained)

  source = ({'checkpoint': config.checkpoint} if config.checkpoint else
            {'saved_model': config.saved_model} if config.saved_model else {})

  def solve(image, name, search, hint):  # The network takes no prior.
    out = steps.model_unmix(graph, image, name, search, levels, config.max_network_pixels,
                            bool(restore), hints.views_image(image, hint))
    out['info'] = dict(out.get('info', {}), **source)  # Which trained network ran.
    return out

  return image_unmixer('model', requested, trained, config, lambda _: (0, levels - 1),
                        solve, levels, bool(restore))


def image_unmixer(method: str, requested: str, allowed: Sequence[str],
                   config: PredictorConfig, default_range: Callable[[str], Tuple[int, int]],
                   solve: Callable[..., Outputs], display: float, restore: bool,
                   plan: Optional[steps.Planner] = None) -> Unmixer:
  """An Unmixer of mixture images: `steps.run`'s steps around `solve` (and the method's
  own range planning `plan`, None: the family's)."""
  fn = lambda image, hint=None: steps.run(as_rgb(image), requested, allowed,
                                          config.disparity_range, default_range, method,
                                          solve, hint, config.swap_eyes,
                                          config.mixing_weight, plan, config.descreen,
                                          config.rectify)
  return Unmixer(fn, method, requested, display, restore)


def family_of(mixture: str) -> families.Family:
  """The family of a mixture name; for 'auto', the one detection finds."""
  return families.detected() if mixture == mixture_choice.AUTO else families.of(mixture)


def classical_range(mixture: str) -> Tuple[int, int]:
  """The classical method's own range for a mixture (`Family.classical_range`)."""
  return families.of(mixture).classical_range()


