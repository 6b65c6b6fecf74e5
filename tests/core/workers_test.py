"""Tests for mixstereo_tf.core.workers."""

import os
import select
import signal
import threading
import time

from mixstereo_tf.core import workers


def test_usable_cpus_follows_the_request_or_the_affinity_mask():
  assert workers.usable_cpus(3) == 3
  expected = (len(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity')
              else os.cpu_count())
  assert workers.usable_cpus() == expected >= 1


def test_run_tasks_keeps_order_and_reuses_its_threads():
  names = set()

  def task(value):
    names.add(threading.current_thread().name)
    time.sleep(0.01)
    return value * value

  assert workers.run_tasks(task, list(range(8)), 2) == [v * v for v in range(8)]
  first = set(names)
  assert workers.run_tasks(task, list(range(8)), 2) == [v * v for v in range(8)]
  assert names == first and len(first) == 2  # The same two threads both times.
  assert all(name.startswith('mixstereo-kernels') for name in first)


def test_run_tasks_runs_in_the_callers_thread_for_one_thread_or_task():
  caller = threading.current_thread().name
  seen = workers.run_tasks(lambda _: threading.current_thread().name, [0, 1, 2], 1)
  assert seen == [caller] * 3
  assert workers.run_tasks(lambda _: threading.current_thread().name, [0], 4) == [caller]


def test_a_task_that_runs_tasks_does_not_wait_on_its_own_pool():
  inner = lambda value: workers.run_tasks(lambda v: v + 1, [value, value], 2)
  # Two outer tasks fill a pool of two; each inner call runs in its task's thread.
  assert workers.run_tasks(inner, [1, 5], 2) == [[2, 2], [6, 6]]


def test_a_forked_child_starts_its_own_pool():
  workers.run_tasks(abs, [-1, -2], 2)  # The parent's pool exists.
  read, write = os.pipe()
  child = os.fork()
  if child == 0:  # pragma: no cover - the child reports through the pipe.
    try:
      result = workers.run_tasks(abs, [-3, -4], 2)
      os.write(write, b'ok' if result == [3, 4] else b'bad')
    finally:
      os._exit(0)  # pylint: disable=protected-access
  os.close(write)
  ready, _, _ = select.select([read], [], [], 60)  # A child on a dead pool would hang.
  if not ready:
    os.kill(child, signal.SIGKILL)
  os.waitpid(child, 0)
  assert ready and os.read(read, 16) == b'ok'


def test_row_blocks_cover_every_row_once_in_near_equal_blocks():
  assert workers.row_blocks(10, 3) == [(0, 3), (3, 7), (7, 10)]
  assert workers.row_blocks(2, 8) == [(0, 1), (1, 2)]  # No empty block.
  assert workers.row_blocks(5, 0) == [(0, 5)]
  blocks = workers.row_blocks(721, 8)
  assert blocks[0][0] == 0 and blocks[-1][1] == 721
  assert all(a[1] == b[0] for a, b in zip(blocks, blocks[1:]))
  assert {b - a for a, b in blocks} <= {90, 91}
