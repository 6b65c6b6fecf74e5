"""The unmix tool's logic: choose an unmixer, run it over images and videos, write results.

Outputs per image `<stem>` in the output folder: the views (`<stem>_left.png` and
`<stem>_right.png` for the 'separate' layout, else `<stem>_<layout>.png`), the colour-mapped
left disparity `<stem>_disparity.png` (one fixed range per run), KITTI-style
`<stem>_disparity16.png` (uint16, d * 256) and float32 pixels `<stem>_disparity.npy`.
Per video: the layout as `<stem>_<layout>.mp4` (or `_left` / `_right`) and
`<stem>_disparity.mp4`.
"""

import dataclasses
import os
import time
from typing import Callable, Dict, List, Optional, Tuple

from absl import logging
import cv2
import numpy as np

from mixstereo_tf import baselines
from mixstereo_tf import inference
from mixstereo_tf import media
from mixstereo_tf import mixtures
from mixstereo_tf.baselines import sgm

METHODS = ('model', 'classical')
UnmixFn = Callable[[np.ndarray], Dict[str, np.ndarray]]


@dataclasses.dataclass(frozen=True)
class Unmixing:
  """A ready unmixer: fn(uint8 [H, W, 3]) -> {'left', 'right', 'disparity_left', ...}."""
  fn: UnmixFn
  mixture: str
  default_max_disparity: float


@dataclasses.dataclass
class UnmixReport:
  """What `unmix_inputs` did: counts, failures as (path, reason), timings in seconds."""
  processed: int = 0
  frames: int = 0
  failures: List[Tuple[str, str]] = dataclasses.field(default_factory=list)
  seconds: float = 0.0
  unmix_seconds: float = 0.0

  @property
  def frames_per_second(self) -> float:
    """Frames over the whole run, reading and writing included."""
    return self.frames / self.seconds if self.seconds > 0 else 0.0


def failure_message(report: UnmixReport) -> Optional[str]:
  """The error that ends the run with a non-zero status: every input failed."""
  if report.failures and not report.processed:
    return f'error: all {len(report.failures)} input(s) failed.'
  return None


def _classical(mixture: str) -> Unmixing:
  """The training-free baseline; its display range is its disparity search range."""
  if mixture not in baselines.SUPPORTED_MIXTURES:
    raise ValueError(f'--method=classical does not support --mixture={mixture}; '
                     f'supported: {", ".join(baselines.SUPPORTED_MIXTURES)}.')
  return Unmixing(lambda image: baselines.unmix_classical(image, mixture), mixture,
                  sgm.SgmConfig().max_disparity)


def make_unmixing(method: str = 'model', saved_model: Optional[str] = None,
                  checkpoint: Optional[str] = None, mixture: Optional[str] = None,
                  restore_colour: Optional[bool] = None) -> Unmixing:
  """Builds the unmixer the flags ask for.

  Args:
    method: 'model' (a trained network) or 'classical' (training-free baseline).
    saved_model: export directory (method 'model'; exactly one of this and `checkpoint`).
    checkpoint: run directory or checkpoint prefix (method 'model').
    mixture: the input's mixture operator; must equal the model's recorded one (default:
      the recorded one); required for 'classical'.
    restore_colour: paper section 4.2 colour restoration (default: channel anaglyphs).

  Raises:
    ValueError: inconsistent arguments, named as flags.
  """
  if mixture is not None:
    mixtures.get_mixture(mixture)  # ValueError listing the valid names.
  if method == 'classical':
    if saved_model or checkpoint:
      raise ValueError('--method=classical takes neither --saved_model nor --checkpoint.')
    if mixture is None:
      raise ValueError('--method=classical needs --mixture.')
    return _classical(mixture)
  if method != 'model':
    raise ValueError(f'Unknown --method={method!r}; valid: {", ".join(METHODS)}.')
  if bool(saved_model) == bool(checkpoint):
    raise ValueError('Give exactly one of --saved_model and --checkpoint.')

  def check_mixture(run_info):
    if mixture is not None and mixture != run_info.mixture:
      raise ValueError(f'--mixture={mixture} but the model was trained on '
                       f'{run_info.mixture!r} mixtures ({saved_model or checkpoint}).')

  if saved_model:
    unmixer = inference.Unmixer.from_saved_model(saved_model, restore_colour)
    check_mixture(unmixer.run_info)
  else:
    # The recorded mixture is checked before the model is built.
    model_dir, _ = inference.resolve_checkpoint(checkpoint)
    check_mixture(inference.read_run_info(os.path.join(model_dir, inference.CONFIG_FILE)))
    unmixer = inference.Unmixer.from_model(*inference.load_run(checkpoint), restore_colour)
  return Unmixing(unmixer, unmixer.run_info.mixture,
                  unmixer.run_info.model_config.max_disparity)


def write_image_outputs(outputs: Dict[str, np.ndarray], output_dir: str, stem: str,
                        layout: str, max_disparity: float) -> List[str]:
  """Writes one image's files (module docstring); returns their paths."""
  paths = []
  for suffix, image in media.layout_images(outputs['left'], outputs['right'], layout):
    paths.append(os.path.join(output_dir, f'{stem}_{suffix}.png'))
    media.write_image(paths[-1], image)
  disparity = np.asarray(outputs['disparity_left'], np.float32)
  paths.append(os.path.join(output_dir, f'{stem}_disparity.png'))
  media.write_image(paths[-1], media.colorize_disparity(disparity, max_disparity))
  paths.append(os.path.join(output_dir, f'{stem}_disparity16.png'))
  media.write_disparity_png16(paths[-1], disparity)
  paths.append(os.path.join(output_dir, f'{stem}_disparity.npy'))
  np.save(paths[-1], disparity)
  return paths


def _unmix_video(fn: UnmixFn, item: media.MediaItem, output_dir: str, layout: str,
                 max_disparity: float, report: UnmixReport) -> int:
  """Unmixes every frame of a video into layout and disparity videos; returns frames."""
  fps, frames = media.video_frames(item.path)
  suffixes = ['left', 'right'] if layout == 'separate' else [layout]
  writers = {s: media.VideoWriter(os.path.join(output_dir, f'{item.stem}_{s}.mp4'), fps)
             for s in suffixes + ['disparity']}
  count = 0
  try:
    for frame in frames:
      start = time.perf_counter()
      outputs = fn(frame)
      report.unmix_seconds += time.perf_counter() - start
      for suffix, image in media.layout_images(outputs['left'], outputs['right'], layout):
        writers[suffix].write(image)
      writers['disparity'].write(
          media.colorize_disparity(outputs['disparity_left'], max_disparity))
      count += 1
      if count % 50 == 0:
        logging.info('  %s: %d frames', item.path, count)
  finally:
    for writer in writers.values():
      writer.close()
  return count


def unmix_inputs(unmixing: Unmixing, input_spec: str, output_dir: str,
                 layout: str = 'separate',
                 max_display_disparity: Optional[float] = None) -> UnmixReport:
  """Unmixes every image / video of `input_spec` (see `media.iter_inputs`).

  Unreadable inputs are logged by name, recorded in `UnmixReport.failures` and skipped.

  Raises:
    ValueError: bad layout / display range, or `input_spec` names nothing usable.
  """
  if layout not in media.LAYOUTS:
    raise ValueError(f'Unknown --layout={layout!r}; valid: {", ".join(media.LAYOUTS)}.')
  max_disparity = max_display_disparity or unmixing.default_max_disparity
  if not max_disparity > 0:
    raise ValueError(f'--max_display_disparity must be positive, got {max_disparity}.')
  items = list(media.iter_inputs(input_spec))
  os.makedirs(output_dir, exist_ok=True)
  report = UnmixReport()
  run_start = time.perf_counter()
  for index, item in enumerate(items, 1):
    start = time.perf_counter()
    try:
      if item.is_video:
        frames = _unmix_video(unmixing.fn, item, output_dir, layout, max_disparity, report)
      else:
        image = media.read_image(item.path)
        unmix_start = time.perf_counter()
        outputs = unmixing.fn(image)
        report.unmix_seconds += time.perf_counter() - unmix_start
        write_image_outputs(outputs, output_dir, item.stem, layout, max_disparity)
        frames = 1
    except (ValueError, cv2.error) as e:
      logging.error('[%d/%d] skipped %s: %s', index, len(items), item.path, e)
      report.failures.append((item.path, str(e)))
      continue
    report.processed += 1
    report.frames += frames
    logging.info('[%d/%d] %s: %d frame(s) in %.2f s', index, len(items), item.path, frames,
                 time.perf_counter() - start)
  report.seconds = time.perf_counter() - run_start
  return report
