"""Before-and-after benchmarks in one run: a measurement evaluated in a fresh process, in
the working tree or in a checkout of an earlier commit (`git worktree add DIR REV`).

    python -m experiments.benchmark_learned --before_checkout=DIR
    python -m experiments.benchmark_diplopia --before_checkout=DIR

The flag is declared here once for every benchmark that takes it.
"""

import json
import os
import subprocess
import sys

from absl import flags

flags.DEFINE_string('before_checkout', '', 'A checkout of an earlier commit (e.g. `git '
                    'worktree add DIR REV`) whose package and experiments give each row\'s '
                    '"before" in the same run (empty: none).')


def measure(module: str, expression: str, checkout: str = ''):
  """The JSON value of Python `expression` (`b`: `experiments.<module>`) in a fresh
  process; run in `checkout` (its package and experiments) when given, which is checked
  to be the package that ran."""
  code = (f'import json, mixstereo_tf; from experiments import {module} as b; '
          'print("RESULT", json.dumps([mixstereo_tf.__file__, ' + expression + ']))')
  env = dict(os.environ, PYTHONPATH=os.path.abspath(checkout)) if checkout else None
  out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                       check=True, env=env, cwd=checkout or None).stdout
  package, value = json.loads(out.split('RESULT ', 1)[1])
  check_package(package, checkout)
  return value


def check_package(package: str, checkout: str = '') -> None:
  """RuntimeError unless `package` (a path inside the package that ran) lies in `checkout`
  (the working tree when empty): a stale install answered otherwise."""
  tree = os.path.abspath(checkout or os.getcwd())
  if not os.path.abspath(package).startswith(tree + os.sep):
    where = f'--before_checkout={checkout}' if checkout else 'the working tree'
    raise RuntimeError(f'{where}: the package came from {package} (a stale install?).')
