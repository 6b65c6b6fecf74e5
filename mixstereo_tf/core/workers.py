"""How many threads a kernel may use (the one place that reads the CPU count), and the
threads that run kernels' row blocks.

`run_tasks` runs on one lasting thread pool per thread count, not a new pool per call: a
720p double-image frame makes about 40 calls (its conjugate-gradient steps among them),
and starting threads for each cost about 60 ms a frame. A task that itself calls
`run_tasks` runs its tasks in its own thread (no pool waits on itself), and a forked child
starts new pools (threads do not survive a fork).
"""

import concurrent.futures
import os
import threading
from typing import Callable, Dict, Sequence

import numpy as np

_POOLS: Dict[int, concurrent.futures.ThreadPoolExecutor] = {}
_POOLS_LOCK = threading.Lock()
_LOCAL = threading.local()


def usable_cpus(requested: int = 0) -> int:
  """`requested` threads, or when 0 the CPUs this process may use (on Linux its affinity
  mask, e.g. under `taskset`, not the machine's count)."""
  if requested:
    return requested
  if hasattr(os, 'sched_getaffinity'):
    return len(os.sched_getaffinity(0))
  return os.cpu_count() or 1


def _mark_worker() -> None:
  _LOCAL.worker = True


def _pool(threads: int) -> concurrent.futures.ThreadPoolExecutor:
  with _POOLS_LOCK:
    if threads not in _POOLS:
      _POOLS[threads] = concurrent.futures.ThreadPoolExecutor(
          threads, thread_name_prefix='mixstereo-kernels', initializer=_mark_worker)
    return _POOLS[threads]


def _forget_pools() -> None:
  global _POOLS_LOCK  # pylint: disable=global-statement
  _POOLS.clear()
  _POOLS_LOCK = threading.Lock()


if hasattr(os, 'register_at_fork'):
  os.register_at_fork(after_in_child=_forget_pools)


def run_tasks(fn: Callable[[object], object], tasks: Sequence[object], threads: int) -> list:
  """[fn(task) for task in tasks], at most `threads` at a time on the lasting pool (in
  this thread when threads == 1, for one task, or inside a pool's task); fn should
  release the GIL (numba's nogil kernels, OpenCV) to run in parallel."""
  if threads == 1 or len(tasks) <= 1 or getattr(_LOCAL, 'worker', False):
    return [fn(task) for task in tasks]
  return list(_pool(min(threads, len(tasks))).map(fn, tasks))


def row_blocks(height: int, blocks: int):
  """(start, stop) row ranges cutting `height` rows into min(height, blocks) near-equal
  blocks, one task each for `run_tasks`."""
  bounds = np.linspace(0, height, min(height, max(1, blocks)) + 1).round().astype(int)
  return [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]
