"""How clearly phase correlation tells a camera's frame-to-frame translation from no
relation: the peak of `video.motion.global_shift` (MotionConfig.min_response) measured.

    python -m experiments.motion_response --photo_dir=photos/warps

Every photograph of --photo_dir (the training photographs, `experiments/get_photos.sh`)
and scikit-image's colour images, area-reduced to 1400x800; frames are 1280x720 crops:
  * unrelated: the first crops of two different photographs (every pair of unequal ones);
  * moved: one photograph, the second crop moved by a random (dx, dy) in [-30, 30) x
    [-10, 10) px, both blurred (Gaussian, sigma 1.5) with noise of 8 levels (seed 1);
  * zoom 2%, rotation 1 degree: the second crop scaled or turned about its centre.
Writes the peaks' range and the error of the shift found to
experiments/results/motion_response.md.
"""

from absl import app
from absl import flags
import cv2
import numpy as np

from experiments import detection_photos  # Defines --photo_dir (experiments.validation).
from experiments import markdown
from mixstereo_tf.video import motion

flags.DEFINE_string('motion_response_output', 'experiments/results/motion_response.md',
                    'Markdown report.')
FLAGS = flags.FLAGS
SIZE, CROP = (1400, 800), (slice(40, 760), slice(60, 1340))


def _peak(first, second):
  """((dx, dy) in frame pixels, peak) of two 1280x720 frames (`motion.translation`)."""
  copies = [motion.motion_copy(np.clip(f, 0, 255).astype(np.uint8), 320)
            for f in (first, second)]
  return motion.translation(*copies, frame_width=1280)


def _degraded(rng, image):
  return cv2.GaussianBlur(image, (0, 0), 1.5) + rng.normal(0, 8, image.shape)


def _cases(images, rng):
  """{case: [(peak, shift error px or None)]}."""
  out = {'unrelated': [], 'moved': [], 'zoom 2%': [], 'rotation 1 degree': []}
  for i, first in enumerate(images):
    for second in images[i + 1:]:
      if np.array_equal(first, second):  # scikit-image's chelsea and cat.
        continue
      out['unrelated'].append((_peak(first[CROP], second[CROP])[1], None))
    dx, dy = int(rng.integers(-30, 30)), int(rng.integers(-10, 10))
    moved = first[40 - dy:760 - dy, 60 - dx:1340 - dx]
    (fx, fy), peak = _peak(_degraded(rng, first[CROP]), _degraded(rng, moved))
    out['moved'].append((peak, max(abs(fx - dx), abs(fy - dy))))
    for case, (angle, scale) in (('zoom 2%', (0, 1.02)), ('rotation 1 degree', (1, 1))):
      turn = cv2.getRotationMatrix2D((SIZE[0] / 2, SIZE[1] / 2), angle, scale)
      second = cv2.warpAffine(first, turn, SIZE, flags=cv2.INTER_CUBIC)
      out[case].append((_peak(first[CROP], second[CROP])[1], None))
  return out


def main(argv):
  del argv
  images = [cv2.resize(image, SIZE, interpolation=cv2.INTER_AREA).astype(np.float32)
            for _, image in detection_photos._photographs()]  # pylint: disable=protected-access
  rows = []
  for case, found in _cases(images, np.random.default_rng(1)).items():
    peaks = np.array([peak for peak, _ in found])
    errors = [error for _, error in found if error is not None]
    rows.append([case, len(found), f'{peaks.min():.3f}', f'{np.median(peaks):.3f}',
                 f'{peaks.max():.3f}', f'{max(errors):.1f}' if errors else '',
                 f'{sum(e <= 1 for e in errors)}' if errors else ''])
  lines = ['# Phase-correlation peaks of frame pairs (`video.motion`)', '',
           f'{len(images)} photographs (--photo_dir and scikit-image), 1280x720 frames, '
           'copies 320 px wide (`experiments/motion_response.py`). `MotionConfig.min_response` '
           f'is {motion.MotionConfig().min_response}.', '',
           '| pairs | n | min peak | median | max | largest shift error, px | within 1 px |',
           '| --- | --- | --- | --- | --- | --- | --- |',
           *('| ' + ' | '.join(str(cell) for cell in row) + ' |' for row in rows)]
  markdown.write(FLAGS.motion_response_output, lines)


if __name__ == '__main__':
  app.run(main)
