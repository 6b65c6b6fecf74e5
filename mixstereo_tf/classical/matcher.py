"""Census-SGM stereo on signed disparity ranges, at any image size, in bounded memory.

    out = match(left, right, min_disparity, max_disparity, config)          # full range
    out = match(left, right, min_disparity, max_disparity, config, prior)   # video frame
    min_disparity, max_disparity = estimate_range(left, right, config)      # no range known

The cost, aggregation and post-processing are those of `sgm.match` (census 7x9 per channel,
Hamming cost averaged over all channel pairs, 4-path SGM, winner-take-all + parabola, the
right disparity from the diagonal, 3x3 median, left-right check, background-favouring
fill), run by the numba kernels of `census_sgm` (through `parallel_sgm`) on per-pixel
disparity windows:
  * full search: every pixel searches [min_disparity, max_disparity];
  * prior (e.g. the previous video frame's left disparity): pixel (y, x) searches the
    prior's [min, max] over its (2 * spread + 1)^2 neighbourhood widened by `radius`
    (`search_windows.around_prior`), so windows are narrow on smooth surfaces and wide
    only along depth edges, which may move by up to `spread` px;
  * coarse-to-fine, chosen by `match` above MatcherConfig.full_search_cells: the full range
    at 1/f scale (area downsampling, `coarse_factor`), then windows around the upsampled
    result (radius ceil(f) + 2, spread ceil(f) + 1) at full scale.
Signs (docs/DESIGN.md, here signed): the left pixel x matches the right pixel x - d_L, the
right pixel x matches the left pixel x + d_R; 'background' = the smaller disparity.
Threads and memory: see `parallel_sgm` (strips of at most MatcherConfig.max_strip_mib each,
MatcherConfig.threads of them at a time). A 4000x3000 pair with a +-181 or +-300 px range
(coarse-to-fine x4) peaks ~1.3 GiB above the memory held before the call.
"""

import dataclasses
import math
from typing import Optional, Tuple

import cv2
import numpy as np

from mixstereo_tf.classical import fast_postprocess
from mixstereo_tf.classical import parallel_sgm
from mixstereo_tf.classical import search_windows
from mixstereo_tf.core import planning_copies
from mixstereo_tf.core import workers


@dataclasses.dataclass(frozen=True)
class MatcherConfig:
  """Parameters of `match` and `estimate_range`.

  Attributes:
    census_height, census_width: odd census window (at most 65 pixels: 64-bit codes).
    p1, p2: SGM penalties for a 1 px / a larger disparity change between neighbours
      (census bits).
    lr_threshold: largest accepted |d_L(x) - d_R(x - d_L(x))|, pixels.
    full_search_cells: above H * W * D cells (D disparities) `match` goes coarse-to-fine.
    prior_radius: pixels added on both sides of a prior's local [min, max].
    prior_spread: the local [min, max] of a prior is taken over (2 * spread + 1)^2 pixels.
    prior_missing_spread: where the prior is NaN, over (2 * this + 1)^2 pixels.
    threads: worker threads; 0 = every CPU this process may use.
    strips: horizontal strips; 0 = max(threads, what max_strip_mib needs); 1 = exactly
      `sgm.match` (one strip holds 2 bytes per searched cell of the image).
    strip_overlap: rows a strip adds above and below for its vertical paths.
    max_strip_mib: aggregated costs of one strip when strips = 0, MiB.
    range_width, range_fraction: `estimate_range` searches an area-downsampled copy this
      wide, pixels (a frame's: `planning_copies`), over +- this fraction of that width.
    range_density: `estimate_range` keeps the disparities d whose window [d - 2, d + 2]
      holds at least this share of the left-right consistent pixels ...
    range_margin: ... widened by this many pixels of the downsampled copy on each side.
  """
  census_height: int = 7
  census_width: int = 9
  p1: int = 12
  p2: int = 80
  lr_threshold: float = 1.0
  full_search_cells: int = 200_000_000
  prior_radius: int = 4
  prior_spread: int = 4
  prior_missing_spread: int = 4
  threads: int = 0
  strips: int = 0
  strip_overlap: int = 32
  max_strip_mib: int = 256
  range_width: int = 320
  range_fraction: float = 1.0 / 3.0
  range_density: float = 0.01
  range_margin: float = 3.0

  def __post_init__(self):
    def need(ok, field, what):
      if not ok:
        raise ValueError(f'MatcherConfig.{field} must be {what}, got '
                         f'{getattr(self, field)!r}.')
    for field in ('census_height', 'census_width'):
      need(getattr(self, field) % 2 == 1, field, 'odd')
    need(self.census_height * self.census_width <= 65, 'census_width',
         f'at most 65 // census_height = {65 // self.census_height} (64-bit codes)')
    need(0 < self.p1, 'p1', '> 0')
    need(self.p1 <= self.p2 <= 16000, 'p2', 'in [p1, 16000] (uint16 sums of 4 paths)')
    need(self.lr_threshold >= 0, 'lr_threshold', '>= 0')
    need(self.full_search_cells > 0, 'full_search_cells', '> 0')
    for field in ('prior_radius', 'prior_spread', 'prior_missing_spread', 'threads', 'strips',
                  'strip_overlap'):
      need(getattr(self, field) >= 0, field, '>= 0')
    need(self.max_strip_mib > 0, 'max_strip_mib', '> 0')
    need(self.range_width >= 4 * self.census_width, 'range_width',
         f'>= 4 * census_width = {4 * self.census_width}')
    need(0 < self.range_fraction < 1, 'range_fraction', 'in (0, 1)')
    need(0 < self.range_density < 1, 'range_density', 'in (0, 1)')
    need(self.range_margin >= 0, 'range_margin', '>= 0')

  def thread_count(self) -> int:
    """`threads`, or when 0 the CPUs this process may use."""
    return workers.usable_cpus(self.threads)


def _pair(left, right, config: MatcherConfig) -> Tuple[np.ndarray, np.ndarray]:
  """float32 C-contiguous [H, W, K] stacks of two images of one size."""
  left, right = (np.asarray(x, np.float32) for x in (left, right))
  left, right = (x[..., None] if x.ndim == 2 else x for x in (left, right))
  if left.ndim != 3 or right.ndim != 3 or left.shape[:2] != right.shape[:2]:
    raise ValueError(f'left and right must be [H, W] or [H, W, K] images of one size, got '
                     f'{left.shape} and {right.shape}.')
  h, w = left.shape[:2]
  if h < config.census_height or w < config.census_width:
    raise ValueError(f'a {h}x{w} image is smaller than the matcher\'s census window of '
                     f'{config.census_height}x{config.census_width} pixels.')
  return np.ascontiguousarray(left), np.ascontiguousarray(right)


def _search_range(min_disparity, max_disparity, width: int) -> Tuple[int, int]:
  """The range clipped to disparities with a match inside an image `width` px wide."""
  for name, value in (('min_disparity', min_disparity), ('max_disparity', max_disparity)):
    if int(value) != value:
      raise ValueError(f'{name} must be a whole number of pixels, got {value!r}.')
  low, high = int(min_disparity), int(max_disparity)
  if low >= high:
    raise ValueError(f'need min_disparity < max_disparity, got [{low}, {high}].')
  if max(low, 1 - width) >= min(high, width - 1):
    raise ValueError(f'[min_disparity, max_disparity] = [{low}, {high}] leaves fewer than '
                     f'two disparities with a match inside an image {width} px wide '
                     f'(|d| <= {width - 1}).')
  return max(low, 1 - width), min(high, width - 1)


def coarse_factor(height: int, width: int, min_disparity: int, max_disparity: int,
                  config: MatcherConfig) -> int:
  """1 for a full search, else `match`'s coarse-to-fine factor: the smallest power of 2, f,
  with H W D / f^3 <= config.full_search_cells (1/f^2 of the pixels, 1/f of the
  disparities), keeping the reduced image at least twice the census window on each side."""
  cells = height * width * (max_disparity - min_disparity + 1)
  factor = 1
  while (cells > config.full_search_cells * factor ** 3 and
         width / (2 * factor) >= 2 * config.census_width and
         height / (2 * factor) >= 2 * config.census_height):
    factor *= 2
  return factor


def _search(left, right, lo, widths, config: MatcherConfig) -> dict:
  """Matches over the windows lo + [0, widths); post-processed as `sgm.match`."""
  threads = config.thread_count()
  window = (config.census_height, config.census_width)
  codes_left = parallel_sgm.census_codes(left, *window, threads)
  codes_right = parallel_sgm.census_codes(right, *window, threads)
  bounds = parallel_sgm.strip_bounds(widths, threads, config.strips,
                                     config.max_strip_mib << 20)
  d_left, d_right = parallel_sgm.disparities(
      codes_left, codes_right, lo, widths, config.p1, config.p2,
      (config.census_height * config.census_width - 1) // 2, threads, bounds,
      config.strip_overlap if len(bounds) > 2 else 0)
  # A right pixel no window reaches gets a value the left-right check always refuses.
  d_right[np.isnan(d_right)] = float(lo.min()) - 1e4
  return fast_postprocess.postprocess(d_left, d_right, config.lr_threshold)


def _full(left, right, low: int, high: int, config: MatcherConfig) -> dict:
  shape = left.shape[:2]
  return _search(left, right, np.full(shape, low, np.int32),
                 np.full(shape, high - low + 1, np.int32), config)


def _downsample(image: np.ndarray, factor: float) -> np.ndarray:
  """Area downsampling of [H, W, K] by `factor` (sizes rounded)."""
  h, w = image.shape[:2]
  size = (max(1, round(w / factor)), max(1, round(h / factor)))
  out = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
  return np.ascontiguousarray(out[..., None] if out.ndim == 2 else out)


def match(left, right, min_disparity: int, max_disparity: int,
          config: MatcherConfig = MatcherConfig(),
          prior: Optional[np.ndarray] = None) -> dict:
  """Left and right disparities of a stereo pair over a signed range.

  Args:
    left, right: [H, W] or [H, W, K] intensities (K may differ: e.g. a red-cyan
      anaglyph's R against its G and B; the cost averages the census Hamming distances of
      all channel pairs).
    min_disparity, max_disparity: inclusive signed range, whole pixels; clipped to
      |d| <= W - 1.
    config: parameters.
    prior: optional float [H, W] left disparity (e.g. the previous video frame's); then
      only windows around it are searched (`search_windows.around_prior` with
      config.prior_radius, prior_spread and prior_missing_spread; NaN pixels search the
      valid prior's range nearby, or the whole range where none is near).

  Returns:
    'disparity_left', 'disparity_right': float32 [H, W] signed pixels, filled everywhere
    (left x matches right x - d_L; right x matches left x + d_R); 'consistent_left',
    'consistent_right': bool [H, W], the left-right check before filling.

  Raises:
    ValueError: malformed images or prior, min_disparity >= max_disparity, a range with no
      match inside the image, or an image smaller than the census window.
  """
  left, right = _pair(left, right, config)
  h, w = left.shape[:2]
  low, high = _search_range(min_disparity, max_disparity, w)
  if prior is not None:
    prior = np.asarray(prior, np.float32)
    if prior.shape != (h, w) or np.isinf(prior).any():
      raise ValueError(f'prior must be an [H, W] = [{h}, {w}] disparity map without '
                       f'infinities, got shape {prior.shape}.')
    lo, widths = search_windows.around_prior(prior, low, high, config.prior_radius,
                                             config.prior_spread,
                                             config.prior_missing_spread)
    return _search(left, right, lo, widths, config)
  factor = coarse_factor(h, w, low, high, config)
  if factor == 1:
    return _full(left, right, low, high, config)
  small_left, small_right = _downsample(left, factor), _downsample(right, factor)
  small_width = small_left.shape[1]
  scale = w / small_width
  coarse = _full(small_left, small_right, max(math.floor(low / scale), 1 - small_width),
                 min(math.ceil(high / scale), small_width - 1), config)['disparity_left']
  prior = cv2.resize(coarse, (w, h), interpolation=cv2.INTER_LINEAR) * scale
  lo, widths = search_windows.around_prior(prior, low, high, math.ceil(scale) + 2,
                                           math.ceil(scale) + 1)
  return _search(left, right, lo, widths, config)


def range_copy(images, config: MatcherConfig = MatcherConfig()):
  """(copies, scale, reach) of `estimate_range`'s search: [H, W, K] `images` area-downsampled
  to config.range_width px a frame (`planning_copies`; narrower ones as they are), the
  factor back to full size, and the searched +- reach, pixels of the copy."""
  w, frame = images[0].shape[1], planning_copies.frame_width(images[0].shape)
  if frame > config.range_width:
    images = [_downsample(x, frame / config.range_width) for x in images]
  small = images[0].shape
  return images, w / small[1], min(small[1] - 1, max(1, planning_copies.reach(
      small, config.range_fraction)))


def dense_range(found: np.ndarray, reach: int, scale: float, width: int,
                config: MatcherConfig = MatcherConfig()) -> Tuple[int, int]:
  """`estimate_range`'s range from the consistent disparities `found` of the copy searched
  over +- `reach`: those whose 5-px window holds >= config.range_density of them, widened
  by config.range_margin, times `scale`, clipped to |d| <= `width` - 1 (the whole search
  when none is dense)."""
  low, high = -reach, reach
  counts = np.histogram(found, bins=np.arange(-reach, reach + 2))[0]
  # The 5-px window sums, one per bin ('same' would pad fewer than 5 bins to 5).
  share = np.convolve(counts, np.ones(5))[2:2 + counts.size] / max(1, found.size)
  dense = np.nonzero((share >= config.range_density) & (counts > 0))[0]
  if dense.size:
    low = dense.min() - reach - config.range_margin
    high = dense.max() - reach + config.range_margin
  low = max(math.floor(low * scale), 1 - width)
  high = min(math.ceil(high * scale), width - 1)
  if low >= high:  # One disparity (range_margin 0): widen to two.
    low, high = min(low, width - 2), min(low, width - 2) + 1
  return low, high


def estimate_range(left, right,
                   config: MatcherConfig = MatcherConfig()) -> Tuple[int, int]:
  """The disparity range of a pair from the images alone.

  A full search of +- config.range_fraction of the width on copies area-downsampled to
  config.range_width px (smaller images are searched as they are; `range_copy`); among the
  left-right consistent left disparities, those found whose 5-px window holds >=
  config.range_density of them (surfaces: false matches are few and spread over the whole
  search), widened by range_margin pixels of the copy, scaled back to full size
  (`dense_range`).

  Args:
    left, right: as `match`.
    config: parameters.

  Returns:
    (min_disparity, max_disparity): ints, min < max, |d| <= W - 1; the whole searched
    range when no pixel passes the left-right check.
  """
  left, right = _pair(left, right, config)
  h, w = left.shape[:2]
  (left, right), scale, reach = range_copy((left, right), config)
  if scale > 1 and left.shape[0] < config.census_height:  # A narrow range_width's copy.
    raise ValueError(f'a {h}x{w} image downsampled to MatcherConfig.range_width = '
                     f'{config.range_width} is {left.shape[0]} px high, less than '
                     f'MatcherConfig.census_height = {config.census_height}: too thin to '
                     'estimate its disparity range; give it (PredictorConfig.disparity_range).')
  out = _full(left, right, -reach, reach, config)
  return dense_range(out['disparity_left'][out['consistent_left']], reach, scale, w, config)
