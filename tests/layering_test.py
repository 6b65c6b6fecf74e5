"""The package is a house by role: each wing imports only the wings below it.

Wings, bottom to top (docs/DESIGN.md, "Layout"): core < ops < models < data < restoration <
classical < artifacts < unmixing < video < training < evaluation < cli < the binaries at the
package top. `FORBIDDEN` names the arrows that must never exist (the issue's list); `RANK`
orders every wing so that any upward import fails as well.
"""

import ast
import os

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGE = 'mixstereo_tf'
RANK = {wing: rank for rank, wing in enumerate((
    'core', 'ops', 'models', 'data', 'restoration', 'classical', 'artifacts', 'unmixing',
    'video', 'training', 'evaluation', 'cli'))}
TOP = len(RANK)  # The public face and the binaries.
FORBIDDEN = {
    'core': set(RANK) | {'top'},
    'ops': {'models'},
    'models': {'data'},
    'unmixing': {'data', 'training', 'cli'},
    'classical': {'unmixing', 'video', 'models'},
    'restoration': {'unmixing', 'video'},
    'evaluation': {'training'},
    'artifacts': {'unmixing'},
    'video': {'training'},
}
BINARIES = ('__init__', '__main__', 'train', 'evaluate', 'export', 'unmix', 'batch')


def wing_of(module: str) -> str:
  """'core', 'ops', ... for mixstereo_tf.<wing>...; 'top' for the package top."""
  parts = module.split('.')
  return parts[1] if len(parts) > 2 or parts[1] in RANK else 'top'


def package_imports(root: str = REPO):
  """[(importing module, imported module)] of every project import under mixstereo_tf."""
  found = []
  for folder, _, files in os.walk(os.path.join(root, PACKAGE)):
    for name in sorted(files):
      if not name.endswith('.py'):
        continue
      path = os.path.join(folder, name)
      module = os.path.relpath(path, root)[:-3].replace(os.sep, '.')
      with open(path, encoding='utf-8') as f:
        tree = ast.parse(f.read(), path)
      for node in ast.walk(tree):
        if isinstance(node, ast.Import):
          found += [(module, a.name) for a in node.names if a.name.startswith(PACKAGE + '.')]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
          if node.module == PACKAGE:
            found += [(module, f'{PACKAGE}.{a.name}') for a in node.names]
          elif node.module.startswith(PACKAGE + '.'):
            found.append((module, node.module))
  return found


def violations(imports):
  """The imports that break the layering, as 'importer -> imported (why)' lines."""
  bad = []
  for source, target in imports:
    low, high = wing_of(source), wing_of(target)
    if low == high:
      continue
    if high in FORBIDDEN.get(low, ()):
      bad.append(f'{source} -> {target} (forbidden: {low} -> {high})')
    elif RANK.get(high, TOP) > RANK.get(low, TOP):
      bad.append(f'{source} -> {target} (upward: {low} -> {high})')
  return bad


def test_every_module_lives_in_a_wing_or_is_a_binary():
  top = sorted(os.path.splitext(n)[0] for n in os.listdir(os.path.join(REPO, PACKAGE))
               if n.endswith('.py'))
  assert set(top) <= set(BINARIES), top
  folders = {n for n in os.listdir(os.path.join(REPO, PACKAGE))
             if os.path.isdir(os.path.join(REPO, PACKAGE, n)) and n != '__pycache__'}
  assert folders == set(RANK), folders ^ set(RANK)


def test_the_package_respects_its_layering():
  imports = package_imports()
  assert len(imports) > 150
  assert violations(imports) == []


def test_a_planted_violation_is_caught(tmp_path):
  """A copy of the package with core importing unmixing, and ops importing models."""
  package = tmp_path / PACKAGE
  for folder, _, files in os.walk(os.path.join(REPO, PACKAGE)):
    relative = os.path.relpath(folder, REPO)
    for name in files:
      if name.endswith('.py'):
        (tmp_path / relative).mkdir(parents=True, exist_ok=True)
        with open(os.path.join(folder, name), encoding='utf-8') as f:
          (tmp_path / relative / name).write_text(f.read(), encoding='utf-8')
  (package / 'core' / 'planted.py').write_text(
      'from mixstereo_tf.unmixing import detection\n', encoding='utf-8')
  (package / 'ops' / 'planted.py').write_text(
      'import mixstereo_tf.models.refiner\n', encoding='utf-8')
  (package / 'unmixing' / 'planted.py').write_text(
      'from mixstereo_tf.video import temporal\n', encoding='utf-8')
  found = sorted(violations(package_imports(str(tmp_path))))
  assert found == [
      'mixstereo_tf.core.planted -> mixstereo_tf.unmixing (forbidden: core -> unmixing)',
      'mixstereo_tf.ops.planted -> mixstereo_tf.models.refiner (forbidden: ops -> models)',
      'mixstereo_tf.unmixing.planted -> mixstereo_tf.video (upward: unmixing -> video)'], found
