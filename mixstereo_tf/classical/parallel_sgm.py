"""Runs the `census_sgm` kernels on a thread pool, in horizontal strips of bounded memory.

Threads: census codes (channels x row blocks) and SGM strips are shared among `threads`
Python threads; the kernels release the GIL, so they run in parallel without numba's own
threading layer (nothing to configure, and no clash with TensorFlow's thread pools).

Memory: a running strip holds 2 bytes per searched cell of its rows (the sum of its
window widths) plus row buffers of 17 bytes per cell of its fullest row (the windows of
one image row back to back, `census_sgm`); at most `threads` strips run at a time.
`strip_bounds` cuts the strips so that they hold equal numbers of cells (equal work too),
at least one per thread and more where one would pass `max_strip_bytes`. Each strip
aggregates `overlap` extra rows above and below, where its vertical paths start; one strip
(no overlap) reproduces `sgm.match` exactly.
A stored cost volume (`match_volume`) runs in one strip by default, so it reproduces
`sgm.match_volume` exactly; asked for `threads` > 1 it runs as many strips with the same
overlap rule.
"""

from typing import Tuple

import numpy as np

from mixstereo_tf.classical import census_costs
from mixstereo_tf.classical import census_sgm
from mixstereo_tf.classical import fast_postprocess
from mixstereo_tf.classical import sgm
from mixstereo_tf.core import workers


def run_blocks(kernel, blocks, threads: int, *arguments, partial: int = 0) -> np.ndarray:
  """kernel(y0, y1, *arguments[, sums]) on every row block of `blocks` (`workers.row_blocks`), on
  `threads` threads; with `partial` C > 0 each block gets its own float64 [C] sums (the
  kernel's last argument), returned added up."""
  sums = np.zeros((len(blocks), partial))
  call = ((lambda k: kernel(*blocks[k], *arguments, sums[k])) if partial else
          (lambda k: kernel(*blocks[k], *arguments)))
  workers.run_tasks(call, list(range(len(blocks))), threads)
  return sums.sum(axis=0)


def census_codes(channels: np.ndarray, height: int, width: int,
                 threads: int) -> np.ndarray:
  """Census codes of every channel, as `sgm.census_transform` (reflected borders).

  Args:
    channels: float32 [H, W, K].
    height, width: odd census window (at most 65 pixels).
    threads: worker threads (channels x row blocks are shared among them).

  Returns:
    uint64 [K, H, W].
  """
  h, w, k = channels.shape
  ry, rx = height // 2, width // 2
  out = np.empty((k, h, w), np.uint64)
  padded = [np.pad(channels[..., c], ((ry, ry), (rx, rx)), mode='reflect') for c in range(k)]
  tasks = [(c, a, b) for c in range(k) for a, b in workers.row_blocks(h, threads)]
  workers.run_tasks(lambda t: census_costs.census_rows(
      padded[t[0]][t[1]:t[2] + 2 * ry], height, width, out[t[0], t[1]:t[2]]), tasks, threads)
  return out


def census_volume(left: np.ndarray, right: np.ndarray, min_disparity: int,
                  num_disparities: int, height: int, width: int, threads: int) -> np.ndarray:
  """The census cost volume the matcher aggregates without storing (`census_costs.cost_row`:
  mean Hamming distance over channel pairs, (height * width - 1) // 2 outside the image),
  stored: uint8 [H, W, D], [y, x, i] scores left x against right x - (min_disparity + i).

  Args:
    left, right: float32 [H, W, K_L], [H, W, K_R] intensities.
    min_disparity, num_disparities: the signed range; height, width: the census window.
    threads: worker threads (codes and row blocks).
  """
  codes_left = census_codes(left, height, width, threads)
  codes_right = census_codes(right, height, width, threads)
  h, w = left.shape[:2]
  out = np.empty((h, w, num_disparities), np.uint8)
  oob = np.uint8((height * width - 1) // 2)
  workers.run_tasks(lambda t: census_costs.volume_rows(
      codes_left, codes_right, int(min_disparity), t[0], t[1], oob, out),
                    workers.row_blocks(h, threads), threads)
  return out


def strip_bounds(widths: np.ndarray, threads: int, strips: int,
                 max_strip_bytes: int) -> np.ndarray:
  """Row bounds [0, ..., H] of the strips, cut so that they hold equal numbers of cells.

  strips > 0 is taken as given; 0 picks max(threads, cells * 2 bytes / max_strip_bytes).
  """
  h = widths.shape[0]
  cells = np.concatenate([[0], np.cumsum(widths.sum(axis=1, dtype=np.int64))])
  if not strips:
    strips = max(threads, -(-2 * int(cells[-1]) // max_strip_bytes))
  strips = min(strips, h)
  rows = np.interp(np.linspace(0, cells[-1], strips + 1), cells, np.arange(h + 1))
  return np.unique(np.rint(rows).astype(np.int64))


def disparities(codes_left: np.ndarray, codes_right: np.ndarray, lo: np.ndarray,
                widths: np.ndarray, p1: int, p2: int, out_of_image_cost: int,
                threads: int, bounds: np.ndarray,
                overlap: int) -> Tuple[np.ndarray, np.ndarray]:
  """Raw left and right winners of SGM over per-pixel disparity windows.

  Args:
    codes_left, codes_right: uint64 [K_L, H, W], [K_R, H, W] census codes.
    lo, widths: int32 [H, W]: pixel (y, x) searches lo + [0, widths) (widths >= 1).
    p1, p2: SGM penalties; out_of_image_cost: cost of a match outside the right image.
    threads: worker threads; bounds: strip row bounds (`strip_bounds`); overlap: extra
      rows above and below each strip.

  Returns:
    float32 [H, W] disparity_left (the left pixel x matches the right pixel x - d) and
    disparity_right (the right pixel x matches the left pixel x + d; NaN where no left
    pixel's window reaches it), signed pixels, parabola-refined, not filtered.
  """
  h, w = lo.shape
  dl = np.empty((h, w), np.float32)
  dr = np.empty((h, w), np.float32)
  lo = np.ascontiguousarray(lo, np.int32)
  widths = np.ascontiguousarray(widths, np.int32)

  def strip(s):
    a, b = int(bounds[s]), int(bounds[s + 1])
    census_sgm.sgm_strip(codes_left, codes_right, lo, widths, max(0, a - overlap),
                         min(h, b + overlap), a, b, p1, p2, np.uint8(out_of_image_cost),
                         dl, dr)

  workers.run_tasks(strip, list(range(len(bounds) - 1)), threads)
  return dl, dr


def match_volume(volume: np.ndarray, config: sgm.SgmConfig, threads: int = 1,
                 overlap: int = 32, max_strip_mib: int = 0) -> dict:
  """`sgm.match_volume` by the numba kernels: SGM, winners and post-processing of a
  left-referenced cost volume, the same outputs bit for bit in one strip (threads = 1).

  Args:
    volume: uint8 [H, W, D]; volume[y, x, i] scores the left pixel x against the right
      pixel x - d_i, d_i = config.min_disparity + i.
    config: penalties and left-right threshold (the census fields are unused).
    threads, overlap, max_strip_mib: as `match_cost_volume`'s.

  Returns:
    As `sgm.match`.
  """
  # A right pixel no left pixel reaches: `sgm.select_disparities` gives it d_0.
  return match_cost_volume(volume, config.min_disparity, config.p1, config.p2,
                           config.lr_threshold, unreached=float(config.min_disparity),
                           threads=threads, overlap=overlap, max_strip_mib=max_strip_mib)


def match_cost_volume(volume: np.ndarray, min_disparity: int, p1: int, p2: int,
                      lr_threshold: float, unreached: float = None, threads: int = 1,
                      overlap: int = 32, max_strip_mib: int = 0) -> dict:
  """SGM, winners and post-processing (`fast_postprocess`) of a left-referenced uint8
  cost volume over a signed range, in `threads` strips of equal rows (1: one strip,
  exact) aggregating `overlap` extra rows above and below (the matcher's rule); with
  `max_strip_mib` > 0 in more strips where the aggregated costs (2 bytes per cell) would
  exceed that many MiB per strip, `threads` of them at a time.

  Args:
    volume: uint8 [H, W, D]; volume[y, x, i] scores the left pixel x against the right
      pixel x - d_i, d_i = min_disparity + i (any sign).
    min_disparity: d_0, pixels; p1, p2: SGM penalties (cost units).
    lr_threshold: largest accepted left-right difference, pixels.
    unreached: the right disparity of a right pixel no left pixel reaches (None: a value
      the left-right check always refuses).

  Returns:
    As `sgm.match`.
  """
  h, w, _ = volume.shape
  d_left = np.empty((h, w), np.float32)
  d_right = np.empty((h, w), np.float32)
  volume = np.ascontiguousarray(volume, np.uint8)
  strips = threads
  if max_strip_mib > 0:
    strips = max(threads, -(-2 * volume.size // (max_strip_mib << 20)))
  workers.run_tasks(lambda block: census_sgm.volume_sgm(
      volume, int(min_disparity), int(p1), int(p2), d_left, d_right,
      (max(0, block[0] - overlap), min(h, block[1] + overlap), *block)),
                    workers.row_blocks(h, strips), threads)
  d_right[np.isnan(d_right)] = np.float32(
      min_disparity - 1e4 if unreached is None else unreached)
  return fast_postprocess.postprocess(d_left, d_right, lr_threshold)
