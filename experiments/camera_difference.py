"""How much the two cameras of each evaluation pair differ in colour at corresponding pixels,
and what that costs an anaglyph's views (issue "Learned cross-channel matching").

    python -m experiments.camera_difference --shared_dir=../shared/stereo_samples \
        [--camera_difference_output=experiments/results/camera_difference.md]

A colour anaglyph keeps the left camera's red and the right camera's green and blue, so each
view's missing channels can only come from the other camera. Where the cameras differ
(exposure, white balance, vignetting, view-dependent shading) no restoration can tell: a
scene seen by two cameras whose green and blue gains differ makes the same anaglyph as a
greener scene seen by equal cameras. Per scene (the pairs of `same_channel.py`,
window-aligned as there), over the valid ground-truth pixels seen by both cameras (the match
inside the right image, and the truth the frontmost there: within 1 px of the right
disparity forward-warped from it, `eye_order.right_from_left`; for KITTI's sparse Velodyne
points only among the points themselves): per channel, the median of L(x) - R(x - d) (grey
levels, the bias; R sampled linearly) and its RMS; and the PSNR of the 'oracle copy' views at those correspondences:
each view's own channels exact, its missing ones copied from the other camera at the true
disparity: the best a restoration that trusts the other camera can do there, whatever its
matching (the resampling's blur included). Then the same with each channel's median removed:
what knowing the cameras' global difference would add. The KITTI 2015 frame, which has no
ground truth, is measured at the census matcher's consistent matches of its luma
(`realworld.estimated_disparities`; row marked 'estimated'): correspondences the matcher
found, not truth, so its RMS includes the matcher's errors.
"""

import platform
import time
from typing import Dict

from absl import app
from absl import flags
import numpy as np

from experiments import markdown
from experiments import same_channel  # The scenes and their window alignment.
from mixstereo_tf.core import mixtures
from mixstereo_tf.evaluation import realworld
from mixstereo_tf.restoration import views
from mixstereo_tf.unmixing import eye_order

flags.DEFINE_string('camera_difference_output', 'experiments/results/camera_difference.md',
                    'Markdown report.')
FLAGS = flags.FLAGS


def _psnr(mse: float) -> float:
  return float(10 * np.log10(255.0 ** 2 / mse)) if mse > 0 else float('inf')


def camera_difference(pair: Dict[str, np.ndarray], name: str = 'anaglyph') -> Dict[str, object]:
  """The module docstring's numbers for one pair and anaglyph encoding `name`.

  Args:
    pair: 'left', 'right' uint8 [H, W, 3]; 'disparity_left' float [H, W] (pixels, the left
      x matches the right x - d); 'valid_left' bool [H, W].
    name: the encoding whose eyes' channels (`MixtureSpec.eye_channels`) are kept.

  Returns:
    'bias' (median), 'rms': float [3], grey levels, of L(x) - R(x - d) over the pixels seen
    by both cameras; 'pixels': their count;
    'psnr_left', 'psnr_right', 'psnr_left_unbiased', 'psnr_right_unbiased': dB.
  """
  d = np.asarray(pair['disparity_left'], np.float32)
  valid = np.asarray(pair['valid_left'], bool)
  d_right = eye_order.right_from_left(np.where(valid, d, np.nan))
  rows, columns = np.mgrid[:d.shape[0], :d.shape[1]]
  target = np.clip(np.rint(columns - d).astype(np.int64), 0, d.shape[1] - 1)
  inside = (columns - d >= 0) & (columns - d <= d.shape[1] - 1)
  front = np.abs(np.nan_to_num(d_right[rows, target], nan=np.inf) - d) <= 1.0
  used = valid & inside & front
  if not used.any():
    raise ValueError('camera_difference: no valid ground truth seen by both cameras.')
  warped = views.sample_horizontal(pair['right'].astype(np.float32), -d)
  diff = (pair['left'].astype(np.float32) - warped)[used].astype(np.float64)  # [N, 3]
  bias = np.median(diff, 0)
  square, centred = np.mean(diff ** 2, 0), np.mean((diff - bias) ** 2, 0)
  out = {'bias': bias, 'rms': np.sqrt(square), 'pixels': int(used.sum())}
  for side, own in zip(('left', 'right'), mixtures.get_mixture(name).eye_channels):
    missing = [c for c in range(3) if c not in own]
    out[f'psnr_{side}'] = _psnr(square[missing].sum() / 3)
    out[f'psnr_{side}_unbiased'] = _psnr(centred[missing].sum() / 3)
  return out


def _row(scene: str, numbers: Dict[str, object]) -> str:
  triple = lambda v: ' / '.join(f'{x:+.1f}' for x in v)
  return (f"| {scene} | {triple(numbers['bias'])} | "
          f"{' / '.join(f'{x:.1f}' for x in numbers['rms'])} | "
          f"{numbers['psnr_left']:.2f} / {numbers['psnr_right']:.2f} | "
          f"{numbers['psnr_left_unbiased']:.2f} / {numbers['psnr_right_unbiased']:.2f} |")


def main(argv):
  del argv
  start = time.perf_counter()
  lines = ['| scene | median L - R, R / G / B (grey levels) | RMS R / G / B | oracle copy '
           'views L / R (dB) | bias removed L / R (dB) |', '| --- ' * 5 + '|']
  for scene, data in same_channel.scenes(FLAGS.shared_dir, views_only=True):
    pair = realworld.window_align(data, same_channel.FRACTION)
    label = f'{scene} (estimated)' if data.get('views_only') else scene
    lines.append(_row(label, camera_difference(pair)))
  machine = ' '.join(filter(None, (platform.system(), platform.machine())))
  text = ['# Camera differences at corresponding pixels (colour anaglyph)', '',
          f'Written by `python -m experiments.camera_difference'
          f"{' --shared_dir=' + FLAGS.shared_dir if FLAGS.shared_dir else ''}` on {machine} "
          f'in {time.perf_counter() - start:.0f} s. See the module docstring; procedural '
          'scenes are rendered with equal cameras (their differences are the renderer\'s '
          'shading and the linear resampling).', ''] + lines
  markdown.write(FLAGS.camera_difference_output, text)


if __name__ == '__main__':
  app.run(main)
