"""Overlapping a frame loop's input, compute and output in threads, order kept.

    with Prefetcher(frames, depth=4) as ahead, SerialWorker(depth=4) as writer:
      for frame in ahead:                      # decoded in a background thread
        images = compute(frame)                # this thread
        writer.submit(encode, frame, images)   # encoded in a background thread, in order
      writer.drain()                           # raises the first failure of a task

Decoding and encoding (FFmpeg through PyAV) and the numba kernels release the GIL, so the
three stages run at once on different cores. Both queues are bounded (`depth`), so memory
stays bounded when one stage is slower. A failure in a background stage is raised in the
calling thread at its next call; leaving a `with` block (also by an exception or Ctrl-C)
stops the prefetching thread and waits for the submitted tasks, which therefore always run
in submission order and completely or not at all.
"""

import queue
import threading
from typing import Callable, Iterable, Iterator, List

_END = object()


class Prefetcher:
  """Iterates `items` in a background thread, at most `depth` items ahead of the reader."""

  def __init__(self, items: Iterable, depth: int = 4):
    if depth < 1:
      raise ValueError(f'Prefetcher depth must be >= 1, got {depth}.')
    self._items = items
    self._queue: queue.Queue = queue.Queue(depth)
    self._stop = threading.Event()
    self._thread = threading.Thread(target=self._produce, daemon=True)
    self._thread.start()

  def _put(self, item) -> bool:
    while not self._stop.is_set():
      try:
        self._queue.put(item, timeout=0.1)
        return True
      except queue.Full:
        continue
    return False

  def _produce(self) -> None:
    try:
      for item in self._items:
        if not self._put((item, None)):
          return
    except BaseException as error:  # pylint: disable=broad-except (re-raised by the reader)
      self._put((_END, error))
      return
    self._put((_END, None))

  def __iter__(self) -> Iterator:
    while True:
      item, error = self._queue.get()
      if error is not None:
        raise error
      if item is _END:
        return
      yield item

  def close(self) -> None:
    """Stops the background thread (the rest of `items` is not read) and waits for it."""
    self._stop.set()
    self._thread.join()

  def __enter__(self) -> 'Prefetcher':
    return self

  def __exit__(self, *exc) -> None:
    self.close()


class SerialWorker:
  """Runs submitted calls one at a time, in submission order, in a background thread."""

  def __init__(self, depth: int = 4):
    if depth < 1:
      raise ValueError(f'SerialWorker depth must be >= 1, got {depth}.')
    self._queue: queue.Queue = queue.Queue(depth)
    self._errors: List[BaseException] = []
    self._thread = threading.Thread(target=self._consume, daemon=True)
    self._thread.start()

  def _consume(self) -> None:
    while True:
      task = self._queue.get()
      if task is _END:
        return
      if not self._errors:  # After a failure the remaining tasks are dropped.
        try:
          task()
        except BaseException as error:  # pylint: disable=broad-except (raised by submit/drain)
          self._errors.append(error)

  def _raise(self) -> None:
    if self._errors:
      raise self._errors[0]

  def submit(self, fn: Callable, *args) -> None:
    """Queues fn(*args), waiting while `depth` calls are pending; raises an earlier
    call's failure."""
    self._raise()
    self._queue.put(lambda: fn(*args))

  def drain(self) -> None:
    """Waits until every submitted call has run; raises the first failure."""
    done = threading.Event()
    self._queue.put(done.set)
    while not done.wait(0.1) and not self._errors:
      continue
    self._raise()

  def close(self) -> None:
    """Runs what is queued (unless a call failed), then stops the thread."""
    self._queue.put(_END)
    self._thread.join()

  def __enter__(self) -> 'SerialWorker':
    return self

  def __exit__(self, *exc) -> None:
    self.close()
