"""The device line: what each binary logs first about the hardware that does the work."""

import ast
import os

import pytest

from mixstereo_tf.cli import device

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BINARIES = ('train', 'evaluate', 'export', 'unmix')


def test_no_gpu_names_the_cpu_cores_and_onednn():
  assert device.describe((), 2, 'on', cuda_driver=False) == (
      'no GPU found: running on 2 CPU cores (oneDNN on)')
  assert device.describe((), 1, 'off', cuda_driver=False) == (
      'no GPU found: running on 1 CPU core (oneDNN off)')


def test_a_driver_without_a_usable_gpu_says_how_to_install_the_gpu_build():
  text = device.describe((), 16, 'on', cuda_driver=True)
  assert text.startswith('no GPU found: running on 16 CPU cores')
  assert "pip install -e '.[gpu]'" in text


def test_gpus_are_named_with_memory_and_compute_capability():
  gpus = (device.Gpu('NVIDIA H100 80GB HBM3', 85_029_158_912, (9, 0)),
          device.Gpu('NVIDIA A100-SXM4-40GB'))
  assert device.describe(gpus, 16, 'on', cuda_driver=True) == (
      'GPU 0: NVIDIA H100 80GB HBM3, 79.2 GiB, compute capability 9.0; '
      'GPU 1: NVIDIA A100-SXM4-40GB')


def test_this_machine_gets_one_line():
  text = device.line()
  assert '\n' not in text and (text.startswith('GPU 0: ') or
                               text.startswith('no GPU found: running on '))


@pytest.mark.parametrize('binary', BINARIES)
def test_every_binary_logs_the_device_line_in_main(binary):
  path = os.path.join(REPO, 'mixstereo_tf', f'{binary}.py')
  with open(path, encoding='utf-8') as f:
    tree = ast.parse(f.read(), path)
  main = next(n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == 'main')
  calls = [ast.unparse(n.func) for n in ast.walk(main) if isinstance(n, ast.Call)]
  assert 'device.log_line' in calls, binary
