"""Training-free de-diplopia: shift estimation by self-matching, layers by least squares.

The mixture is I = (L + R) / 2 on one pixel grid. With the right pixel x matching the left
pixel x + d_R(x) (docs/DESIGN.md), R(x) = L(x + d_R(x)) wherever the right pixel is visible
in the left view, so

    I(x) = (L(x) + L(x + d_R(x))) / 2,

one linear equation per pixel in the unknown left view. Steps:
  1. Global shift (reported, not used further): the power cepstrum of the rows peaks at
     the dominant echo delay (classic echo detection; the autocorrelation of natural
     images peaks at lag 1 instead).
  2. Per-pixel shifts: I(x) and I(x - d_L(x)) share the component L(x), so SGM on a ZNCC
     volume of the mixture against itself (`diplopia_costs.self_matching_volume`, lags from
     `min_disparity` >= 1 up; in a wide range the lags below `min_lag` penalised; plus a
     regional echo score from the local power cepstrum, `diplopia_cepstrum`) gives d_L,
     the volume's diagonal search d_R; then the left-right check and filling of `sgm`
     (`parallel_sgm.match_volume`). Images wider than `max_width` are matched on a
     reduced copy (`working_scale`).
  3. Layers: a regularised least squares for L given d_R, then R = (I - a L) / (1 - a)
     (`diplopia_layers.separate_layers`, weight a), at full size.

Ambiguity: (L, R, d) and (R, L, -d) give the same symmetric average; positive disparities
(the left camera on the left) decide which layer is left.
"""

import dataclasses
from typing import Callable, Dict, Optional, Tuple, Union

from absl import logging
import numpy as np

from mixstereo_tf.classical import diplopia_cepstrum
from mixstereo_tf.classical import diplopia_costs
from mixstereo_tf.classical import diplopia_layers
from mixstereo_tf.classical import diplopia_weight
from mixstereo_tf.classical import parallel_sgm
from mixstereo_tf.classical import sgm
from mixstereo_tf.classical import working_scale
from mixstereo_tf.core import image_range
from mixstereo_tf.core import planning_copies
from mixstereo_tf.core import workers

Costs = Callable[[np.ndarray, 'DiplopiaConfig'], np.ndarray]


@dataclasses.dataclass(frozen=True)
class DiplopiaConfig:
  """Parameters of the de-diplopia baseline. Each value was chosen on validation double
  images or a validation clip; the measurements are in docs/DESIGN.md and
  docs/LEARNED_DIPLOPIA.md (`experiments/results/diplopia_validation.md`).

  Attributes:
    matching: SGM parameters of the self-matching (min_disparity >= 1; the census
      fields unused). P1 16, P2 160 (8 / 64 before 2026-11-26: validation bad-1 38.7 ->
      35.0%); `diplopia_range.estimate_range` keeps its own (`RANGE_PENALTIES`).
    window_radius: ZNCC window radius, pixels: 7 (3 before 2026-11-26: validation bad-1
      40.8 -> 35.0%); the echo shares only half of each window's signal.
    highpass_sigma, cost_scale: the high-pass' Gaussian sigma, pixels; units per 1 - zncc.
    layers: prior weights and solver of the layer separation.
    prior_weight, prior_cap: a video frame's temporal prior (`unmix_diplopia(prior=)`):
      each lag costs prior_weight units per pixel outside the window around the previous
      frame's disparity (`search_windows.around_prior`), at most prior_cap; 4 and 16,
      chosen on a validation clip (flicker 3.05 -> 1.04 px, bad-1 58.5 -> 53.8%).
    min_lag, small_lag_penalty: lags below min_lag cost small_lag_penalty more where the
      range reaches 4 x min_lag or more (`diplopia_costs.penalise_small_lags`): at lags of
      1-3 px the windows compare neighbouring pixels, which blur and noise correlate
      whatever the echo. 4 and 8, chosen on validation and on the temporal clip
      (LEARNED_DIPLOPIA.md).
    cepstrum: the regional echo score added to the costs (`diplopia_cepstrum`, since
      2026-11-29: validation bad-1 30.4 -> 24.3%; weight 0 turns it off).
    max_width: the self-matching (costs, SGM, the weight) runs on a copy reduced
      ceil(W / max_width) times (`working_scale`; 0: never; W a frame's width:
      `planning_copies`), the layers at full size. 1280, chosen on large validation
      double images (docs/LEARNED_DIPLOPIA.md "Large images": bad-1 54.1 -> 43.6% at
      1920 x 1080, 84.4 -> 52.2% at 4000 x 3000); frames up to 1280 px wide, the
      evaluation frames and 720p video, are not reduced.
    max_float_mib, max_strip_mib: memory bounds. Above max_float_mib of float32 costs
      (4 H W D bytes) the ZNCC kernel runs twice (per-lag means, then the uint8 volume:
      the same volume); SGM runs in strips of at most max_strip_mib of path sums
      (`parallel_sgm.match_cost_volume`; 720p and 1080p frames keep one strip per core).
  """
  matching: sgm.SgmConfig = sgm.SgmConfig(min_disparity=1, p1=16, p2=160)
  window_radius: int = 7
  highpass_sigma: float = 1.0
  cost_scale: float = 32.0
  layers: diplopia_layers.LayerConfig = diplopia_layers.LayerConfig()
  prior_weight: int = 4
  prior_cap: int = 16
  min_lag: int = 4
  small_lag_penalty: int = 8
  cepstrum: diplopia_cepstrum.CepstrumConfig = diplopia_cepstrum.CepstrumConfig()
  max_width: int = 1280
  max_float_mib: int = 1024
  max_strip_mib: int = 512

  def __post_init__(self):
    if not 0 <= self.prior_weight <= 255 or not 0 <= self.prior_cap <= 255:
      raise ValueError(f'DiplopiaConfig.prior_weight and prior_cap must lie in [0, 255] '
                       f'(uint8 cost units), got {self.prior_weight} and {self.prior_cap}.')
    if self.min_lag < 1 or not 0 <= self.small_lag_penalty <= 255:
      raise ValueError(f'DiplopiaConfig.min_lag must be >= 1 and small_lag_penalty in '
                       f'[0, 255] (uint8 cost units), got {self.min_lag} and '
                       f'{self.small_lag_penalty}.')
    for field in ('max_width', 'max_float_mib', 'max_strip_mib'):
      if getattr(self, field) < 0:
        raise ValueError(f'DiplopiaConfig.{field} must be >= 0, got {getattr(self, field)}.')
    if self.matching.min_disparity < 1:
      raise ValueError('Diplopia self-matching needs matching.min_disparity >= 1 (lag 0 '
                       'matches every image to itself).')


def check_size(shape: Tuple[int, ...], config: DiplopiaConfig) -> None:
  """ValueError naming the size of an image [H, W, ...] smaller than the ZNCC window (too
  small to tell echoes from texture; a 1-px strip has no lag at all)."""
  side = 2 * config.window_radius + 1
  if shape[0] < side or shape[1] < side:
    raise ValueError(f'a {shape[0]}x{shape[1]} image is smaller than the double-image '
                     f"matcher's ZNCC window of {side}x{side} pixels.")


def _self_match(image, config, weight, costs, prior, prior_window):
  """Step 2 and the weight on the copy reduced to `config.max_width` (`working_scale`):
  ({'disparity_left', 'disparity_right'} at full size, (the a used, a note or None):
  `diplopia_weight.resolve_weight`)."""
  matching = config.matching
  copy = working_scale.reduce(image, working_scale.factor(
      planning_copies.frame_width(image.shape), config.max_width),
                              (matching.min_disparity, matching.max_disparity), prior)
  config = dataclasses.replace(config, matching=dataclasses.replace(
      matching, min_disparity=copy.search[0], max_disparity=copy.search[1]))
  echo = config.cepstrum.weight > 0 and (copy.prior is None or config.cepstrum.with_prior)
  # ZNCC's and the echo score's image (none where a learned stage's costs stand alone).
  gray = diplopia_costs.gray_255(copy.image) if costs is None or echo else None
  volume = (diplopia_costs.self_matching_volume(gray, config) if costs is None
            else costs(copy.image, config))
  diplopia_costs.penalise_small_lags(volume, config)
  if echo:
    diplopia_cepstrum.add_echo_costs(volume, gray, config.matching.min_disparity,
                                     config.cepstrum)
  if copy.prior is not None:
    diplopia_costs.add_prior(volume, config, copy.prior, prior_window or (1, 2))
  matched = parallel_sgm.match_volume(volume, config.matching,
                                     threads=workers.usable_cpus(0),
                                     max_strip_mib=config.max_strip_mib)
  del volume  # H x W x D bytes, not held through the layer solve.
  resolved = diplopia_weight.resolve_weight(weight, copy.image, matched['disparity_left'],
                                            matched['consistent_left'])  # (a, note).
  if resolved[1]:
    logging.warning('--mixing_weight=auto: %s.', resolved[1])
  return {key: working_scale.enlarge(matched[key], image.shape[:2], copy.scale)
          for key in ('disparity_left', 'disparity_right')}, resolved


def _searching(config: DiplopiaConfig, disparity_range: Optional[Tuple[int, int]]
               ) -> DiplopiaConfig:
  """`config` searching `disparity_range` (None: its own), or ValueError naming a range
  that is not 1 <= min < max."""
  if disparity_range is None:
    return config
  low, high = disparity_range
  if not 1 <= low < high:
    raise ValueError(f'A diplopia disparity range must satisfy 1 <= min < max (the views '
                     f'of an average are ordered by positive disparity), got {low},{high}.')
  return dataclasses.replace(config, matching=dataclasses.replace(
      config.matching, min_disparity=int(low), max_disparity=int(high)))


def unmix_diplopia(mixture, disparity_range: Optional[Tuple[int, int]] = None,
                   config: Optional[DiplopiaConfig] = None,
                   weight: Union[None, float, str] = None,
                   costs: Optional[Costs] = None, prior: Optional[np.ndarray] = None,
                   prior_window: Optional[Tuple[int, int]] = None,
                   on_disparity: Optional[Callable[[Dict[str, np.ndarray]], None]] = None,
                   views_image: Optional[np.ndarray] = None) -> Dict[str, object]:
  """Separates a double image I = a L + (1 - a) R into two views and disparities.

  Args:
    mixture: uint8 [H, W, 3] RGB, or float in [0, 1].
    disparity_range: (min, max) pixels to search, min >= 1 (the average is symmetric in
      the views, so disparities are positive by convention; lag 0 matches every image to
      itself); None: the config's range.
    config: parameters (default `DiplopiaConfig()`).
    weight: a; None: 1/2, 'auto': estimated (`diplopia_weight.resolve_weight`).
    costs: (mixture float [H, W, 3] in [0, 1], config) -> the uint8 [H, W, D] self-matching
      volume over config.matching's lags (None: `diplopia_costs.zncc_costs`; a learned
      stage's otherwise).
    prior: float [H, W], the previous video frame's left disparity (NaN: none there), or
      None; lags outside its window are penalised (`diplopia_costs.add_prior`).
    prior_window: (radius, spread) of `search_windows.around_prior` (None: 1, 2).
    on_disparity: called with both disparities once they are matched, before the layers
      are solved (`hints.FrameHint.on_disparity`).
    views_image: uint16 [H, W, 3], the mixture as stored where `mixture` is its 8-bit copy
      (`image_range.eight_bits`): the layers are solved from it and returned as uint16;
      None: from `mixture`.

  Returns:
    'left', 'right': uint8 [H, W, 3] (uint16 with a views_image); 'right_warped': the
    left layer sampled at x + d_R, as 'right' (`separate_layers`); 'disparity_left',
    'disparity_right': float32 [H, W], pixels, positive; 'disparity_range': the (min, max)
    searched; 'mixing_weight': the a used; 'mixing_weight_note' where 'auto' found no
    clear echo and used 1/2 (`diplopia_weight.NO_ECHO`).

  Raises:
    ValueError: a range with min < 1 or min >= max, no lag of it within the image, or a
      views_image of another shape.
  """
  config = _searching(config or DiplopiaConfig(), disparity_range)
  image = image_range.as_unit_float(mixture, 'mixture')
  if views_image is not None and np.shape(views_image) != image.shape:
    raise ValueError(f'views_image has shape {np.shape(views_image)}, the mixture '
                     f'{image.shape}: it must be the same image, stored at 16 bits.')
  matched, (weight, weight_note) = _self_match(image, config, weight, costs, prior,
                                              prior_window)
  if on_disparity is not None:
    on_disparity(dict(matched))
  depth = np.uint8 if views_image is None else np.asarray(views_image).dtype
  layers = diplopia_layers.separate_layers(
      image if views_image is None else image_range.as_unit_float(views_image, 'views_image'),
      matched['disparity_right'], config.layers, weight)
  return {**{key: image_range.unit_to(layers[key], depth)
             for key in ('left', 'right', 'right_warped')},
          'disparity_left': matched['disparity_left'],
          'disparity_right': matched['disparity_right'],
          'disparity_range': (config.matching.min_disparity, config.matching.max_disparity),
          'mixing_weight': weight,
          **({'mixing_weight_note': weight_note} if weight_note else {})}


def weight_record(out: Dict[str, object]) -> Dict[str, object]:
  """What an info file records of `unmix_diplopia`'s weight: 'mixing_weight' (rounded to
  3 decimals) and its 'mixing_weight_note' where it has one."""
  note = out.get('mixing_weight_note')
  return {'mixing_weight': round(float(out['mixing_weight']), 3),
          **({'mixing_weight_note': note} if note else {})}
