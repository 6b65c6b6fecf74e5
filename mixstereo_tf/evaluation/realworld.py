"""Real-world conditions from any stereo pair with ground truth: published-style anaglyphs,
window alignment, and the scores that still mean something for lossy encodings.

    pair = window_align(data, fraction=0.3)          # disparities now straddle zero
    image = make_anaglyph(pair, 'gray', 'ffmpeg')     # or encoder 'ours' (mixtures.py)
    row = score(pair, outputs)                        # RGB and luma PSNR, bad-1, bad-3

Window alignment (anaglyph makers place the zero-parallax plane inside the scene): with
[lo, hi] the 1st-99th percentiles of the valid left disparities and s = round(lo +
fraction (hi - lo)), the left view keeps columns [s, W) and the right view [0, W - s)
(s >= 0; for s < 0 the other way round), so every disparity becomes d - s: a `fraction` of
the range is negative (behind the screen). Luma PSNR compares Y = 0.299 R + 0.587 G +
0.114 B (`mixtures.LUMA`), the one thing a gray anaglyph transmits. A pair without ground
truth gets its window from `estimated_disparities`.
"""

import os
from typing import Dict, Iterator, Optional, Tuple

import numpy as np

from mixstereo_tf.classical import matcher
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import disparity_io
from mixstereo_tf.data import image_io
from mixstereo_tf.data import sources
from mixstereo_tf.evaluation import ffmpeg_encoder
from mixstereo_tf.evaluation import metrics

ENCODERS = ('ffmpeg', 'ours')
SCENEFLOW_FRAME = 'sceneflow_A-0032-0006'


def scenes(shared_dir: Optional[str],
           max_disparity: int = 96) -> Iterator[Tuple[str, Dict[str, np.ndarray]]]:
  """(name, data) of the scenes with ground truth: the 8 `sample` held-out scenes and
  Motorcycle (made for `max_disparity`), then the SceneFlow frame of `shared_dir` when
  given. data: 'left', 'right' uint8, 'disparity_left' float32, 'valid_left' bool."""
  config = sources.DataConfig(dataset='sample', heldout_scenes=8, max_disparity=max_disparity)
  for record in sources.list_samples(config, 'heldout'):
    yield record.name, sources.load_sample(record)
  if shared_dir:
    folder = os.path.join(shared_dir, SCENEFLOW_FRAME)
    disparity = disparity_io.read_pfm(os.path.join(folder, 'disp_left.pfm')).astype(np.float32)
    yield SCENEFLOW_FRAME, {
        'left': image_io.read_image(os.path.join(folder, 'left.png')),
        'right': image_io.read_image(os.path.join(folder, 'right.png')),
        'disparity_left': disparity, 'valid_left': disparity > 0}


def window_shift(disparity: np.ndarray, valid: np.ndarray, fraction: float) -> int:
  """s (pixels) such that `fraction` of the valid disparity range lies below zero."""
  low, high = np.percentile(disparity[valid], [1.0, 99.0])
  return int(round(low + fraction * (high - low)))


def estimated_disparities(left: np.ndarray, right: np.ndarray) -> Dict[str, np.ndarray]:
  """`window_align`'s data for a pair without ground truth: 'disparity_left' and
  'valid_left' are the census matcher's left-right consistent disparities of the pair's
  luma over [0, W / 4] px, good enough to place a window, not to score."""
  found = matcher.match(luma(left), luma(right), 0, left.shape[1] // 4)
  return {'left': left, 'right': right, 'disparity_left': found['disparity_left'],
          'valid_left': found['consistent_left']}


def window_align(data: Dict[str, np.ndarray], fraction: float) -> Dict[str, np.ndarray]:
  """The pair cropped so its disparities are d - s (module docstring).

  Args:
    data: 'left', 'right' uint8 [H, W, 3], 'disparity_left' float [H, W] (pixels, left x
      matches right x - d), 'valid_left' bool [H, W].
    fraction: in [0, 1].

  Returns:
    The same keys, W - |s| columns wide, plus 'shift': s.
  """
  if not 0.0 <= fraction <= 1.0:
    raise ValueError(f'fraction must be in [0, 1], got {fraction}.')
  s = window_shift(data['disparity_left'], data['valid_left'], fraction)
  width = data['left'].shape[1]
  if abs(s) >= width // 2:
    raise ValueError(f'a window shift of {s} px leaves too little of a {width} px image.')
  kept, other = (slice(s, width), slice(0, width - s)) if s >= 0 else (
      slice(0, width + s), slice(-s, width))
  return {'left': data['left'][:, kept], 'right': data['right'][:, other],
          'disparity_left': data['disparity_left'][:, kept] - s,
          'valid_left': data['valid_left'][:, kept], 'shift': s}


def make_anaglyph(data: Dict[str, np.ndarray], name: str, encoder: str) -> np.ndarray:
  """uint8 anaglyph of data's pair, by FFmpeg ('ffmpeg') or `mixtures` ('ours')."""
  if encoder == 'ffmpeg':
    return ffmpeg_encoder.encode(data['left'], data['right'], name)
  if encoder != 'ours':
    raise ValueError(f'Unknown encoder {encoder!r}; valid: {", ".join(ENCODERS)}.')
  mixed = mixtures.mix(name, image_range.u8_to_signed(data['left']),
                       image_range.u8_to_signed(data['right']))
  return image_range.signed_to_u8(mixed.numpy())


def luma(image_u8: np.ndarray) -> np.ndarray:
  """Y on the 0..255 scale, float [H, W]."""
  return np.asarray(image_u8, np.float64) @ np.asarray(mixtures.LUMA)


def score(data: Dict[str, np.ndarray], left: np.ndarray, right: np.ndarray,
          disparity=None) -> Dict[str, float]:
  """psnr_left/right (RGB), ypsnr_left/right (luma) and, given a left disparity map
  (signed pixels), bad1 / bad3 over the valid pixels."""
  row = {'psnr_left': metrics.psnr(left, data['left']),
         'psnr_right': metrics.psnr(right, data['right']),
         'ypsnr_left': metrics.psnr(luma(left), luma(data['left'])),
         'ypsnr_right': metrics.psnr(luma(right), luma(data['right']))}
  if disparity is not None:
    # The metrics read GT <= 0 as unknown: compare before the shift (same pixels, errors).
    shift = data.get('shift', 0)
    gt, valid = data['disparity_left'] + shift, data['valid_left']
    row['bad1'] = metrics.bad_pixel_rate(disparity + shift, gt, valid, 1.0)
    row['bad3'] = metrics.bad_pixel_rate(disparity + shift, gt, valid, 3.0)
  return row
