"""A tilted double image: the direction of its echo, found, and how well it self-matches.

A double image I = a L + (1 - a) R photographed with the camera rolled, or scanned
crooked, shows every surface twice along a tilted line: a copy at p and one at p - v with
v = (d cos t, d sin t) for every depth d, so dy = dx tan t through the origin (its eyes'
vertical offset cannot be undone by turning or moving the image: both copies move
together). The double-image matcher searches along rows; a Motorcycle double image turned
by 1 / 2 / 4 degrees went from bad-1 33.0% to 39.7 / 64.6 / 75.7% (scratch
`s28/dtilt/base.py`; `experiments/tilt.py`).

    tilt = estimate(gray)             # epipolar.Tilt(angle, 0.0, matches) or None
    share = consistent_share(gray)    # what the turn is checked by (`unmixing/tilt.py`)

`estimate`: on a copy `width` px wide, high-passed (minus a Gaussian of `highpass_sigma`:
a smooth image resembles itself a few pixels away more than its echo does), up to
`features` corners are matched against the same copy to their LEFT only (dx >= min_lag:
each copy of a surface sees the other on one side, and its own echo of the other layer on
the other), by normalised cross-correlation of `patch`-px patches within reach_fraction
of the width and +- reach_y px, kept where the peak reaches min_score (an echo shares one
of its two components: about 1/2), stands out and lies inside the search (not at its
edge: a smooth patch's correlation still rising towards lag 0). The slope of
dy = slope dx through the matches with dx >= min_dx is found by RANSAC over single
matches (inliers within inlier_px), then least squares on the inliers. Angles in degrees,
counter-clockwise as OpenCV turns images (`epipolar.rectify`).
"""

import dataclasses
from typing import Optional

import cv2
import numpy as np

from mixstereo_tf.classical import diplopia
from mixstereo_tf.classical import diplopia_range
from mixstereo_tf.classical import epipolar
from mixstereo_tf.core import planning_copies


@dataclasses.dataclass(frozen=True)
class EchoConfig:
  """Parameters of `estimate` (module docstring). Chosen on the real pairs' double images
  at a = 0.3 / 0.5 / 0.7 turned by 0, 1, 2 and -3 degrees (scratch `s28/dtilt/t4.py`,
  `t6.py`): high-pass 1.5 px, 640 px: the angle within 0.5 degrees of the truth on
  Motorcycle, SceneFlow and the KITTI object frame (one of its 12 with too few matches;
  none high-passed: 9 of 36 off by 0.9-3.7 degrees; at 1280 px, 7 of 12 KITTI object
  images off by 0.5-1.3), but off by 0.6-2.7 on 11 of 12 of KITTI 2015 #151, whose
  disparities at 640 px are mostly under 20 px; the matcher's check (`unmixing/tilt.py`)
  keeps an image level where a turn does not help."""
  width: int = 640
  features: int = 600
  patch: int = 15
  highpass_sigma: float = 1.5
  reach_fraction: float = 0.25
  reach_y: int = 12
  min_lag: int = 4
  min_score: float = 0.4
  min_dx: float = 6.0
  min_matches: int = 20
  inlier_px: float = 1.0


def echo_displacements(gray: np.ndarray, config: EchoConfig = EchoConfig()) -> np.ndarray:
  """[N, 2] (dx, dy), dx >= config.min_lag, from corners of float32 [h, w] `gray` to the
  echo on their left (module docstring), pixels of `gray`."""
  gray = np.float32(gray)
  detail = gray - cv2.GaussianBlur(gray, (0, 0), config.highpass_sigma)
  r, reach_x = config.patch // 2, int(config.reach_fraction * gray.shape[1])
  found = []
  for x, y, top in epipolar.corners(gray, config.features, config.patch, config.reach_y):
    template = detail[y - r:y + r + 1, x - r:x + r + 1]
    x0, x1 = max(0, x - r - reach_x), x + r + 3 - config.min_lag  # Last lag: min_lag - 2.
    if template.std() < 1.0 or x1 - x0 < config.patch + 4:
      continue
    window = detail[top:y + r + 1 + config.reach_y, x0:x1]
    match = epipolar.match_template(template, window, config.min_score, interior=True)
    if match is not None:
      found.append((x - (x0 + match[0] + r), y - (top + match[1] + r)))
  return np.array(found, np.float64).reshape(-1, 2)


def fit_slope(moves: np.ndarray, config: EchoConfig = EchoConfig()):
  """(slope, inliers) of dy = slope dx through the [N, 2] `moves` with dx >= config.min_dx
  (RANSAC over single moves, then least squares), None with fewer than 2."""
  moves = moves[moves[:, 0] >= config.min_dx]
  if len(moves) < 2:
    return None
  dx, dy = moves[:, 0], moves[:, 1]
  best = None
  for slope in dy / dx:
    inliers = np.abs(dy - slope * dx) <= config.inlier_px
    if best is None or inliers.sum() > best.sum():
      best = inliers
  return float((dx[best] * dy[best]).sum() / (dx[best] ** 2).sum()), int(best.sum())


def estimate(gray: np.ndarray, config: EchoConfig = EchoConfig()) -> Optional[epipolar.Tilt]:
  """The echo's `epipolar.Tilt` (offset 0) of a [H, W] double image's intensities (any
  scale; matched on a copy config.width px a frame, `planning_copies`), None with fewer
  than config.min_matches inliers."""
  small = planning_copies.area_copy(np.float32(gray), config.width)
  span = max(float(np.ptp(small)), 1e-6)
  line = fit_slope(echo_displacements(255.0 * (small - small.min()) / span, config), config)
  if line is None or line[1] < config.min_matches:
    return None
  return epipolar.Tilt(float(np.degrees(np.arctan(line[0]))), 0.0, line[1])


def consistent_share(gray: np.ndarray, width: int,
                     config: Optional[diplopia.DiplopiaConfig] = None) -> float:
  """The share of pixels (8-px border left out) of a copy `width` px a frame
  (`planning_copies`) of float [H, W] `gray` (0-255) whose self-matching over lags
  [1, a third of the copy] (the range estimate's: `diplopia_range`) is left-right
  consistent at a lag >= config.min_lag (the smallest lags match a smooth image's blur,
  not an echo)."""
  config = config or diplopia.DiplopiaConfig()
  small = planning_copies.area_copy(np.float32(gray), width)
  reach = max(2, planning_copies.reach(small.shape, 1 / 3))
  matched = diplopia_range.coarse_self_match(small, reach, config)
  found = matched['consistent_left'] & (matched['disparity_left'] >= config.min_lag)
  return float(found[8:-8, 8:-8].mean())
