"""The one line every tool logs at start: what will do the work.

On a GPU machine whose TensorFlow lacks its CUDA libraries (`pip install tensorflow`
instead of `pip install -e '.[gpu]'`), TensorFlow's own "Cannot dlopen some GPU libraries"
warning is among the start-up lines `startup` hides, and a run silently trains on the CPU.
So each binary logs, first thing, one line of its own:

  GPU 0: NVIDIA H100 80GB HBM3, 79.1 GiB, compute capability 9.0
  no GPU found: running on 2 CPU cores (oneDNN on)

The second form adds a hint when a CUDA driver is installed (a GPU is there, TensorFlow
cannot use it). oneDNN is TensorFlow's fast CPU kernel library; `mixstereo_tf` turns it
on (its `__init__`), and without it the 3D convolutions train ~20x slower.
"""

import ctypes
import dataclasses
from typing import Optional, Sequence, Tuple

from absl import logging
import tensorflow as tf

from mixstereo_tf.core import workers

_GIB = 1024 ** 3


@dataclasses.dataclass(frozen=True)
class Gpu:
  """One GPU as TensorFlow sees it: name, total memory (bytes, None if unknown) and CUDA
  compute capability (None if unknown)."""
  name: str
  memory: Optional[int] = None
  capability: Optional[Tuple[int, int]] = None


def _libcuda() -> Optional[ctypes.CDLL]:
  try:
    return ctypes.CDLL('libcuda.so.1')
  except OSError:
    return None


def gpu_memory_bytes(ordinal: int) -> Optional[int]:
  """Total memory of the CUDA device `ordinal` (after CUDA_VISIBLE_DEVICES, as TensorFlow
  numbers them) from the CUDA driver, or None without a driver or on any failure."""
  cuda = _libcuda()
  if cuda is None:
    return None
  try:
    device, total = ctypes.c_int(), ctypes.c_size_t()
    if (cuda.cuInit(0) or cuda.cuDeviceGet(ctypes.byref(device), ordinal) or
        cuda.cuDeviceTotalMem_v2(ctypes.byref(total), device)):
      return None
    return int(total.value)
  except AttributeError:  # A driver without these entry points.
    return None


def onednn_state() -> str:
  """'on' or 'off': whether TensorFlow's oneDNN CPU kernels run ('unknown' if it cannot
  say)."""
  try:
    from tensorflow.python.util import _pywrap_util_port  # pylint: disable=g-import-not-at-top
    return 'on' if _pywrap_util_port.IsMklEnabled() else 'off'
  except (ImportError, AttributeError):
    return 'unknown'


def visible_gpus() -> Tuple[Gpu, ...]:
  """The GPUs TensorFlow will use, in its order."""
  found = []
  for ordinal, device in enumerate(tf.config.list_physical_devices('GPU')):
    try:
      details = tf.config.experimental.get_device_details(device)
    except (ValueError, RuntimeError):
      details = {}
    found.append(Gpu(name=details.get('device_name', device.name),
                     memory=gpu_memory_bytes(ordinal),
                     capability=details.get('compute_capability')))
  return tuple(found)


def describe(gpus: Sequence[Gpu], cpu_cores: int, onednn: str, cuda_driver: bool) -> str:
  """The device line of these facts (module docstring)."""
  if not gpus:
    text = f'no GPU found: running on {cpu_cores} CPU core{"s" if cpu_cores != 1 else ""}'
    text += f' (oneDNN {onednn})'
    if cuda_driver:
      text += ("; a CUDA driver is installed but TensorFlow cannot use it: install its CUDA "
               "libraries with pip install -e '.[gpu]'")
    return text
  parts = []
  for index, gpu in enumerate(gpus):
    facts = [gpu.name]
    if gpu.memory is not None:
      facts.append(f'{gpu.memory / _GIB:.1f} GiB')
    if gpu.capability:
      facts.append('compute capability ' + '.'.join(str(v) for v in gpu.capability))
    parts.append(f'GPU {index}: ' + ', '.join(facts))
  return '; '.join(parts)


def line() -> str:
  """The device line of this process."""
  return describe(visible_gpus(), workers.usable_cpus(), onednn_state(),
                  _libcuda() is not None)


def log_line() -> str:
  """Logs the device line (INFO) and returns it; the binaries call it first thing."""
  text = line()
  logging.info('%s', text)
  return text
