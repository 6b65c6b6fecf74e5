"""The command-line tools start quietly: no TensorFlow start-up chatter, no CUDA errors,
only their own device line."""

import os
import subprocess
import sys

import numpy as np

from mixstereo_tf.cli import media

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def test_a_cli_run_prints_no_cuda_or_startup_lines_but_keeps_its_own_log(tmp_path):
  image = np.random.default_rng(0).integers(0, 256, (24, 40, 3), dtype=np.uint8)
  media.write_image(str(tmp_path / 'in.png'), image)
  env = {k: v for k, v in os.environ.items() if k != 'TF_CPP_MIN_LOG_LEVEL'}
  result = subprocess.run(
      [sys.executable, '-m', 'mixstereo_tf.unmix', '--method=classical', '--mixture=anaglyph',
       f'--input={tmp_path / "in.png"}', f'--output_dir={tmp_path / "out"}'],
      cwd=REPO, env=env, capture_output=True, text=True, timeout=300, check=False)
  assert result.returncode == 0, result.stderr[-3000:]
  lines = result.stderr.splitlines()
  assert not [line for line in lines if 'cuda' in line.lower() or 'cuInit' in line], lines
  assert not [line for line in lines if line.startswith('I0000')], lines
  assert any('1 input(s) done' in line for line in lines), lines  # Our own INFO log.
  # The device line (cli/device.py), the one start-up line that is ours.
  assert any('no GPU found: running on' in line or '] GPU 0: ' in line for line in lines), lines


def test_cuda_registration_errors_are_hidden_other_errors_are_not():
  from mixstereo_tf.core import quiet_import  # pylint: disable=g-import-not-at-top
  assert quiet_import.is_noise('E0000 00:00:1731.5 77 cuda_fft.cc:485] Unable to register cuFFT '
                           'factory: Attempting to register factory for plugin cuFFT when one '
                           'has already been registered')
  assert quiet_import.is_noise('W0000 00:00:1731.5 77 py_utils.cc:38] TF-TRT Warning: Could not '
                           'find TensorRT')
  assert not quiet_import.is_noise('E0000 00:00:1731.5 77 gpu_device.cc:2342] Cannot dlopen some '
                               'GPU libraries.')
  assert quiet_import.is_noise('I0000 00:00:1731.5 77 cpu_feature_guard.cc:210] This TensorFlow '
                           'binary is optimized')


def test_a_checkout_shadowed_by_another_copy_of_the_package_is_warned_about(tmp_path):
  from mixstereo_tf.cli import startup  # pylint: disable=import-outside-toplevel
  assert startup.shadowing_warning(str(tmp_path)) == ''  # No source tree here.
  (tmp_path / 'mixstereo_tf').mkdir()
  (tmp_path / 'mixstereo_tf' / '__init__.py').write_text('')
  assert str(tmp_path / 'mixstereo_tf') in startup.shadowing_warning(str(tmp_path))
  imported_root = os.path.dirname(os.path.dirname(os.path.dirname(startup.__file__)))
  assert startup.shadowing_warning(imported_root) == ''  # The imported tree itself.


def test_beams_apitools_note_is_dropped_and_other_root_records_kept(caplog):
  import logging  # pylint: disable=import-outside-toplevel
  from mixstereo_tf.cli import startup  # pylint: disable=import-outside-toplevel,unused-import
  caplog.set_level(logging.WARNING)
  logging.warning('apitools not found, and bigquery client libraries are not available.')
  logging.warning('a real warning')
  assert [r.getMessage() for r in caplog.records] == ['a real warning']
