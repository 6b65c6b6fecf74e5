"""Two-channel anaglyphs (red-blue, red-green glasses): one eye per channel, the third empty.

    found = detect(small, reach_fraction, min_score, softness)  # (name, confidence, reason)

Red-blue and red-green glasses predate red-cyan ones and remain the cheapest; FFmpeg makes
their anaglyphs (`arbg`, `argg`): R = the left view's luma, B (or G) = the right view's,
the third channel black. `detection`'s families need three channels, two of one eye
aligned against each other, so such an image scored as no anaglyph (Motorcycle's red-blue
anaglyph: best family 0.068 < 0.08). Here a channel is empty when, above its 1st
percentile, its 90th percentile lies within EMPTY_P90 and its 99th within EMPTY_P99 of
full scale (lossy storage leaks a little of the others into it, most at their edges)
while each other channel spreads over FULL_SPREAD or more (a picture in each); the other
two are matched against each other (the census matcher, as the families are) and the
share of left-right consistent pixels displaced by 1.5 px or more is the score, held to
the families' threshold. Red is the left eye (as the glasses are worn and FFmpeg
encodes); `--swap_eyes` turns it. Chosen on Motorcycle, SceneFlow, the KITTI object
frame and held-out wallpapers (scratch `s28/rb/spread*.py`): the empty channel of their
red-blue / red-green anaglyphs through FFmpeg's JPEG and H.264 reaches 21 levels at the
99th percentile, through OpenCV's quality-50 JPEG of a 247-px one 18 / 44 (90th / 99th);
three-channel FFmpeg anaglyphs of 12 photo warps (png, JPEG, H.264) keep every channel
over 78, photographs over 26 (two, almost without blue, read as empty and are refused as
before: their other two channels align). Those frames are evaluation frames too, so
`results/detection.md`'s two-channel rows are not independent of these levels.
A print has no empty channel: two inks on white paper, one an eye (red-blue 3-D comics: the
left view in blue ink, which takes R and G, the right in red ink, which takes G and B),
darken G wherever either is, so G is the product of R and B at the same pixel, no view of
its own (`ink_channel`; the channel each encoding leaves empty, B for red-green). It is
taken for the empty one only where the other two are clearly displaced (`INK_MIN_SCORE`:
three training photographs whose green the product fits scored 0.09-0.15); else the
families decide. Levels chosen on simulated prints of training photo warps and the
training photographs (scratch `s30/print`): the product fit's residual (`INK_FIT`) and
its share of either channel's own fit (`INK_SHARE`; three-channel anaglyphs of the real
pairs keep 0.88 or more).
"""

from typing import Optional, Tuple

import numpy as np

from mixstereo_tf.core import mixtures
from mixstereo_tf.unmixing import channel_matching
from mixstereo_tf.unmixing import colour_sets

# Each two-channel encoding's empty channel (`mixtures`: red_blue G, red_green B).
EMPTY_CHANNEL = {name: mixtures.get_mixture(name).empty_channels[0]
                 for name in mixtures.ANAGLYPH_NAMES
                 if len(mixtures.get_mixture(name).empty_channels) == 1}
EMPTY_P90, EMPTY_P99 = 0.08, 0.2  # Of full scale, above the channel's 1st percentile.
FULL_SPREAD = 0.25  # The other channels' 99th minus 1st percentile, of full scale.
INK_FIT, INK_SHARE, INK_SINGLE = 0.03, 0.6, 0.01  # RMS of full scale; share of one channel's.
INK_MIN_SCORE = 0.2  # The displaced share a print's two channels need (photographs: 0.15).


def empty_channel(small: np.ndarray) -> Optional[int]:
  """The channel of a 0..255 [h, w, 3] copy that carries nothing while the other two
  carry a picture (module docstring), or None."""
  low, p90, p99 = np.percentile(small.reshape(-1, 3), (1, 90, 99), axis=0)
  empty = np.flatnonzero((p90 - low <= EMPTY_P90 * 255) & (p99 - low <= EMPTY_P99 * 255))
  if len(empty) != 1 or np.delete(p99 - low, empty).min() < FULL_SPREAD * 255:
    return None
  return int(empty[0])


def _fit_rms(target: np.ndarray, *columns: np.ndarray) -> float:
  """RMS residual of the least-squares fit of `target` by a constant and `columns`."""
  design = np.stack((np.ones_like(target),) + columns, axis=1)
  coefficients = np.linalg.lstsq(design, target, rcond=None)[0]
  return float(np.sqrt(np.mean((design @ coefficients - target) ** 2)))


def ink_channel(small: np.ndarray) -> Optional[int]:
  """The channel of a 0..255 [h, w, 3] copy that a print's two inks make of the other two
  (module docstring): fitted by them and their product within INK_FIT of full scale, and
  by at most INK_SHARE of what either alone (with its square) leaves, which is at least
  INK_SINGLE (a gray anaglyph's G is its B); of two such, the one with the smaller share
  (an eye's channel can come near the fit too); or None."""
  flat = small.reshape(-1, 3).astype(np.float64) / 255.0
  shares = {}
  for channel in sorted(set(EMPTY_CHANNEL.values())):
    one, two = (flat[:, c] for c in range(3) if c != channel)
    joint = _fit_rms(flat[:, channel], one, two, one * two)
    single = min(_fit_rms(flat[:, channel], one, one * one),
                 _fit_rms(flat[:, channel], two, two * two))
    if joint <= INK_FIT and single >= INK_SINGLE and joint <= INK_SHARE * single:
      shares[channel] = joint / single
  return min(shares, key=shares.get) if shares else None


def detect(small: np.ndarray, reach_fraction: float, min_score: float,
           softness: float) -> Optional[Tuple[Optional[str], float, str]]:
  """(name, confidence, reason) of a two-channel anaglyph's 0..255 copy `small`, name None
  where its two channels are not displaced (score < min_score; confidence that it is no
  anaglyph); None where no channel is empty or the empty one is no encoding's (red), or
  where a print's ink channel (`ink_channel`) stands for it and the others align."""
  empty, inked = empty_channel(small), None
  if empty is None:
    empty = inked = ink_channel(small)
  names = [name for name, channel in EMPTY_CHANNEL.items() if channel == empty]
  if not names:
    return None
  left, right = (c for c in range(3) if c != empty)
  out = channel_matching.match(small[..., left], small[..., right],
                               channel_matching.span(small, reach_fraction))
  score = channel_matching.displaced_share(out)
  min_score = min_score if inked is None else max(min_score, INK_MIN_SCORE)
  confidence = colour_sets.logistic((score - min_score) / softness)
  if score < min_score:
    if inked is not None:
      return None  # No print: the families decide (a photograph is refused as before).
    return None, 1.0 - confidence, (f'channel {"RGB"[empty]} is empty and the other two '
                                    f'are not displaced (score {score:.3f} < {min_score})')
  what = 'the product of the other two (a print)' if inked is not None else 'empty'
  return names[0], confidence, (f'channel {"RGB"[empty]} is {what}, the other two displaced '
                                f'(score {score:.3f}): {names[0]}')
