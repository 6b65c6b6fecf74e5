"""Tests for mixstereo_tf.core.workers."""

import os

from mixstereo_tf.core import workers


def test_usable_cpus_follows_the_request_or_the_affinity_mask():
  assert workers.usable_cpus(3) == 3
  expected = (len(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity')
              else os.cpu_count())
  assert workers.usable_cpus() == expected >= 1
