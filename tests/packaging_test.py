"""The wheel carries what an installed package needs outside the repository."""

import glob
import os
import subprocess
import sys
import zipfile

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_the_wheel_ships_the_split_lists_as_package_data(tmp_path):
  result = subprocess.run(
      [sys.executable, '-m', 'pip', 'wheel', '--no-deps', '--no-build-isolation', '-q',
       '-w', str(tmp_path), REPO], capture_output=True, text=True, timeout=300, check=False)
  assert result.returncode == 0, result.stderr[-3000:]
  wheel, = glob.glob(str(tmp_path / 'mixstereo_tf-*.whl'))
  names = set(zipfile.ZipFile(wheel).namelist())
  for name in ('eigen_test_files.txt', 'kitti_train_files.txt', 'eigen_train_files.txt'):
    assert f'mixstereo_tf/data_lists/kitti/{name}' in names
  assert 'mixstereo_tf/data_lists/middlebury/finetune_scenes.txt' in names
  assert 'mixstereo_tf/evaluation/protocols/eigen.py' in names
  assert 'mixstereo_tf/cli/flags.py' in names
  shipped = {n for n in names if n.startswith('mixstereo_tf/artifacts/pretrained/')}
  for model in ('anaglyph', 'diplopia'):
    assert {f'mixstereo_tf/artifacts/pretrained/{model}/info.json',
            f'mixstereo_tf/artifacts/pretrained/{model}/weights.npz'} <= shipped
  # Installed (the wheel unpacked, no repository around it): the Eigen protocol's default
  # list resolves to the packaged copy, all 697 test frames.
  site = tmp_path / 'site'
  zipfile.ZipFile(wheel).extractall(site)
  script = ('import os\n'
            'from mixstereo_tf.data import split_lists\n'
            'from mixstereo_tf.evaluation import protocols\n'
            'from mixstereo_tf.artifacts import pretrained\n'
            "path = split_lists.resolve(protocols.get('eigen').default_split_list)\n"
            "entry = pretrained.choose(None, 'auto')\n"
            'pretrained.load_model(entry)\n'
            'print(path, sum(1 for _ in open(path)), entry.folder)\n')
  outside = tmp_path / 'elsewhere'
  outside.mkdir()
  env = dict(os.environ, PYTHONPATH=str(site))
  result = subprocess.run([sys.executable, '-c', script], cwd=str(outside), env=env,
                          capture_output=True, text=True, timeout=300, check=False)
  assert result.returncode == 0, result.stderr[-3000:]
  path, count, model = result.stdout.split()
  assert path.startswith(str(site)) and path.endswith('eigen_test_files.txt')
  assert count == '697'
  assert model.startswith(str(site))  # The shipped model loads from the installed package.
