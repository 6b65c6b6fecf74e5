"""The double-image matcher's cost volume (`diplopia`, step 2): ZNCC of the mixture against
itself, corrected for self-similarity, the penalty of the smallest lags in a wide range and
a video frame's temporal prior.

`config` is a `diplopia.DiplopiaConfig`: its `matching` range, window, high-pass, cost scale,
small-lag and prior fields.
"""

from typing import Tuple

import cv2
import numpy as np

from mixstereo_tf.classical import parallel_sgm
from mixstereo_tf.classical import search_windows
from mixstereo_tf.classical import zncc_kernel
from mixstereo_tf.core import workers


def self_matching_volume(gray: np.ndarray, config) -> np.ndarray:
  """ZNCC costs of the high-passed mixture against itself, corrected for self-similarity.

  A linear score suits an additive mixture: I(x) and I(x - d_L) share one of their two
  components, a normalised correlation of about 1/2, where census codes barely react.
  The image is high-passed (minus a Gaussian blur) and compared in (2r+1)^2 windows; the
  cost is (1 - zncc) * `cost_scale`. Neighbouring pixels of a smooth image correlate, so
  the cost rises from lag 0 towards the level of unrelated texture over a few pixels and
  would favour the smallest lags: the expected cost of lag d without an echo is estimated
  by the upper envelope (running maximum over lags) of the image-mean cost per lag, which
  an echo only lowers, and each lag gets the penalty (envelope maximum - envelope(d)).
  The window sums run in `zncc_kernel` (row blocks in threads); above
  `config.max_float_mib` of float costs they run twice instead of storing them.

  Args:
    gray: float [H, W] mixture intensities.
    config: window, high-pass and disparity range.

  Returns:
    uint8 [H, W, D] left-referenced costs, d_i = min_disparity + i (as `sgm.cost_volume`).

  Raises:
    ValueError: no lag of the range fits in the image (a 1-px strip).
  """
  matching = config.matching
  height, width = gray.shape
  max_disparity = min(matching.max_disparity, width - 1)
  high = (gray - cv2.GaussianBlur(gray, (0, 0), config.highpass_sigma)).astype(np.float32)
  window = (2 * config.window_radius + 1,) * 2
  energy = cv2.boxFilter(high * high, -1, window)
  lags = np.arange(matching.min_disparity, max_disparity + 1, dtype=np.int64)
  if not lags.size:
    raise ValueError(f'a {height}x{width} image has no lag of [{matching.min_disparity}, '
                     f'{matching.max_disparity}] to match (the width allows {width - 1}).')
  threads = workers.usable_cpus(0)
  blocks = workers.row_blocks(height, 4 * threads)
  stored = 4 * height * width * lags.size <= config.max_float_mib << 20
  costs = np.empty((height, width, lags.size), np.float32) if stored else None

  def kernel(out, penalty):
    return parallel_sgm.run_blocks(zncc_kernel.zncc_rows, blocks, threads, high, energy,
                                   int(lags[0]), lags.size, config.window_radius,
                                   np.float32(config.cost_scale), out, penalty,
                                   partial=lags.size)

  sums = kernel(costs, None)
  envelope = np.maximum.accumulate(sums / (height * (width - lags)))  # Mean cost per lag.
  penalty = (envelope.max() - envelope).astype(np.float32)
  volume = np.empty((height, width, lags.size), np.uint8)
  if stored:
    parallel_sgm.run_blocks(zncc_kernel.quantize_rows, blocks, threads, costs, penalty,
                            volume)
  else:
    kernel(volume, penalty)
  return volume


def small_lags(config) -> int:
  """How many of config.matching's lags lie below `min_lag` in a range reaching 4 x min_lag
  or more (0 in a narrower one: copies that close keep their lags as they are)."""
  matching = config.matching
  if matching.max_disparity < 4 * config.min_lag:
    return 0
  return max(0, config.min_lag - matching.min_disparity)


def penalise_small_lags(volume: np.ndarray, config) -> np.ndarray:
  """Adds `small_lag_penalty` (saturating) to the `small_lags` of a uint8 [H, W, D] volume
  over config.matching's lags, in place; returns the volume."""
  count = small_lags(config)
  if count and config.small_lag_penalty:
    small = volume[..., :count]
    np.minimum(small.astype(np.int16) + config.small_lag_penalty, 255, out=small,
               casting='unsafe')
  return volume


def gray_255(image01: np.ndarray) -> np.ndarray:
  """The channel mean of float [H, W, 3] [0, 1] values in 0..255 units: image01.mean(-1) *
  255 bit for bit (the same three additions in order), without NumPy's slow reduction
  over a short last axis."""
  if image01.shape[-1] != 3:
    return image01.mean(axis=-1) * 255.0
  return (image01[..., 0] + image01[..., 1] + image01[..., 2]) / 3 * 255.0


def zncc_costs(mixture01: np.ndarray, config) -> np.ndarray:
  """`self_matching_volume` of the mixture's channel mean (0..255 units)."""
  return self_matching_volume(gray_255(mixture01), config)


def add_prior(volume: np.ndarray, config, prior: np.ndarray,
              window: Tuple[int, int]) -> np.ndarray:
  """`volume` (uint8 [H, W, D] over config.matching's lags) with a temporal prior's penalty
  added in place: min(config.prior_weight * distance, config.prior_cap) cost units, the
  distance in pixels from each lag to the window of `search_windows.around_prior(prior,
  ..., *window)` (0 inside; NaN priors give whole-range windows); returns it.

  Raises:
    ValueError: a prior whose shape is not the volume's [H, W].
  """
  if prior.shape != volume.shape[:2]:
    raise ValueError(f'The prior is {prior.shape}; the frame is {volume.shape[:2]}.')
  low, high = config.matching.min_disparity, config.matching.max_disparity
  lo, widths = search_windows.around_prior(prior, low, high, *window)
  threads = workers.usable_cpus(0)
  parallel_sgm.run_blocks(zncc_kernel.prior_rows, workers.row_blocks(len(volume), threads),
                          threads, lo, widths, low, config.prior_weight, config.prior_cap,
                          volume)
  return volume
