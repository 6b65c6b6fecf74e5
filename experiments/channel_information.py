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
The shipped learned stage (`--pretrained=anaglyph_matching`, float32, over the same range)
is run on the pairings it can take, as anaglyphs: luma vs luma and R vs R and G vs G as
gray anaglyphs (its same-channel branch), R vs G, B as the colour anaglyph. Its R vs R is
what a perfect separation of the right eye's red would give it: the floor of any
separation under this stage.
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

from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.cli import startup  # pylint: disable=unused-import
from mixstereo_tf.classical import matcher
from mixstereo_tf.core import mixtures
from mixstereo_tf.unmixing import learned_matching

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


def gray_anaglyph(left_eye: np.ndarray, right_eye: np.ndarray) -> np.ndarray:
  """The anaglyph of two single-channel eyes (float 0..255 [H, W]) as the gray encoding
  stores them: [H, W, 3] in [0, 1], the left eye in red, the right in green and blue."""
  return np.stack([left_eye, right_eye, right_eye], -1).astype(np.float32) / 255.0


def _colour_anaglyph(left: np.ndarray, right: np.ndarray) -> np.ndarray:
  return np.concatenate([left[..., :1], right[..., 1:]], -1) / 255.0


# label -> (left RGB, right RGB, float32 0..255) -> (anaglyph in [0, 1], its encoding):
# the pairings the learned stage takes.
LEARNED_PAIRINGS: Dict[str, Callable[[np.ndarray, np.ndarray], Tuple[np.ndarray, str]]] = {
    REFERENCE: lambda left, right: (gray_anaglyph(left @ LUMA, right @ LUMA), 'gray'),
    'R vs G, B': lambda left, right: (_colour_anaglyph(left, right), 'anaglyph'),
    'R vs R': lambda left, right: (gray_anaglyph(left[..., 0], right[..., 0]), 'gray'),
    'G vs G': lambda left, right: (gray_anaglyph(left[..., 1], right[..., 1]), 'gray'),
}


def bad1s(pair: dict, valid: np.ndarray,
          descriptors: learned_matching.Descriptors) -> Dict[str, float]:
  """{pairing: bad-1 of the left disparity over `valid`}: the census matcher's for
  PAIRINGS, the learned stage's (`descriptors`) for LEARNED_PAIRINGS (keys prefixed
  'learned '), every pairing searched over the true range +- MARGIN px."""
  truth = pair['disparity_left']
  low = int(np.floor(truth[valid].min())) - MARGIN
  high = int(np.ceil(truth[valid].max())) + MARGIN
  left, right = (pair[k].astype(np.float32) for k in ('left', 'right'))
  bad1 = lambda out: float(np.mean(np.abs(out['disparity_left'] - truth)[valid] > 1.0))
  scores = {}
  for pairing, eyes in PAIRINGS.items():
    scores[pairing] = bad1(matcher.match(*eyes(left, right), low, high))
  for pairing, mixture in LEARNED_PAIRINGS.items():
    out = learned_matching.match(descriptors, *mixture(left, right), low, high)
    scores['learned ' + pairing] = bad1(out)
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


def table(rows: List[dict], pairings: List[str], prefix: str = '') -> List[str]:
  """Markdown: per group, each pairing's mean bad-1 (row keys `prefix` + pairing) and its
  ratio to the reference's."""
  lines = ['| scenes | ' + ' | '.join(pairings) + ' |', '| --- ' * (1 + len(pairings)) + '|']
  for group in dict.fromkeys(r['group'] for r in rows):
    mean = {p: np.mean([r[prefix + p] for r in rows if r['group'] == group])
            for p in pairings}
    cells = [f'{100 * mean[p]:.1f}%' + ('' if p == REFERENCE else
                                         f' ({mean[p] / mean[REFERENCE]:.2f}x)')
             for p in pairings]
    lines.append(f'| {group} | ' + ' | '.join(cells) + ' |')
  return lines


def main(argv):
  del argv
  start = time.perf_counter()
  descriptors = learned_matching.descriptor_function(
      pretrained.load_model(pretrained.get('anaglyph_matching')))  # float32
  rows = []
  for group, name, pair, valid in sources(FLAGS.shared_dir, FLAGS.photo_dir):
    rows.append(dict(group=group, scene=name, **bad1s(pair, valid, descriptors)))
    print(name, ' '.join(f'{p}: {100 * s:.1f}%' for p, s in rows[-1].items()
                         if p not in ('group', 'scene')), file=sys.stderr, flush=True)
  header = (f'# Channel information: the census matcher on channel pairings\n\nWritten by '
            f'`python -m experiments.channel_information` in '
            f'{time.perf_counter() - start:.0f} s. bad-1 of the left disparity over the '
            'valid ground truth (photo warps: the visible pixels), the true range +- 3 px; '
            'in brackets the ratio to luma vs luma. Pairings and sources: the module '
            'docstring. procedural: mean of 8 scenes; photo warps: mean of 12.\n')
  learned = ('\n## The learned stage on the pairings it takes\n\nThe shipped stage '
             '(`anaglyph_matching`, float32): luma, R and G pairings as gray anaglyphs, '
             'R vs G, B as the colour anaglyph. Its R vs R is the floor of any separation '
             "of the right eye's red under this stage.\n")
  text = '\n'.join(table(rows, list(PAIRINGS)) + [learned] +
                   table(rows, list(LEARNED_PAIRINGS), 'learned '))
  with open(FLAGS.channel_output, 'w') as f:
    f.write(header + '\n' + text + '\n')
  print(text)


if __name__ == '__main__':
  app.run(main)
