"""The package and the experiment scripts import cleanly and their import graph is acyclic."""

import ast
import os
import subprocess
import sys

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGES = ('mixstereo_tf', 'experiments')


def _modules():
  """{module name: file path} of every .py file under PACKAGES."""
  found = {}
  for package in PACKAGES:
    for folder, _, files in os.walk(os.path.join(REPO, package)):
      for name in files:
        if name.endswith('.py'):
          path = os.path.join(folder, name)
          module = os.path.relpath(path, REPO)[:-3].replace(os.sep, '.')
          found[module[:-len('.__init__')] if module.endswith('.__init__') else module] = path
  return found


def _edges(modules):
  """{module: set of project modules it imports}, from the import statements anywhere in it."""
  edges = {}
  for module, path in modules.items():
    with open(path, encoding='utf-8') as f:
      tree = ast.parse(f.read(), path)
    targets = set()
    for node in ast.walk(tree):
      if isinstance(node, ast.Import):
        targets.update(alias.name for alias in node.names if alias.name in modules)
      elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
        for alias in node.names:
          full = f'{node.module}.{alias.name}'
          if full in modules:
            targets.add(full)
          elif node.module in modules:
            targets.add(node.module)
    edges[module] = targets - {module}
  return edges


def _cycle(edges):
  """One import cycle as a list of modules, or None."""
  state, path = {}, []

  def visit(module):
    state[module] = 'open'
    path.append(module)
    for target in sorted(edges[module]):
      if state.get(target) == 'open':
        return path[path.index(target):] + [target]
      if target not in state:
        found = visit(target)
        if found:
          return found
    path.pop()
    state[module] = 'done'
    return None

  for module in sorted(edges):
    if module not in state:
      found = visit(module)
      if found:
        return found
  return None


def test_the_import_graph_is_acyclic():
  edges = _edges(_modules())
  assert len(edges) > 40
  assert _cycle(edges) is None, ' -> '.join(_cycle(edges))


def test_cycle_finder_finds_a_planted_cycle():
  assert _cycle({'a': {'b'}, 'b': {'c'}, 'c': {'a'}, 'd': set()}) == ['a', 'b', 'c', 'a']
  assert _cycle({'a': {'b'}, 'b': set()}) is None


def test_every_module_imports_in_one_fresh_interpreter():
  """Every module (binaries included, so every flag is declared exactly once) imports."""
  names = sorted(_modules())
  script = ('import importlib, sys\n'
            'for name in sys.argv[1:]:\n'
            '  importlib.import_module(name)\n'
            'print("imported", len(sys.argv) - 1)\n')
  env = dict(os.environ, PYTHONPATH=REPO)
  result = subprocess.run([sys.executable, '-c', script, *names], cwd=REPO, env=env,
                          capture_output=True, text=True, timeout=300, check=False)
  assert result.returncode == 0, result.stderr[-3000:]
  assert result.stdout.strip().endswith(f'imported {len(names)}')
