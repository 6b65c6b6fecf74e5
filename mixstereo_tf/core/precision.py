"""Whether inference convolutions run in bfloat16: the one place that decides it.

CPUs with native bfloat16 dot products (x86 `avx512_bf16` or `amx_bf16`, which oneDNN
uses) run TensorFlow's convolutions in bfloat16 about twice as fast as in float32
(experiments/BENCHMARKS.md section 20); elsewhere oneDNN emulates them, slower than
float32. Variables stay float32; what the layers compute in bfloat16 is chosen by the model
(`models/layers_util.compute_in_bfloat16`). `MIXSTEREO_BFLOAT16=0` or `1` overrides the
detection; set but empty, it is read as unset (`MIXSTEREO_BFLOAT16= cmd` in a shell).
"""

import os

ENVIRONMENT = 'MIXSTEREO_BFLOAT16'
_FLAGS = ('avx512_bf16', 'amx_bf16')


def _cpu_flags(path: str = '/proc/cpuinfo') -> set:
  """The feature flags of the first CPU listed in `path` (empty where it is unreadable)."""
  try:
    with open(path, encoding='utf-8', errors='replace') as handle:
      for line in handle:
        if line.startswith('flags'):
          return set(line.split(':', 1)[1].split())
  except OSError:
    pass
  return set()


def inference_bfloat16(cpuinfo: str = '/proc/cpuinfo') -> bool:
  """True where inference convolutions should run in bfloat16 (module docstring).

  Raises:
    ValueError: MIXSTEREO_BFLOAT16 set to something other than 0 or 1.
  """
  forced = os.environ.get(ENVIRONMENT, '').strip()
  if forced:
    if forced not in ('0', '1'):
      raise ValueError(f'{ENVIRONMENT} must be 0 or 1, got {forced!r}.')
    return forced == '1'
  return bool(_cpu_flags(cpuinfo) & set(_FLAGS))
