"""Consecutive frames of a shot unmixed side by side: one frame's views are restored
while the next frame is matched.

Within a shot, frame t + 1 needs only frame t's disparities (its prior,
`temporal.VideoState`), not its views. The first stage reports its disparities through the
hint's `on_disparity` before it restores the views (the anaglyph matcher,
`classical.anaglyph.unmix_anaglyph`) or solves the layers (double images,
`classical.diplopia.unmix_diplopia`), and before a refiner refines them;
`FramePipeline.submit` returns as soon as that happens, so the next frame's matching runs
beside this frame's restoration or refinement, and both share the kernels' threads
(`core.workers`): the single-threaded parts of one fill the cores the other leaves idle.
The reported disparities are the next frame's prior, not the frame's final ones, also
when a refiner changes them. Frames that report nothing early (a shot's first frame,
whose decisions the next frame needs, and frames of a shot whose encoding is not settled,
`hints.FrameHint.may_be`) are waited for whole, and their outputs are the prior. Run one
at a time with these priors, the outputs are the same (tests). With temporal consistency
off (`--notemporal`: every frame decided alone) the next frame needs nothing of this one
and starts at once; at most two frames are in flight either way. A frame the unmixer
already ran on with the very hint the pipeline gives it (`Unmixed`: a video's opening
frame, `cli.video_files.opening`) is not unmixed again.

    pipeline = FramePipeline(unmixer, temporal.VideoState(config))
    for image in frames:
      pending = pipeline.submit(image)   # returns once the next frame may start
      ...                                # pending.result(): the frame's outputs
    pipeline.close()
"""

import concurrent.futures
import dataclasses
import threading
from typing import Callable, Dict, Optional

import numpy as np

from mixstereo_tf.core import hints
from mixstereo_tf.video import temporal

# Frames in flight: one being restored, the next being matched.
_FRAMES = 2


@dataclasses.dataclass(frozen=True)
class Unmixed:
  """`outputs` of `unmixer(image, hint=hint)`, run before the pipeline started."""
  image: np.ndarray
  hint: hints.FrameHint
  outputs: Dict[str, object]

  def serves(self, image: np.ndarray, hint: hints.FrameHint) -> bool:
    """Whether `outputs` are those of `image` unmixed with `hint`: the same pixels and
    the same hint, its fallback_mixture aside (only a frame in which detection finds no
    anaglyph reads it, and these outputs came from a frame in which it found one or
    from a named encoding). Hints holding arrays or callbacks (a prior, on_disparity,
    a stored image: never a shot's first frame's) serve nothing."""
    if not np.array_equal(self.image, image):  # False for another shape too.
      return False
    for field in dataclasses.fields(hints.FrameHint):
      if field.name == 'fallback_mixture':
        continue
      values = getattr(self.hint, field.name), getattr(hint, field.name)
      if any(isinstance(v, np.ndarray) or callable(v) for v in values) or (
          values[0] != values[1]):
        return False
    return True


class FramePipeline:
  """Runs `unmixer(image, hint=...)` of consecutive frames in threads, overlapping each
  frame's restoration with the next frame's matching (module docstring).

  Attributes:
    state: the VideoState whose hints the frames get (begun in submission order).
  """

  def __init__(self, unmixer: Callable[..., Dict[str, object]], state: temporal.VideoState):
    self.state = state
    self._unmixer = unmixer
    self._executor = concurrent.futures.ThreadPoolExecutor(
        _FRAMES, thread_name_prefix='mixstereo-frames')
    self._slots = threading.Semaphore(_FRAMES)

  def submit(self, image: np.ndarray, cut: bool = False, unmixed: Optional[Unmixed] = None,
             **hint_fields) -> concurrent.futures.Future:
    """Starts unmixing `image` (`state.begin(image, cut)`'s hint, with `hint_fields`
    replaced) and returns its Future once the next frame may start: when its disparities
    are reported (`hints.FrameHint.on_disparity`) or it is done; with the state's temporal
    consistency off (every frame alone) as soon as fewer than two frames are in flight.
    Where `unmixed` serves this image and hint, its outputs are the frame's, done.

    Raises:
      The frame's own error when it failed before reporting its disparities.
    """
    hint = dataclasses.replace(self.state.begin(image, cut=cut), **hint_fields)
    if unmixed is not None and unmixed.serves(image, hint):
      self.state.end(unmixed.outputs)
      done = concurrent.futures.Future()
      done.set_result(unmixed.outputs)
      return done
    ready, told = threading.Event(), []
    # The shot's decisions are made (never so with temporal consistency off, nor while
    # its encoding may still change): only the prior is new.
    if hint.mixture is not None and hint.may_be is None:

      def on_disparity(found):
        self.state.end(found)
        told.append(True)
        ready.set()

      hint = dataclasses.replace(hint, on_disparity=on_disparity)
    self._slots.acquire()
    pending = self._executor.submit(self._unmixer, image, hint=hint)
    pending.add_done_callback(lambda _: (self._slots.release(), ready.set()))
    if not self.state.config.enabled:  # The next frame needs nothing of this one.
      return pending
    ready.wait()
    if not told:
      self.state.end(pending.result())
    return pending

  def close(self) -> None:
    """Waits for the frames in flight, then stops the threads."""
    self._executor.shutdown(wait=True)

  def __enter__(self) -> 'FramePipeline':
    return self

  def __exit__(self, *exc) -> None:
    self.close()
