"""House style the package keeps: functions one reads at once."""

import ast
import os

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MAX_FUNCTION_LINES = 60


def long_functions(root: str, limit: int = MAX_FUNCTION_LINES):
  """['path:function (lines)'] of every function under `root` longer than `limit` lines."""
  found = []
  for folder, _, files in os.walk(root):
    for name in sorted(files):
      if name.endswith('.py'):
        path = os.path.join(folder, name)
        with open(path, encoding='utf-8') as f:
          tree = ast.parse(f.read(), path)
        for node in ast.walk(tree):
          if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            lines = node.end_lineno - node.lineno + 1
            if lines > limit:
              found.append(f'{os.path.relpath(path, root)}:{node.name} ({lines})')
  return found


def test_no_function_in_the_package_is_longer_than_60_lines():
  assert long_functions(os.path.join(REPO, 'mixstereo_tf')) == []


def test_a_long_function_is_found(tmp_path):
  body = ''.join(f'  x{i} = {i}\n' for i in range(61))
  (tmp_path / 'long.py').write_text(f'def f():\n{body}\n\ndef g():\n  return 1\n')
  assert long_functions(str(tmp_path)) == ['long.py:f (62)']
