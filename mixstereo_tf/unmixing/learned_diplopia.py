"""The learned echo stage of double images: learned self-similarity costs, SGM, layers.

A double image I = a L + (1 - a) R shows every surface twice; its self-similarity between
x and x - d peaks at the left disparity d_L(x) and at echoes of texture, and the classical
method scores it by ZNCC of the high-passed mixture (`diplopia_costs.self_matching_volume`).
Here:
  1. descriptors of the mixture (`matching_features.EchoFeatures`, trained on photographs
     warped by drawn disparity fields with a random weight a; `training/feature_loop.py`);
  2. cost volume over the positive lags: `zncc_weight` of the ZNCC cost plus the rest of
     (1 - cosine(here(x), there(x - d))) x `cost_scale` (`feature_costs.cosine_costs`), uint8;
  3. then as the classical method (`diplopia.unmix_diplopia` with these costs): SGM with
     its left-right check and filling, the mixing weight (1/2, given, or estimated:
     `diplopia_weight.resolve_weight`) and the regularised layer separation.
Disparities are positive by convention (docs/DESIGN.md): the copy further right is the
left eye's.
"""

import dataclasses
from typing import Callable, Dict, Optional, Tuple

import numpy as np
import tensorflow as tf

from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import diplopia_cepstrum
from mixstereo_tf.classical import diplopia_costs
from mixstereo_tf.classical import feature_costs
from mixstereo_tf.core import hints
from mixstereo_tf.core import workers
from mixstereo_tf.models import matching_features

Echo = Callable[[tf.Tensor], tf.Tensor]
_KEYS = ('left', 'right', 'disparity_left', 'disparity_right')


@dataclasses.dataclass(frozen=True)
class EchoConfig:
  """Parameters of the learned echo stage.

  Attributes:
    cost_scale: uint8 cost units per unit of 1 - cosine.
    zncc_weight: share of the classical ZNCC cost in the blended cost (0: learned only).
    penalties: SGM (P1, P2) on the blended cost: 8 / 64, those the stage was trained and
      measured with. The classical ZNCC's 16 / 160 (chosen for it on validation,
      2026-11-26) took the stage's held-out advantage away (wrong echoes on 5 procedural
      scenes 22.5% against classical's 22.6%, 21.2 against 24.9 before) and raised its
      bad-1 on every set of `learned_diplopia.md`.
  """
  cost_scale: float = 32.0
  zncc_weight: float = 0.5
  penalties: Tuple[int, int] = (8, 64)

  def __post_init__(self):
    if not 0 < self.cost_scale <= 127 or not 0 <= self.zncc_weight < 1:
      raise ValueError(f'EchoConfig needs 0 < cost_scale <= 127 and zncc_weight in [0, 1); '
                       f'got {self}.')


def echo_function(model: matching_features.EchoFeatures) -> Echo:
  """The model as a traced function of a mixture [1, H, W, 3] in [0, 1] -> (here, there)."""
  signature = [tf.TensorSpec([1, None, None, 3], tf.float32)]
  return tf.function(lambda mixture: model(mixture), input_signature=signature)


def echo_costs(echo: Echo, config: EchoConfig = EchoConfig()) -> diplopia.Costs:
  """The stage's cost function for `diplopia.unmix_diplopia` (steps 1-2)."""

  def costs(mixture01: np.ndarray, diplopia_config: diplopia.DiplopiaConfig) -> np.ndarray:
    matching = diplopia_config.matching
    low = matching.min_disparity
    high = min(matching.max_disparity, mixture01.shape[1] - 1)
    here, there = echo(tf.constant(mixture01[None], tf.float32))
    volume = feature_costs.cosine_costs(here[0].numpy(), there[0].numpy(), low,
                                        high - low + 1, config.cost_scale,
                                        threads=workers.usable_cpus())
    if config.zncc_weight:
      zncc = diplopia_costs.zncc_costs(mixture01, diplopia_config)
      volume = feature_costs.blend(zncc, volume, config.zncc_weight, workers.usable_cpus())
    return volume

  return costs


def learned_unmix(echo: Echo, image: np.ndarray, name: str, search: Tuple[int, int],
                  hint: Optional[hints.FrameHint] = None,
                  config: EchoConfig = EchoConfig()) -> Dict[str, object]:
  """The stage on a uint8 double image: the views (from the hint's stored_image where it
  has one: a 16-bit mixture's layers at 16 bits), both disparities and, in 'info', the
  mixing weight used (`hint.mixing_weight`: None 1/2, 'auto' estimated, or given)."""
  del name  # One encoding: the double image.
  hint = hint or hints.FrameHint()
  # Without the classical matcher's echo score (2026-11-29): its weight is in ZNCC cost
  # units, and this stage was trained and measured without it.
  classical = diplopia.DiplopiaConfig(cepstrum=diplopia_cepstrum.CepstrumConfig(weight=0.0))
  p1, p2 = config.penalties
  matching = dataclasses.replace(classical.matching, p1=int(p1), p2=int(p2))
  out = diplopia.unmix_diplopia(image, search, weight=hint.mixing_weight,
                                config=dataclasses.replace(classical, matching=matching),
                                costs=echo_costs(echo, config), prior=hint.prior,
                                prior_window=hint.prior_window,
                                on_disparity=hint.on_disparity,
                                views_image=hint.stored_image)
  outputs = {key: out[key] for key in _KEYS}
  outputs['info'] = diplopia.weight_record(out)
  return outputs
