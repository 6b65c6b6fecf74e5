"""Tests of the threaded prefetcher and serial worker: order, bounds, failures."""

import threading
import time

import pytest

from mixstereo_tf.video import pipelining


def test_prefetcher_yields_every_item_in_order_from_another_thread():
  threads = []

  def items():
    for i in range(50):
      threads.append(threading.get_ident())
      yield i

  with pipelining.Prefetcher(items(), depth=3) as ahead:
    assert list(ahead) == list(range(50))
  assert set(threads) != {threading.get_ident()}


def test_prefetcher_reads_at_most_depth_items_ahead_and_stops_on_close():
  produced = []

  def items():
    for i in range(1000):
      produced.append(i)
      yield i

  ahead = pipelining.Prefetcher(items(), depth=2)
  iterator = iter(ahead)
  assert next(iterator) == 0
  time.sleep(0.3)
  # One taken, two queued, one waiting to be queued.
  assert len(produced) <= 4
  ahead.close()
  assert len(produced) <= 5


def test_prefetcher_raises_the_producers_failure_after_its_items():
  def items():
    yield 1
    raise OSError('disk gone')

  with pipelining.Prefetcher(items()) as ahead:
    got = []
    with pytest.raises(OSError, match='disk gone'):
      for item in ahead:
        got.append(item)
  assert got == [1]


def test_serial_worker_runs_calls_in_order_in_one_other_thread():
  order, threads = [], set()

  def task(i):
    time.sleep(0.001 * (i % 3))
    order.append(i)
    threads.add(threading.get_ident())

  with pipelining.SerialWorker(depth=2) as worker:
    for i in range(30):
      worker.submit(task, i)
    worker.drain()
    assert order == list(range(30))
  assert len(threads) == 1 and threading.get_ident() not in threads


def test_serial_worker_raises_a_failure_and_drops_later_calls():
  ran = []

  def task(i):
    if i == 2:
      raise ValueError('encoder failed')
    ran.append(i)

  worker = pipelining.SerialWorker(depth=1)
  with pytest.raises(ValueError, match='encoder failed'):
    for i in range(10):
      worker.submit(task, i)
    worker.drain()
  worker.close()
  assert ran == [0, 1]


def test_depth_must_be_positive():
  with pytest.raises(ValueError, match='depth'):
    pipelining.SerialWorker(depth=0)
  with pytest.raises(ValueError, match='depth'):
    pipelining.Prefetcher([], depth=0)
