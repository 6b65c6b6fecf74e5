"""A tilted anaglyph: the direction its eyes are displaced in, found and made horizontal.

The matchers search along rows. A scan laid crooked on the glass, a photograph of a print
or a screen, or inks printed out of register displace the eyes along a tilted line
(dy = slope dx + offset), and a Motorcycle anaglyph turned by 1 / 2 / 4 degrees went from
bad-1 17.5% to 25.8 / 41.7 / 68.5% (`experiments/tilt.py`).

    tilt = estimate(left_eye, right_eye)      # Tilt(angle, offset, matches) or None
    level, back = rectify(image, tilt, right_channels)
    ... unmix `level` ...; views_and_maps = back(array)

`estimate`: on a copy `width` px wide, up to `features` corners of the left eye's image
(`cv2.goodFeaturesToTrack`) are found in the right eye's by normalised cross-correlation
of `patch`-px patches (gain and offset between the eyes' channels do not matter) within
+- reach_fraction of the width and +- reach_y px, kept where the peak reaches min_score
and stands out (no other peak within 0.05 of it beyond 3 px), refined to sub-pixel by
parabolas. The line dy = slope dx + offset through the displacements is fitted by RANSAC
(inliers within inlier_px of the copy), then least squares on the inliers; a scene at
one depth (dx spread below 4 px) gives the offset alone. Angles in degrees,
counter-clockwise as OpenCV turns images; displacements run from a left-eye pixel to its
match (dx = x_left - x_right, the disparity; dy = y_left - y_right), so a positive offset
is a left eye lower than the right.
"""

import dataclasses
from typing import Callable, Iterator, Optional, Sequence, Tuple

import cv2
import numpy as np


@dataclasses.dataclass(frozen=True)
class EpipolarConfig:
  """Parameters of `estimate` (module docstring) and of when `rectify` is worth it:
  min_angle degrees or min_offset pixels (smaller tilts cost less than a resampling)."""
  width: int = 640
  features: int = 400
  patch: int = 15
  reach_fraction: float = 0.25
  reach_y: int = 12
  min_score: float = 0.8
  min_matches: int = 20
  inlier_px: float = 1.0
  min_angle: float = 0.3
  min_offset: float = 0.5


@dataclasses.dataclass(frozen=True)
class Tilt:
  """The eyes' displacement line: `angle` (degrees the image is turned by to make it
  horizontal), `offset` (the right eye's vertical offset after that turn, pixels) and the
  `matches` it rests on."""
  angle: float
  offset: float
  matches: int


def _peak(scores: np.ndarray, x: int, y: int) -> Tuple[float, float]:
  """Sub-pixel (x, y) of a correlation peak by a parabola along each axis."""
  def vertex(a, b, c):
    bend = a - 2 * b + c
    return 0.0 if bend >= 0 else float(np.clip(0.5 * (a - c) / bend, -0.5, 0.5))
  h, w = scores.shape
  dx = vertex(*scores[y, x - 1:x + 2]) if 0 < x < w - 1 else 0.0
  dy = vertex(*scores[y - 1:y + 2, x]) if 0 < y < h - 1 else 0.0
  return x + dx, y + dy


def match_template(template: np.ndarray, window: np.ndarray, min_score: float,
             interior: bool = False) -> Optional[Tuple[float, float]]:
  """Sub-pixel (x, y) of `template`'s match in `window` (top-left corner, window pixels),
  None where the normalised cross-correlation peak is under min_score or does not stand
  out (another within 0.05 of it beyond 3 px); `interior`: also None where it lies on the
  window's last column or its first or last row (a search cut short there)."""
  scores = cv2.matchTemplate(window, template, cv2.TM_CCOEFF_NORMED)
  _, best, _, (bx, by) = cv2.minMaxLoc(scores)
  if interior and (bx >= scores.shape[1] - 1 or by in (0, scores.shape[0] - 1)):
    return None
  others = scores.copy()
  others[max(0, by - 3):by + 4, max(0, bx - 3):bx + 4] = -1.0
  if best < min_score or others.max() > best - 0.05:
    return None
  return _peak(scores, bx, by)


def corners(image: np.ndarray, features: int, patch: int,
            reach_y: int) -> Iterator[Tuple[int, int, int]]:
  """(x, y, top) of up to `features` corners of float32 [h, w] `image`
  (`cv2.goodFeaturesToTrack`) whose `patch`-px patch, widened by +- reach_y rows (from row
  `top`), lies inside it."""
  found = cv2.goodFeaturesToTrack(image, features, 0.01, 8, blockSize=7)
  height, width = image.shape
  r = patch // 2
  for x, y in np.round(found[:, 0]).astype(int) if found is not None else ():
    top = y - r - reach_y
    if top >= 0 and y + r + reach_y < height and x - r >= 0 and x + r < width:
      yield x, y, top


def displacements(left: np.ndarray, right: np.ndarray,
                  config: EpipolarConfig = EpipolarConfig()) -> np.ndarray:
  """[N, 2] (dx, dy) from left-eye corners to their right-eye matches, pixels of [h, w]
  float32 eye images (module docstring)."""
  width = left.shape[1]
  r, reach_x = config.patch // 2, int(config.reach_fraction * width)
  found = []
  for x, y, top in corners(left, config.features, config.patch, config.reach_y):
    template = left[y - r:y + r + 1, x - r:x + r + 1]
    if template.std() < 3.0:
      continue
    x0 = max(0, x - r - reach_x)
    window = right[top:y + r + 1 + config.reach_y, x0:min(width, x + r + 1 + reach_x)]
    match = match_template(template, window, config.min_score)
    if match is not None:
      found.append((x - (x0 + match[0] + r), y - (top + match[1] + r)))
  return np.array(found, np.float64).reshape(-1, 2)


def fit_line(moves: np.ndarray, inlier_px: float,
             seed: int = 0) -> Optional[Tuple[float, float, int]]:
  """(slope, offset, inliers) of dy = slope dx + offset through [N, 2] displacements
  (RANSAC over pairs, then least squares); slope 0 where dx spreads less than 4 px."""
  if len(moves) < 2:
    return None
  dx, dy = moves[:, 0], moves[:, 1]
  rng, best = np.random.default_rng(seed), None
  for _ in range(300):
    i, j = rng.choice(len(dx), 2, replace=False)
    slope = 0.0 if abs(dx[i] - dx[j]) < 2 else (dy[i] - dy[j]) / (dx[i] - dx[j])
    inliers = np.abs(dy - slope * dx - (dy[i] - slope * dx[i])) <= inlier_px
    if best is None or inliers.sum() > best.sum():
      best = inliers
  if np.ptp(dx[best]) < 4:
    return 0.0, float(np.median(dy[best])), int(best.sum())
  slope, offset = np.linalg.lstsq(np.stack([dx[best], np.ones(best.sum())], 1), dy[best],
                                  rcond=None)[0]
  return float(slope), float(offset), int(best.sum())


def estimate(left: np.ndarray, right: np.ndarray,
             config: EpipolarConfig = EpipolarConfig()) -> Optional[Tilt]:
  """The `Tilt` of two [H, W] eye images (any scale of values), None with fewer than
  config.min_matches inliers."""
  height, width = left.shape[:2]
  scale = max(1.0, width / config.width)
  size = (max(1, round(width / scale)), max(1, round(height / scale)))
  small = [np.ascontiguousarray(cv2.resize(np.float32(x), size, interpolation=cv2.INTER_AREA)
                                if scale > 1 else np.float32(x)) for x in (left, right)]
  span = max(float(np.ptp(small[0])), float(np.ptp(small[1])), 1e-6)
  moves = displacements(*(255.0 * (x - x.min()) / span for x in small), config)
  line = fit_line(moves, config.inlier_px)
  if line is None or line[2] < config.min_matches:
    return None
  slope, offset, count = line
  turn = np.arctan(slope)
  return Tilt(float(np.degrees(turn)), float(offset * scale * np.cos(turn)), count)


def worth_rectifying(tilt: Optional[Tilt], config: EpipolarConfig = EpipolarConfig()) -> bool:
  """Whether `tilt` is large enough for `rectify` (config.min_angle, config.min_offset)."""
  return tilt is not None and (abs(tilt.angle) >= config.min_angle or
                               abs(tilt.offset) >= config.min_offset)


def rectify(image: np.ndarray, tilt: Tilt, right_channels: Sequence[int]
            ) -> Tuple[np.ndarray, Callable[..., np.ndarray], Callable[..., np.ndarray]]:
  """(the image turned by tilt.angle onto a canvas holding all of it, its right-eye
  channels moved down by tilt.offset; `back(array, right=False)`, which brings an array
  of that canvas (a view, a disparity map) back to the image's frame, moving a right-eye
  one up first; `forth(map)`, which turns a float map of the image's frame (a left
  disparity) onto the canvas, NaN where the image has none). Edges are replicated."""
  height, width = image.shape[:2]
  turn = cv2.getRotationMatrix2D((width / 2, height / 2), tilt.angle, 1.0)
  cos, sin = abs(turn[0, 0]), abs(turn[0, 1])
  size = (int(np.ceil(width * cos + height * sin)), int(np.ceil(height * cos + width * sin)))
  turn[:, 2] += (size[0] - width) / 2, (size[1] - height) / 2
  warp = lambda x, m, s: cv2.warpAffine(x, m, s, flags=cv2.INTER_LINEAR,
                                        borderMode=cv2.BORDER_REPLICATE)
  lift = lambda x, dy: warp(x, np.float64([[1, 0, 0], [0, 1, dy]]), (x.shape[1], x.shape[0]))
  level = warp(image, turn, size)
  channels = list(right_channels)
  if channels and tilt.offset:
    level[..., channels] = lift(level[..., channels], tilt.offset).reshape(
        level.shape[:2] + (len(channels),))
  until = cv2.invertAffineTransform(turn)

  def back(array: np.ndarray, right: bool = False) -> np.ndarray:
    array = lift(array, -tilt.offset) if right and tilt.offset else array
    return warp(array, until, (width, height))

  forth = lambda x: cv2.warpAffine(np.float32(x), turn, size, flags=cv2.INTER_LINEAR,
                                   borderMode=cv2.BORDER_CONSTANT, borderValue=np.nan)
  return level, back, forth
