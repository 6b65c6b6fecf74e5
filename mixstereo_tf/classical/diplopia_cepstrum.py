"""A regional echo score for the double-image matcher (`diplopia`, step 2): the local power
cepstrum of the mixture's rows, added to the self-matching costs.

An echo I(x) = a L(x) + (1 - a) L(x + d) multiplies the power spectrum of a row segment by
|a + (1 - a) e^{i w d}|^2, and the log turns that factor into a term added to the image's own
log spectrum; its inverse transform (the power cepstrum) has a peak at quefrency d and, of
the opposite sign, at 2d (the series of log|1 + r e^{i w d}|^2 alternates in sign: r, -r^2 / 2,
...). The image's own spectrum is smooth in w and stays at small quefrencies, so unlike a
window correlation the cepstrum does not favour lags at which the image merely resembles
itself (smooth regions, blur). A periodic texture of period p gives peaks of one sign at p
and 2p, which the rahmonic term (score(d) = c(d) - rahmonic x c(2d)) counts against it.
Not in the paper (its diplopia path is learned end to end); chosen on validation double
images, docs/LEARNED_DIPLOPIA.md ("A regional echo score").

Scores are computed on a coarse grid (windows `rows` x `window` px every `row_step` rows
and `step` columns), standardised per lag (the median and the median absolute deviation
over the grid, each smoothed by a running median over the lags, so that an echo shared by
the whole image keeps its score; the ZNCC costs are likewise corrected per lag for
self-similarity), and each lag's cost gets weight x (clip - clip(score)) units, bilinearly
interpolated between the grid points. Video frames with a temporal prior skip it
(`CepstrumConfig.with_prior`).
"""

import dataclasses

import cv2
import numba
import numpy as np
import scipy.fft

from mixstereo_tf.classical import parallel_sgm
from mixstereo_tf.core import workers


BLUR_SIGMA = 16.0  # px: what is subtracted before the spectra (the scratch study's choice).
LAG_SPAN = 9  # Lags of the running median that sets each lag's level and spread.
CHUNK_ROWS = 16  # Grid rows transformed together (memory: their rows' spectra).
# The widest window, a share of the image's width, chosen on two validation sets
# (docs/LEARNED_DIPLOPIA.md): the temporal clip (320 x 180; the default per shot, bad-1
# 42.1% at 0.5, 46.4% at 0.75) and the refiner's validation examples (160 x 320 and
# 320 x 640; mean classical bad-1 51.9% at 0.5, 51.7% at 0.75 and at 1).
MAX_WIDTH_SHARE = 0.5


@dataclasses.dataclass(frozen=True)
class CepstrumConfig:
  """The echo score's parameters (chosen on the 16 validation double images of
  `experiments/diplopia_validation.py`, docs/LEARNED_DIPLOPIA.md).

  Attributes:
    weight: cost units per standardised score unit (0: off). 1.5: validation bad-1 30.4
      -> 24.3% (1: 24.4%, 2: 24.6%; with noise on each view, scratch, 48.4 -> 38.8%).
    clip: standardised scores are clipped to [-clip, clip] (so a lag costs at most
      2 x clip x weight more).
    rahmonic: the share of the score at 2d taken from the score at d (validation bad-1
      24.3% at 1, 25.8% at 0).
    rows, window: the window, rows x columns; the window grows to the power of two that
      holds twice the largest lag (the cepstrum of n samples resolves quefrencies up to
      n / 2), at most half the image's width (`window_width`). 4 rows: 24.2%; a window
      of at least 256: 25.1%.
    row_step, step: the grid's spacing, rows and columns (step 8: 24.4% for twice the
      transforms; row_step 8: 24.5%).
    with_prior: also on video frames with a temporal prior (False: a shot's later frames
      inherit the echo choice through the prior and skip the score's time).
  """
  weight: float = 1.5
  clip: float = 4.0
  rahmonic: float = 1.0
  rows: int = 8
  window: int = 128
  row_step: int = 4
  step: int = 16
  with_prior: bool = False

  def __post_init__(self):
    if self.weight < 0 or self.clip <= 0 or self.rahmonic < 0:
      raise ValueError(f'CepstrumConfig needs weight >= 0, clip > 0 and rahmonic >= 0, got '
                       f'{self.weight}, {self.clip} and {self.rahmonic}.')
    if min(self.rows, self.window, self.row_step, self.step) < 1:
      raise ValueError(f'CepstrumConfig sizes must be >= 1, got rows {self.rows}, window '
                       f'{self.window}, row_step {self.row_step}, step {self.step}.')


def window_width(config: CepstrumConfig, max_lag: int, image_width: int) -> int:
  """The window's columns: config.window, doubled until it holds 2 x max_lag + 4, but at
  most MAX_WIDTH_SHARE of the image's width (even; at least config.window / 2): a window
  as wide as the image sees mostly the reflected padding, whose mirror images read as
  echoes."""
  width = config.window
  while width < 2 * max_lag + 4:
    width *= 2
  return min(width, max(config.window // 2, 2 * int(MAX_WIDTH_SHARE * image_width / 2)))


def echo_scores(gray: np.ndarray, low: int, high: int, config: CepstrumConfig) -> np.ndarray:
  """Standardised echo scores of lags low..high at the coarse grid.

  Args:
    gray: float [H, W] intensities (any units).
    low, high: the lags, pixels, 1 <= low <= high.
    config: the window and grid.

  Returns:
    float32 [ceil(H / row_step), ceil(W / step), high - low + 1]: at grid point (i, j),
    centred on pixel (i row_step, j step), lag low + k's score less its level, in units
    of its spread (the median and the median absolute deviation over the grid, each a
    running median over LAG_SPAN lags; higher: more of an echo); 0 (no evidence either
    way) for lags above what the window resolves (`window_width`: half its width - 2).
  """
  gray = np.asarray(gray, np.float32)
  size = window_width(config, high, gray.shape[1])
  detail = gray - cv2.GaussianBlur(gray, (0, 0), BLUR_SIGMA)  # Spectra without their DC.
  padded = np.pad(detail, ((config.rows // 2, config.rows // 2), (size // 2, size // 2)),
                  mode='reflect')
  # Every row's windows (a view), each transformed once and shared by the bands it is in.
  windows = np.lib.stride_tricks.sliding_window_view(padded, size, axis=1)[
      :, :gray.shape[1]:config.step]
  lags = np.arange(low, min(high, size // 2 - 2) + 1)
  grid_rows = range(0, gray.shape[0], config.row_step)
  scores = np.zeros((len(grid_rows), windows.shape[1], high - low + 1), np.float32)
  if not len(lags):
    return scores
  for first in range(0, len(grid_rows), CHUNK_ROWS):
    ys = np.asarray(grid_rows[first:first + CHUNK_ROWS])
    scores[first:first + len(ys), :, :len(lags)] = _cepstra(windows, ys, size, lags, config)
  resolved = scores[..., :len(lags)]
  baseline = _along_lags(np.median(resolved, axis=(0, 1)))
  spread = _along_lags(np.median(np.abs(resolved - baseline), axis=(0, 1))) + 1e-9
  resolved[...] = (resolved - baseline) / spread
  return scores


def _cepstra(windows: np.ndarray, ys: np.ndarray, size: int, lags: np.ndarray,
             config: CepstrumConfig) -> np.ndarray:
  """float32 [len(ys), columns, lags] rahmonic-corrected power cepstra of the bands of
  config.rows padded rows starting at `ys` (`windows`: [rows, columns, size] views)."""
  top, threads = ys[0], workers.usable_cpus(0)
  rows = windows[top:ys[-1] + config.rows] * np.hanning(size).astype(np.float32)
  power = np.abs(scipy.fft.rfft(rows, axis=-1, workers=threads)) ** 2
  band = sum(power[ys - top + r] for r in range(config.rows)) / config.rows
  floor = 1e-3 * band.mean(axis=-1, keepdims=True) + 1e-9
  cepstrum = scipy.fft.irfft(np.log(band + floor), n=size, axis=-1, workers=threads)
  doubled = 2 * lags <= size // 2
  rahmonic = np.where(doubled, config.rahmonic, 0.0).astype(np.float32)
  return cepstrum[..., lags] - rahmonic * cepstrum[..., np.minimum(2 * lags, size // 2)]


def _along_lags(values: np.ndarray) -> np.ndarray:
  """The running median of float [D] `values` over LAG_SPAN lags (edges repeated): a
  per-lag level that an echo shared by the whole image (a spike at its lag) does not
  raise."""
  half = LAG_SPAN // 2
  padded = np.pad(values, half, mode='edge')
  return np.median(np.lib.stride_tricks.sliding_window_view(padded, LAG_SPAN), axis=-1)


def add_echo_costs(volume: np.ndarray, gray: np.ndarray, low: int,
                   config: CepstrumConfig) -> np.ndarray:
  """`volume` (uint8 [H, W, D], lags low + i, left-referenced) with weight x (clip -
  clip(echo score)) cost units added in place, saturating at 255; returns it. A zero
  weight leaves it as it is."""
  if config.weight == 0:
    return volume
  scores = echo_scores(gray, low, low + volume.shape[2] - 1, config)
  added = (config.weight * (config.clip - np.clip(scores, -config.clip, config.clip))
           ).astype(np.float32)
  threads = workers.usable_cpus(0)
  parallel_sgm.run_blocks(_add_rows, workers.row_blocks(len(volume), threads), threads,
                          added, config.row_step, config.step, volume)
  return volume


@numba.njit(nogil=True, cache=True, error_model='numpy')
def _add_rows(y0, y1, added, row_step, step, volume):
  """volume[y, x, i] += round(bilinear `added` at (y / row_step, x / step), lag i),
  saturating at 255, for rows [y0, y1)."""
  rows, columns, lags = added.shape
  blended = np.empty((columns, lags), np.float32)  # This row's values at the grid columns.
  for y in range(y0, y1):
    fy = min(y / row_step, rows - 1.0)
    i0 = min(int(fy), max(rows - 2, 0))
    i1 = min(i0 + 1, rows - 1)
    ty = np.float32(fy - i0)
    for j in range(columns):
      for k in range(lags):
        blended[j, k] = (1 - ty) * added[i0, j, k] + ty * added[i1, j, k]
    for x in range(volume.shape[1]):
      fx = min(x / step, columns - 1.0)
      j0 = min(int(fx), max(columns - 2, 0))
      j1 = min(j0 + 1, columns - 1)
      tx = np.float32(fx - j0)
      for k in range(lags):
        value = (1 - tx) * blended[j0, k] + tx * blended[j1, k]
        volume[y, x, k] = np.uint8(min(np.int32(volume[y, x, k]) + np.int32(value + 0.5),
                                       np.int32(255)))
