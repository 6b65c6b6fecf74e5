"""The finest detail of a view's borrowed channels, kept as far as the camera's noise allows.

A colour anaglyph gives each view some channels of its own (the left view's red) and none
of the others, which the restoration warps in from the other eye (`views.restore_views`).
What the other camera recorded there is the scene's detail plus that camera's own noise
and demosaicking, which are no part of this view: warped in, they are an error. How much
of the finest band they make is read from the mixture itself. The channels
that one eye keeps are one camera's at the same pixel: the correlation of two of its
channels in a band is P_s / (P_s + P_n), P_s the power they share, P_n what each has
alone. A scene's own colour detail differs between channels much alike at every scale, a
camera's noise and demosaicking mostly in the finest band, so k, the finest band's
correlation (detail below a Gaussian of `sigma`) over that of a reference band (between
Gaussians of 2 and 4 sigma), is the share of the finest band that is scene. The
least-squares estimate of this view's band from the other camera's (the same scene
detail, the other camera's noise) is k times it: the borrowed channels' finest band is
scaled by k (a Wiener gain), the coarser bands kept.

Measured (`experiments/results/borrowed_detail.md`): k is 1.00 on Motorcycle and the
SceneFlow frame, 0.42 on both KITTI frames (colour anaglyphs written losslessly), 0.96-0.98
on average on 4:2:0 JPEGs of photo warps, whose colour detail is the luma's. Shapes: views float32
[H, W, 3] in [0, 1]; sigma in pixels.
"""

from typing import Optional, Tuple

import cv2
import numpy as np

from mixstereo_tf.core import mixtures

GREEN = 1  # The channel a Bayer mosaic samples at every other site.


def _blur(channel: np.ndarray, sigma: float) -> np.ndarray:
  """A float32 [H, W] channel's Gaussian blur of `sigma` pixels, edges reflected."""
  return cv2.GaussianBlur(channel, (0, 0), sigma, borderType=cv2.BORDER_REFLECT)


def fine_band(channel: np.ndarray, sigma: float) -> Tuple[np.ndarray, np.ndarray]:
  """(coarse, fine) of a float32 [H, W] channel: its Gaussian blur of `sigma` pixels and
  the rest (channel = coarse + fine)."""
  channel = np.asarray(channel, np.float32)
  coarse = _blur(channel, sigma)
  return coarse, channel - coarse


def own_pair(spec: mixtures.MixtureSpec) -> Optional[Tuple[int, int]]:
  """The mixture channels of the eye that keeps two of its own, green one of them
  (`MixtureSpec.right_channels` of the colour anaglyph: green and blue; amber-blue's left
  eye: red and green), or None. A Bayer camera samples red and blue at diagonal sites, so
  their finest bands part even for scene detail (green-magenta's red and blue on the KITTI
  frames: k 0.00, views 0.04-0.21 dB worse; `results/borrowed_detail.md` of 2026-11-30)."""
  for channels in (spec.right_channels, spec.left_channels):
    pair = tuple(sorted(channels.values()))
    if len(pair) == 2 and GREEN in pair:
      return pair
  return None


def _correlation(first: np.ndarray, second: np.ndarray) -> float:
  """The correlation of two float32 [H, W] bands; 0 where either is flat."""
  first, second = first - first.mean(), second - second.mean()
  # Float32 products summed per row, the rows' sums in float64 (a 12-MP photo's bands
  # stay float32).
  dot = lambda a, b: float(np.einsum('ij,ij->i', a, b).sum(dtype=np.float64))
  power = np.sqrt(dot(first, first) * dot(second, second))
  return dot(first, second) / power if power > 1e-12 * first.size else 0.0


def shared_share(mixture: np.ndarray, channels: Tuple[int, int], sigma: float) -> float:
  """k in [0, 1]: the correlation of the mixture's two `channels` in the finest band
  (`fine_band`) over their correlation in a reference band (between Gaussians of 2 and
  4 sigma): the share of the finest band that is scene (module docstring). A scene whose
  colours differ in detail at every scale keeps its detail (k near 1); k = 1 where the
  reference band is uncorrelated or flat."""
  planes = [np.asarray(mixture[..., c], np.float32) for c in channels]
  fine = [fine_band(plane, sigma)[1] for plane in planes]
  reference = [_blur(plane, 2 * sigma) - _blur(plane, 4 * sigma) for plane in planes]
  shared = _correlation(*reference)
  if shared <= 0:
    return 1.0
  return float(np.clip(_correlation(*fine) / shared, 0.0, 1.0))


def scale_borrowed(mixture: np.ndarray, spec: mixtures.MixtureSpec, left: np.ndarray,
                   right: np.ndarray, sigma: float) -> Tuple[np.ndarray, np.ndarray, float]:
  """(left, right, k): each view's channels that the mixture does not give it (borrowed
  from the other eye) with their finest band scaled by k (`shared_share` of `own_pair`);
  the views unchanged and k = 1 where `own_pair` is None or `sigma` <= 0. The
  caller applies it only where the borrowed channels are not observed at all
  (`views.decoupled` encodings), so the mixture still holds exactly."""
  pair = own_pair(spec)
  if pair is None or sigma <= 0:
    return left, right, 1.0
  k = shared_share(mixture, pair, sigma)
  if k >= 1.0:
    return left, right, k
  out = []
  for view, own in ((left, spec.left_channels), (right, spec.right_channels)):
    view = np.array(view, np.float32)
    for c in range(3):
      if c not in own:
        coarse, fine = fine_band(view[..., c], sigma)
        view[..., c] = np.clip(coarse + np.float32(k) * fine, 0.0, 1.0)
    out.append(view)
  return out[0], out[1], k
