"""Tests for the SavedModel export (mixstereo_tf.artifacts.serving and the export binary)."""

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from mixstereo_tf import models
from mixstereo_tf.artifacts import graphs
from mixstereo_tf.artifacts import runs
from mixstereo_tf.artifacts import serving
from mixstereo_tf.unmixing import disparity_range
from mixstereo_tf.unmixing import predictors
from tests.unmixing import predictors_test

SIZES = ((375, 1242), (97, 131))
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Runs in a fresh interpreter with only TensorFlow and NumPy: the export must not need us.
_PLAIN_TF_SCRIPT = textwrap.dedent("""
    import json, sys
    import numpy as np
    import tensorflow as tf
    export_dir, inputs, outputs = sys.argv[1:4]
    loaded = tf.saved_model.load(export_dir)
    serve = loaded.signatures['serving_default']
    results = {}
    with np.load(inputs) as images:
      for key in sorted(images.files):
        out = serve(image=tf.constant(images[key]))
        for name, value in out.items():
          results[key + '/' + name] = value.numpy()
    np.savez(outputs, **results)
    meta = {k: v.numpy() for k, v in loaded.signatures['metadata']().items()}
    meta = {k: v.decode() if isinstance(v, bytes) else int(v) for k, v in meta.items()}
    meta['attribute_mixture'] = loaded.mixture.numpy().decode()
    meta['mixstereo_imported'] = any(m.startswith('mixstereo_tf') for m in sys.modules)
    print(json.dumps(meta))
""")


def _run(command, cwd, env=None):
  env = env or dict(os.environ)
  env['TF_CPP_MIN_LOG_LEVEL'] = '2'
  return subprocess.run(command, capture_output=True, text=True, env=env, cwd=cwd,
                        timeout=300, check=False)


@pytest.fixture(scope='module')
def exported(tmp_path_factory):
  """A training run directory exported by the export binary."""
  root = tmp_path_factory.mktemp('export')
  model, _ = predictors_test.make_run_dir(str(root / 'run'), mixture='diplopia', seed=3)
  export_dir = str(root / 'saved')
  result = _run([sys.executable, '-m', 'mixstereo_tf.export', f'--checkpoint={root / "run"}',
                 f'--export_dir={export_dir}'], cwd=REPO)
  assert result.returncode == 0, result.stderr[-3000:]
  return model, runs.RunInfo('diplopia', 64, 128, predictors_test.TINY), export_dir, str(
      root / 'run')


def test_plain_tensorflow_loads_the_export_and_matches_keras(exported, tmp_path):
  _, info, export_dir, run_dir = exported
  rng = np.random.RandomState(0)
  images = {f'{h}x{w}': rng.randint(0, 256, (h, w, 3)).astype(np.uint8) for h, w in SIZES}
  np.savez(tmp_path / 'in.npz', **images)
  env = dict(os.environ)
  env.pop('PYTHONPATH', None)  # The script must not reach mixstereo_tf.
  result = _run([sys.executable, '-c', _PLAIN_TF_SCRIPT, export_dir, str(tmp_path / 'in.npz'),
                 str(tmp_path / 'out.npz')], cwd=str(tmp_path), env=env)
  assert result.returncode == 0, result.stderr[-3000:]
  meta = json.loads(result.stdout.strip().splitlines()[-1])
  assert not meta['mixstereo_imported']
  assert meta['mixture'] == meta['attribute_mixture'] == 'diplopia'
  assert (meta['crop_height'], meta['crop_width']) == (64, 128)
  assert meta['max_disparity'] == predictors_test.TINY.max_disparity
  assert meta['size_multiple'] == 32
  assert models.ModelConfig.from_dict(json.loads(meta['model_config'])) == info.model_config

  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      checkpoint=run_dir, restore_colour=False,
      disparity_range=disparity_range.NETWORK))  # The image as it is, as the graph sees it.
  with np.load(tmp_path / 'out.npz') as served:
    for key, image in images.items():
      expected = unmixer(image)
      height, width = image.shape[:2]
      for name in ('left', 'right'):
        got = served[f'{key}/{name}']
        assert got.shape == (height, width, 3) and got.dtype == np.uint8
        assert np.abs(got.astype(int) - expected[name]).max() <= 1
      for name, ours in (('disparity', 'disparity_left'),
                         ('disparity_right', 'disparity_right')):
        got = served[f'{key}/{name}']
        assert got.shape == (height, width) and got.dtype == np.float32
        np.testing.assert_allclose(got, expected[ours], atol=1e-4)
      assert served[f'{key}/disparity'].std() > 0  # Not a constant map.


def test_saved_model_unmixer_reads_the_metadata(exported):
  _, info, export_dir, run_dir = exported
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(saved_model=export_dir))
  assert (unmixer.mixture, unmixer.max_disparity) == ('diplopia', info.model_config.max_disparity)
  assert not unmixer.restore_colour
  image = np.random.RandomState(2).randint(0, 256, (45, 70, 3)).astype(np.uint8)
  expected = predictors.build_unmixer(predictors.PredictorConfig(checkpoint=run_dir))(image)
  got = unmixer(image)
  np.testing.assert_allclose(got['disparity_left'], expected['disparity_left'], atol=1e-4)
  assert np.abs(got['left'].astype(int) - expected['left']).max() <= 1
  with open(os.path.join(export_dir, 'assets.extra', serving.RUN_INFO_FILE)) as f:
    assert json.load(f) == info.to_dict()
  assert serving.load_saved_model(export_dir)[1] == info


def test_export_errors(exported, tmp_path):
  model, info, export_dir, _ = exported
  with pytest.raises(ValueError, match='already holds'):
    serving.export_saved_model(graphs.serving_function(model), model.variables, info,
                               export_dir)
  with pytest.raises(ValueError, match='No SavedModel'):
    serving.load_saved_model(str(tmp_path))
  (tmp_path / 'notes.txt').write_text('mine')
  for target, why in ((tmp_path, 'is not empty'), (tmp_path / 'notes.txt', 'is a file'),
                      (os.path.join(export_dir, 'variables'), 'is not empty')):
    with pytest.raises(ValueError, match=why):
      serving.export_saved_model(graphs.serving_function(model), model.variables, info,
                                 str(target))
  assert (tmp_path / 'notes.txt').read_text() == 'mine'


def test_export_of_a_shipped_model_says_why_it_cannot(tmp_path):
  for flags, message in (([], 'Give --checkpoint'),
                         (['--pretrained=anaglyph_matching'],
                          "'features' model, learned descriptors whose costs a classical")):
    result = _run([sys.executable, '-m', 'mixstereo_tf.export',
                   f'--export_dir={tmp_path / "x"}', *flags], cwd=REPO)
    assert result.returncode != 0 and message in result.stderr, result.stderr[-2000:]
    assert 'Traceback' not in result.stderr and not os.path.exists(tmp_path / 'x')


def test_the_checkpoint_weights_were_exported(exported):
  model, _, export_dir, _ = exported
  loaded, _ = serving.load_saved_model(export_dir)
  assert len(loaded.model_variables) == len(model.variables)
  for saved, restored in zip(model.variables, loaded.model_variables):
    np.testing.assert_array_equal(saved.numpy(), restored.numpy())


def test_exporting_a_half_trained_run_warns(tmp_path):
  predictors_test.make_run_dir(str(tmp_path / 'run'), mode='stereo_only')
  result = _run([sys.executable, '-m', 'mixstereo_tf.export', f'--checkpoint={tmp_path / "run"}',
                 f'--export_dir={tmp_path / "saved"}'], cwd=REPO)
  assert result.returncode == 0, result.stderr[-2000:]
  assert 'was trained with mode stereo_only' in result.stderr
