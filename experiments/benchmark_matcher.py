"""The 'matcher' measurement of experiments/benchmark.py: `classical.matcher.match` speed.

Inputs are held-out `sample` scenes made into red-cyan anaglyphs (R of the left view
against G and B of the right, as the classical de-anaglyph matches them):
  1242x375, range [0, 127]: rendered at that size (max_disparity 128);
  1280x720, range [-58, 58]: rendered with max_disparity 116, the right view shifted so
    that the disparities drop by 58 px (a window-aligned anaglyph: signed disparities);
  4000x3000, range [-181, 181]: rendered at 1280x960 (max_disparity 116, shifted by 58 px)
    and upscaled 3.125x bicubically, disparities scaled alike; `match` goes coarse-to-fine.
The 720p case also times a video frame: `match` with a prior = the full result moved by
(2, 1) px and offset by +1 px (a pan since the previous frame). The NumPy `sgm.match`
rows run on the unshifted pair over [0, max - min] (it takes no negative disparities).
Times: the numba kernels are loaded (or compiled) on a tiny pair first ('load_s'); then
`repeats` timed calls, wall and CPU (user + sys of all threads) seconds, min and median.
The harness adds the process' peak resident memory ('peak_gib'); 'rss_before_gib' is the
resident memory before the first timed call (imports, TensorFlow's ~0.6 GiB included, and
the inputs), so the matcher's own peak is at most the difference.
"""

import os
import statistics
import time

import cv2
import numpy as np

from mixstereo_tf.classical import matcher
from mixstereo_tf.classical import search_windows
from mixstereo_tf.classical import sgm
from mixstereo_tf.data import sample
from mixstereo_tf.data import sources

# name: (render height, width, max_disparity, right-view shift px, upscale, search range)
CASES = {
    '1242x375': (375, 1242, 128, 0, 1.0, (0, 127)),
    '1280x720': (720, 1280, 116, 58, 1.0, (-58, 58)),
    '4000x3000': (960, 1280, 116, 58, 3.125, (-181, 181)),
}


def _shift(image: np.ndarray, shift: int) -> np.ndarray:
  """image(x - shift), edges replicated: disparities into it drop by `shift`.

  The left pixel x matched the right pixel x - d, i.e. the shifted one x - (d - shift).
  """
  width = image.shape[1]
  if shift >= 0:
    return np.pad(image, ((0, 0), (shift, 0), (0, 0)), mode='edge')[:, :width]
  return np.pad(image, ((0, 0), (0, -shift), (0, 0)), mode='edge')[:, -shift:]


def anaglyph_case(name: str, signed: bool = True):
  """(left channels, right channels, true left disparity, visible mask, search range)."""
  height, width, max_disparity, shift, scale, search = CASES[name]
  record = sample.sample_records('heldout', num_scenes=1, height=height, width=width,
                                 max_disparity=max_disparity)[0]
  views = sources.load_sample(record)
  right = _shift(views['right'], shift) if signed else views['right']
  truth = views['disparity_left'] - (shift if signed else 0)
  mixture = np.dstack([views['left'][..., :1], right[..., 1:]])
  visible = views['nonocc_left']
  if scale != 1.0:
    size = (round(width * scale), round(height * scale))
    mixture = cv2.resize(mixture, size, interpolation=cv2.INTER_CUBIC)
    truth = cv2.resize(truth, size, interpolation=cv2.INTER_NEAREST) * scale
    visible = cv2.resize(visible.astype(np.uint8), size, interpolation=cv2.INTER_NEAREST) > 0
  if not signed:
    search = (0, search[1] - search[0])
  # The shift moves some matches out of the right view: not visible any more.
  match = np.arange(truth.shape[1])[None, :] - np.rint(truth)
  visible = visible & (match >= 0) & (match < truth.shape[1])
  mixture = mixture.astype(np.float32)
  return mixture[..., :1], mixture[..., 1:], truth, visible, search


def _rss_gib() -> float:
  """Resident memory of this process now (VmRSS), GiB."""
  with open('/proc/self/status') as f:
    return next(int(line.split()[1]) for line in f if line.startswith('VmRSS:')) / 2**20


def _timed(fn, repeats: int, truth, visible) -> dict:
  """Wall and CPU seconds of `repeats` calls of fn(), and bad-1 of the last result."""
  walls, cpus = [], []
  for _ in range(repeats):
    cpu, wall = os.times(), time.perf_counter()
    out = fn()
    walls.append(time.perf_counter() - wall)
    done = os.times()
    cpus.append(done.user + done.system - cpu.user - cpu.system)
  error = np.abs(out['disparity_left'] - truth)[visible]
  return {'wall_min': min(walls), 'wall_median': statistics.median(walls),
          'cpu_min': min(cpus), 'cpu_median': statistics.median(cpus), 'repeats': repeats,
          'bad1': float(np.mean(error > 1.0)), 'consistent': float(
              np.mean(out['consistent_left']))}


def matcher_speed(case: str, method: str = 'numba', repeats: int = 2) -> dict:
  """Seconds, CPU seconds and bad-1 of one case ('numba' = `matcher.match`, 'numpy')."""
  if case not in CASES or method not in ('numba', 'numpy'):
    raise ValueError(f"case must be one of {sorted(CASES)} and method 'numba' or 'numpy', "
                     f'got {case!r}, {method!r}.')
  left, right, truth, visible, (low, high) = anaglyph_case(case, signed=method == 'numba')
  result = {'range': [low, high], 'size': f'{left.shape[1]}x{left.shape[0]}',
            'method': method}
  if method == 'numpy':
    config = sgm.SgmConfig(min_disparity=low, max_disparity=high)
    result['rss_before_gib'] = _rss_gib()
    result['full'] = _timed(lambda: sgm.match(left, right, config), 1, truth, visible)
    return result
  config = matcher.MatcherConfig()
  start = time.perf_counter()
  tiny = np.random.default_rng(0).uniform(0, 255, (16, 32, 1))
  matcher.match(tiny, tiny, -2, 2, config)
  result['load_s'] = time.perf_counter() - start
  result['coarse_factor'] = matcher.coarse_factor(*left.shape[:2], low, high, config)
  result['threads'] = config.thread_count()
  repeats = 1 if left.size > 4e6 else repeats
  result['rss_before_gib'] = _rss_gib()
  result['full'] = _timed(lambda: matcher.match(left, right, low, high, config), repeats,
                          truth, visible)
  if case == '1280x720':
    previous = matcher.match(left, right, low, high, config)['disparity_left']
    prior = np.roll(previous, (1, 2), axis=(0, 1)) + 1.0
    result['mean_window'] = float(search_windows.around_prior(
        prior, low, high, config.prior_radius, config.prior_spread)[1].mean())
    result['prior'] = _timed(lambda: matcher.match(left, right, low, high, config, prior),
                             repeats, truth, visible)
  return result


WORKERS = {'matcher': matcher_speed}
