r"""How well can one eye's channels be matched at all? The census matcher on channel pairings.

    python -m experiments.channel_information --shared_dir=../shared/stereo_samples \
        --photo_dir=photos/warps

Issue 27's reference for a colour anaglyph is the same matcher on a gray anaglyph of the
same pair (luma against luma, `same_channel.py`). A colour anaglyph keeps only the left
eye's red and the right eye's green and blue, so two things separate it from that
reference: the left eye is seen in one channel (less information), and it is compared with
other channels (the cross-channel gap a learned stage can close). This experiment tells
them apart by running the census matcher (`matcher.match`, as shipped, over the true
range +- 3 px) on the ground-truth pairs with the eyes given as:
  * luma vs luma: the gray anaglyph's eyes (BT.601 weights), the reference;
  * R vs G, B: the colour anaglyph's (the matcher averages the census distances of R-G
    and R-B);
  * R vs R: the left eye's red against the right eye's true red: what a perfect
    separation of the right eye's missing red would give this matcher;
  * R vs local fit r: the left red against the right eye's red predicted from its own
    green and blue by a least-squares fit R ~ a G + b B + c in (2r + 1)^2 windows whose
    coefficients are fitted on the right eye's TRUE red (an oracle): the best any
    locally linear colour mapping between the channels can do.
Sources: the scenes of `same_channel.scenes` (window-aligned at 30%) and the 12 validation
photo warps of `matching_validation.py`; the rendered ones (procedural scenes, photo
warps) again with independent noise (sigma 2 grey levels) added to each view
(`validation.noisy`): a rendered pair shows the same texture, its noise included, in
both views, which no camera pair does, and census codes of flat regions then match that
shared noise.
"""

import sys
import time
from typing import Callable, Dict, List, Tuple

from absl import app
from absl import flags
import cv2
import numpy as np

from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.classical import matcher
from mixstereo_tf.core import mixtures

from experiments import matching_validation  # WARP: the validation pairs' size.
from experiments import same_channel  # Defines --shared_dir (its scenes).
from experiments import validation  # Defines --photo_dir.

flags.DEFINE_string('channel_output', 'experiments/results/channel_information.md',
                    'Markdown report.')
FLAGS = flags.FLAGS

LUMA = np.asarray(mixtures.LUMA, np.float32)  # BT.601, as the gray anaglyph's.
MARGIN = 3
REFERENCE = 'luma vs luma'
Eyes = Tuple[np.ndarray, np.ndarray]


def local_fit(target: np.ndarray, green: np.ndarray, blue: np.ndarray,
              radius: int) -> np.ndarray:
  """target predicted from green and blue (float32 [H, W], any one unit) by per-window
  least squares target ~ a green + b blue + c over (2 radius + 1)^2 boxes, the
  coefficients averaged over the boxes covering each pixel (a guided filter with two
  guides; 1e-2 ridge on the guides' variances, reflected borders)."""
  size = (2 * radius + 1,) * 2
  box = lambda x: cv2.boxFilter(x, -1, size, borderType=cv2.BORDER_REFLECT)
  mg, mb, mt = box(green), box(blue), box(target)
  gg = box(green * green) - mg * mg + 1e-2
  bb = box(blue * blue) - mb * mb + 1e-2
  gb = box(green * blue) - mg * mb
  tg, tb = box(target * green) - mt * mg, box(target * blue) - mt * mb
  det = gg * bb - gb * gb
  a, b = (tg * bb - tb * gb) / det, (tb * gg - tg * gb) / det
  return box(a) * green + box(b) * blue + box(mt - a * mg - b * mb)


def _oracle(radius: int) -> Callable[[np.ndarray, np.ndarray], Eyes]:
  return lambda left, right: (left[..., 0], local_fit(right[..., 0], right[..., 1],
                                                      right[..., 2], radius))


# label -> (left RGB, right RGB, float32 0..255) -> the eye images the matcher compares.
PAIRINGS: Dict[str, Callable[[np.ndarray, np.ndarray], Eyes]] = {
    REFERENCE: lambda left, right: (left @ LUMA, right @ LUMA),
    'R vs G, B': lambda left, right: (left[..., 0], right[..., 1:]),
    'R vs R': lambda left, right: (left[..., 0], right[..., 0]),
    'R vs local fit 3 (oracle)': _oracle(3),
    'R vs local fit 7 (oracle)': _oracle(7),
}


def bad1s(pair: dict, valid: np.ndarray) -> Dict[str, float]:
  """{pairing: bad-1 of the census matcher's left disparity over `valid`}, every pairing
  searched over the true range +- MARGIN px."""
  truth = pair['disparity_left']
  low = int(np.floor(truth[valid].min())) - MARGIN
  high = int(np.ceil(truth[valid].max())) + MARGIN
  left, right = (pair[k].astype(np.float32) for k in ('left', 'right'))
  scores = {}
  for pairing, eyes in PAIRINGS.items():
    out = matcher.match(*eyes(left, right), low, high)
    scores[pairing] = float(np.mean(np.abs(out['disparity_left'] - truth)[valid] > 1.0))
  return scores


def sources(shared_dir: str, photo_dir: str):
  """(group, scene name, pair, valid) of every pair scored (module docstring); no photo
  warps without `photo_dir` (--photo_dir, which `validation.required_atlas` reads)."""
  for group, name, pair in same_channel.pairs(shared_dir):
    yield group, name, pair, pair['valid_left']
  if not photo_dir:
    return
  pairs = validation.photo_pairs(matching_validation.WARP, 12, validation.required_atlas())
  for number, pair in enumerate(pairs):
    yield 'photo warps', f'warp {number}', pair, pair['nonocc_left']
    yield (f'photo warps + noise {validation.NOISE_SIGMA:g}', f'warp {number} + noise',
           validation.noisy(pair, number), pair['nonocc_left'])


def table(rows: List[dict]) -> List[str]:
  """Markdown: per group, each pairing's mean bad-1 and its ratio to the reference."""
  lines = ['| scenes | ' + ' | '.join(PAIRINGS) + ' |', '| --- ' * (1 + len(PAIRINGS)) + '|']
  for group in dict.fromkeys(r['group'] for r in rows):
    mean = {p: np.mean([r[p] for r in rows if r['group'] == group]) for p in PAIRINGS}
    cells = [f'{100 * mean[p]:.1f}%' + ('' if p == REFERENCE else
                                         f' ({mean[p] / mean[REFERENCE]:.2f}x)')
             for p in PAIRINGS]
    lines.append(f'| {group} | ' + ' | '.join(cells) + ' |')
  return lines


def main(argv):
  del argv
  start = time.perf_counter()
  rows = []
  for group, name, pair, valid in sources(FLAGS.shared_dir, FLAGS.photo_dir):
    rows.append(dict(group=group, scene=name, **bad1s(pair, valid)))
    print(name, ' '.join(f'{p}: {100 * rows[-1][p]:.1f}%' for p in PAIRINGS),
          file=sys.stderr, flush=True)
  header = (f'# Channel information: the census matcher on channel pairings\n\nWritten by '
            f'`python -m experiments.channel_information` in '
            f'{time.perf_counter() - start:.0f} s. bad-1 of the left disparity over the '
            'valid ground truth (photo warps: the visible pixels), the true range +- 3 px; '
            'in brackets the ratio to luma vs luma. Pairings and sources: the module '
            'docstring. procedural: mean of 8 scenes; photo warps: mean of 12.\n')
  with open(FLAGS.channel_output, 'w') as f:
    f.write(header + '\n' + '\n'.join(table(rows)) + '\n')
  print('\n'.join(table(rows)))


if __name__ == '__main__':
  app.run(main)
