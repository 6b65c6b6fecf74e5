"""The command-line tools start quietly: no TensorFlow start-up chatter, no CUDA errors."""

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
