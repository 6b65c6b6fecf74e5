"""Printed anaglyphs scanned: finding the halftone screen and smoothing it away.

A print lays each ink in dots on a regular screen (cyan, magenta, yellow and black at
their own angles, one period); a scan keeps the dots. The census matcher then matches the
screens (each ink's lattice is the same in both eyes' channels' neighbourhoods, or none),
not the picture: a Motorcycle anaglyph halftoned with 5-px cells fell from bad-1 17% to
86% and views of 28 dB to 10-12 dB (`experiments/halftone.py`).

    screen = find_screen(image)                 # Screen(period, peak, share) or None
    smooth = descreen(image, screen.period)     # Gaussian, sigma = blur * period
    image, info = resolve(image, 'auto')        # the setting of --descreen

Finding the screen (`find_screen`): the power spectrum of a central crop of each channel
(Hann window) divided by its median over each ring of frequencies; the strongest such
peak at periods [min_period, max_period] px must stand min_peak times above its ring.
Then the screen must cover the picture: over the image's textured tiles (tile x tile px,
a channel's standard deviation at least min_tile_std levels, at most max_tiles of them
evenly spread), the median share of a tile's AC power within ring_tolerance of the peak's
frequency is at least min_share. Dots fill every midtone of a print; a periodic texture
in a photograph (a brick wall, a spring, sand ripples) leaves most tiles without it.
Flat images, whose rings have almost no power, can show tall peaks (a gradient's dither)
but no share.
"""

import dataclasses
import functools
from typing import Dict, Optional, Tuple, Union

import cv2
import numpy as np

AUTO, OFF = 'auto', 'off'  # --descreen: find the screen per image (a video: per shot); none.


@dataclasses.dataclass(frozen=True)
class HalftoneConfig:
  """Parameters of `find_screen` and `descreen` (module docstring); chosen on validation
  photo warps halftoned by this project's operator and by ImageMagick's ordered dither
  (docs/DESIGN.md, classical: halftone screens).

  Attributes:
    crop: side of the central crop whose spectrum finds the peak, pixels.
    min_period, max_period: the screen periods looked for, pixels.
    min_peak: the peak's power over its ring's median.
    tile, max_tiles, min_tile_std: the coverage test's tiles (pixels), their number and the
      texture they need (levels of 255).
    ring_tolerance: the ring's half width, a fraction of the peak's frequency.
    min_share: the median tile's power share within the ring.
    blur: `descreen`'s Gaussian sigma, a fraction of the period.
  """
  crop: int = 512
  min_period: float = 2.2
  max_period: float = 16.0
  min_peak: float = 1000.0
  tile: int = 64
  max_tiles: int = 256
  min_tile_std: float = 4.0
  ring_tolerance: float = 0.08
  min_share: float = 0.3
  blur: float = 0.5


@dataclasses.dataclass(frozen=True)
class Screen:
  """A halftone screen found: its `period` (pixels), `peak` (power over the ring's median)
  and `share` (the median tile's power share at its frequency)."""
  period: float
  peak: float
  share: float


def _spectrum(block: np.ndarray) -> np.ndarray:
  """Power spectrum [s, s] (zero frequency at the centre) of an [s, s, C] block, summed over
  channels, each without its mean and Hann-windowed."""
  side = block.shape[0]
  window = np.outer(np.hanning(side), np.hanning(side))
  power = np.zeros((side, side))
  for channel in np.moveaxis(block.astype(np.float64), -1, 0):
    power += np.abs(np.fft.fftshift(np.fft.fft2((channel - channel.mean()) * window))) ** 2
  return power


@functools.lru_cache(maxsize=4)
def _frequencies(side: int) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
  """(radial frequency in cycles per pixel [side, side] of a centred spectrum, the flat
  indices sorted by ring (rounded radius * side), where each ring starts in that order)."""
  fy, fx = np.mgrid[-(side // 2):side - side // 2, -(side // 2):side - side // 2] / side
  radius = np.hypot(fx, fy)
  ring = np.round(radius * side).astype(int).ravel()
  order = np.argsort(ring, kind='stable')
  return radius, order, np.searchsorted(ring[order], np.arange(ring.max() + 2))


def _ring_medians(power: np.ndarray, order: np.ndarray, starts: np.ndarray) -> np.ndarray:
  """The median of `power` over each ring, at every cell [side, side]."""
  ranked = power.ravel()[order]
  medians = np.empty(power.size)
  for begin, end in zip(starts[:-1], starts[1:]):
    medians[order[begin:end]] = np.median(ranked[begin:end])
  return medians.reshape(power.shape)


def strongest_peak(image: np.ndarray, config: HalftoneConfig = HalftoneConfig()
                   ) -> Tuple[float, float]:
  """(period in pixels, power over its ring's median) of the strongest spectral peak of
  the central crop within [min_period, max_period], the largest over the channels."""
  side = min(config.crop, image.shape[0], image.shape[1]) // 2 * 2
  top, left = (image.shape[0] - side) // 2, (image.shape[1] - side) // 2
  crop = image[top:top + side, left:left + side].reshape(side, side, -1)
  radius, order, starts = _frequencies(side)
  band = (radius >= 1 / config.max_period) & (radius <= 1 / config.min_period)
  best = np.zeros((side, side))
  for channel in range(crop.shape[2]):
    power = _spectrum(crop[..., channel:channel + 1])
    medians = _ring_medians(power, order, starts)
    best = np.maximum(best, np.where(band, power / np.maximum(medians, 1e-12), 0))
  index = int(np.argmax(best))
  return 1.0 / float(radius.flat[index]), float(best.flat[index])


def coverage(image: np.ndarray, period: float,
             config: HalftoneConfig = HalftoneConfig()) -> float:
  """The median over textured tiles of the share of a tile's AC power within
  ring_tolerance of 1 / period (0 where no tile is textured)."""
  side = config.tile
  radius = _frequencies(side)[0]
  ring = np.abs(radius - 1 / period) <= max(config.ring_tolerance / period, 1.5 / side)
  levels = 255.0 if image.dtype.kind == 'f' else 1 / 257 if image.dtype == np.uint16 else 1.0
  image = image.reshape(image.shape[0], image.shape[1], -1)
  corners = [(y, x) for y in range(0, image.shape[0] - side + 1, side)
             for x in range(0, image.shape[1] - side + 1, side)]
  step = max(1, len(corners) // config.max_tiles)
  shares = []
  for y, x in corners[::step]:
    block = image[y:y + side, x:x + side].astype(np.float64) * levels  # 0..255.
    if block.std(axis=(0, 1)).max() < config.min_tile_std:
      continue
    power = _spectrum(block)
    power[side // 2, side // 2] = 0.0
    shares.append(power[ring].sum() / max(power.sum(), 1e-12))
  return float(np.median(shares)) if shares else 0.0


def find_screen(image: np.ndarray, config: HalftoneConfig = HalftoneConfig()
                ) -> Optional[Screen]:
  """The halftone screen of an [H, W, C] (or [H, W]) image, None where it shows none
  (module docstring)."""
  if min(image.shape[:2]) < 2 * config.tile:
    return None
  period, peak = strongest_peak(image, config)
  if peak < config.min_peak:
    return None
  share = coverage(image, period, config)
  return Screen(period, peak, share) if share >= config.min_share else None


def descreen(image: np.ndarray, period: float,
             config: HalftoneConfig = HalftoneConfig()) -> np.ndarray:
  """`image` (any dtype OpenCV blurs: uint8, uint16, float32) smoothed by a Gaussian of
  sigma config.blur * period pixels per channel, same shape and dtype."""
  return cv2.GaussianBlur(image, (0, 0), config.blur * float(period))


def resolve(image: np.ndarray, setting: Union[str, float],
            config: HalftoneConfig = HalftoneConfig()
            ) -> Tuple[np.ndarray, Dict[str, object]]:
  """(the image to unmix, {'screen_period': pixels} where it was descreened) under a
  --descreen `setting`: OFF, AUTO (`find_screen`) or a period in pixels.

  Raises:
    ValueError: a setting that is none of these.
  """
  if setting == OFF:
    return image, {}
  if setting == AUTO:
    found = find_screen(image, config)
    if found is None:
      return image, {}
    period = round(found.period, 2)
  else:
    period = check_period(setting)
  return descreen(image, period, config), {'screen_period': period}


def check_period(value) -> float:
  """A screen period as a float > 1 pixel; ValueError otherwise."""
  if isinstance(value, (bool, str)) or not np.isfinite(value) or not value > 1.0:
    raise ValueError(f"a halftone screen's period must be 'auto', 'off' or a number of "
                     f'pixels above 1, got {value!r}.')
  return float(value)
