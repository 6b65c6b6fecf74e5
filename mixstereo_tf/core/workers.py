"""How many threads a kernel may use: the one place that reads the CPU count."""

import os


def usable_cpus(requested: int = 0) -> int:
  """`requested` threads, or when 0 the CPUs this process may use (on Linux its affinity
  mask, e.g. under `taskset`, not the machine's count)."""
  if requested:
    return requested
  if hasattr(os, 'sched_getaffinity'):
    return len(os.sched_getaffinity(0))
  return os.cpu_count() or 1
