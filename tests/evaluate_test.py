"""Tests for the result tables (evaluation/report.py) and the mixstereo-eval binary."""

import csv
import dataclasses
import json
import os
import subprocess
import sys

import pytest
import tensorflow as tf

from mixstereo_tf import models
from mixstereo_tf.artifacts import graphs
from mixstereo_tf.artifacts import runs
from mixstereo_tf.artifacts import serving
from mixstereo_tf.data import sample
from mixstereo_tf.evaluation import report
from mixstereo_tf.evaluation import results
from mixstereo_tf.evaluation import runner
from mixstereo_tf.unmixing import disparity_range
from mixstereo_tf.unmixing import predictors
from tests.evaluation import runner_test

EvalConfig = results.EvalConfig

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Size multiple 4, disparity range 8: a forward pass on 32 x 64 takes milliseconds.
TINY = models.ModelConfig(separation_widths=(4, 4), stereo_features=4,
                          stereo_residual_blocks=1, stereo_3d_widths=(4,), max_disparity=8)


def _oracle_result(config):
  return runner.evaluate(config, runner_test.oracle(config))


def test_middlebury_table_has_the_papers_rows_for_matching_scenes(tmp_path):
  root = runner_test.make_middlebury(tmp_path / 'mb')
  result = _oracle_result(EvalConfig('middlebury', 'anaglyph', root))
  text = report.format_report(result)
  lines = text.splitlines()
  assert 'this run (model)' in text and '2 of 2 images' in lines[0]
  # Ours first, then the trivial baseline and the paper's three rows per known scene.
  tsukuba = lines.index(next(l for l in lines if l.startswith('tsukuba')))
  assert '100.00' in lines[tsukuba] and '0.00%' in lines[tsukuba]
  assert 'mixture as each view' in lines[tsukuba + 1]
  for offset, numbers in ((2, ('32.99', '35.31', '10.44%')), (3, ('30.83', '14.02%')),
                          (4, ('30.32', '12.53%'))):
    assert all(n in lines[tsukuba + offset] for n in numbers), lines[tsukuba + offset]
  assert '26.31' in text and '4.51%' in text  # Cones (folder 'Cones').
  # The paper's means are over its four scenes: not set beside this two-scene mean.
  mean = next(i for i, l in enumerate(lines) if l.startswith('mean'))
  assert '5.93%' not in text and 'paper:' not in ''.join(lines[mean:mean + 3])
  assert "the paper's means (over Tsukuba, Venus, Cones, Teddy) are left out" in text
  # The paper has no diplopia Middlebury numbers: only our rows.
  diplopia = _oracle_result(EvalConfig('middlebury', 'diplopia', root))
  assert 'paper:' not in report.format_report(diplopia)  # Row labels 'paper: <method>'.


def test_kitti_tables_partial_rule_and_paper_rows(tmp_path):
  root = runner_test.make_kitti2015(tmp_path / 'kitti')
  config = EvalConfig('kitti2015', 'anaglyph', root, allow_partial=True)
  result = _oracle_result(config)
  text = report.format_report(result)
  assert 'partial: 2 of 200 images' in text
  for number in ('26.30', '28.76', '5.96%', '13.66%', '14.40%', '19.5009', '20.0914'):
    assert number in text, number
  ours = next(l for l in text.splitlines() if l.startswith('this run'))
  assert ours.split()[3:6] == ['100.00', '100.00', '0.00%']
  assert 'colour restoration off' in text  # The test predictor restores nothing.
  restored = dataclasses.replace(result, restore_colour=True)
  assert 'colour restoration on' in report.format_report(restored)
  assert 'with ground truth' not in text  # Both frames have it.
  one_without = dataclasses.replace(result, counts=dict(result.counts, d1_all=1))
  assert 'D1 and EPE over the 1 with ground truth' in report.format_report(one_without)
  refused = dataclasses.replace(result, config=dataclasses.replace(config, allow_partial=False))
  with pytest.raises(ValueError, match='allow_partial'):
    report.format_report(refused)
  diplopia = _oracle_result(dataclasses.replace(config, mixture='diplopia'))
  text = report.markdown_report(diplopia)
  assert '| paper: oracle (clean pair) |' in text and '5.28%' in text and '6.67%' in text
  assert '17.03' in text and '13.66%' not in text
  # What wrote it comes first: the command, the machine and the weights.
  source = report.provenance(['/usr/bin/mixstereo-eval', '--protocol=kitti2015',
                              '--data_dir=my data'], 'ckpt-8.index sha256:0123')
  assert source.startswith("Written by `mixstereo-eval --protocol=kitti2015 "
                           "'--data_dir=my data'` (mixstereo_tf ")
  assert f'({report.code_version()}) on ' in source
  assert source.endswith('CPU cores; weights ckpt-8.index sha256:0123.')
  assert report.markdown_report(diplopia, source).startswith(source + '\n\n**')


def test_eigen_and_sample_tables(tmp_path):
  list_path = runner_test._write_eigen(str(tmp_path))  # pylint: disable=protected-access
  config = EvalConfig('eigen', 'monocular', str(tmp_path), split_list=list_path)
  result = runner.evaluate(config, runner_test.unmixer(lambda m: {
      'left': m, 'right': m, 'disparity_left': m[..., 0] * 0.0 + 1.0}, 'monocular'))
  text = report.format_report(result)
  lines = text.splitlines()
  assert 'abs_rel' in text and 'a3' in text and '1 of 1 images' in text
  # One table per cap, each with the paper's rows of that cap.
  cap50 = next(i for i, l in enumerate(lines) if l.startswith('Eigen split depth, cap 50 m'))
  cap80 = next(i for i, l in enumerate(lines) if l.startswith('Eigen split depth, cap 80 m'))
  assert cap50 < cap80
  assert '0.126' in '\n'.join(lines[cap50:cap80]) and '4.471' in '\n'.join(lines[cap50:cap80])
  assert 'paper: Zhou et al.' in '\n'.join(lines[cap80:]) and '6.709' in '\n'.join(lines[cap80:])
  assert 'paper: Zhou et al.' not in '\n'.join(lines[cap50:cap80])
  # The calibration's focal length, 100 px: 1 px is 54 m for GT 10 m, clamped to the cap.
  assert lines[cap50 + 3].split()[3] == '4.000'  # |50 - 10| / 10.
  assert lines[cap80 + 3].split()[3] == '4.400'  # |54 - 10| / 10.
  sample_result = _oracle_result(EvalConfig('sample', 'anaglyph', max_disparity=8,
                                            heldout_scenes=1))
  lines = report.format_report(sample_result).splitlines()
  assert lines[3].startswith('synthetic_heldout_00000')
  assert lines[5].startswith('mean') and 'this run' in lines[5] and '0.00%' in lines[5]
  assert lines[6].startswith('mean') and 'mixture as each view' in lines[6]


def test_write_csv_one_row_per_image(tmp_path):
  root = runner_test.make_kitti2015(tmp_path / 'kitti', frames=3)
  result = _oracle_result(EvalConfig('kitti2015', 'anaglyph', root, allow_partial=True))
  path = str(tmp_path / 'rows.csv')
  report.write_csv(path, result.rows)
  with open(path, newline='', encoding='utf-8') as f:
    rows = list(csv.DictReader(f))
  assert [r['name'] for r in rows] == ['000000_10', '000001_10', '000002_10']
  assert float(rows[0]['d1_all']) == 0.0 and float(rows[2]['psnr_left']) == 100.0
  assert rows[0]['width'] == '64'


@pytest.fixture(scope='module')
def run_dir(tmp_path_factory):
  """A tiny untrained run in the layout training writes (config.json + checkpoint)."""
  path = tmp_path_factory.mktemp('run')
  tf.keras.utils.set_random_seed(3)
  model = models.build_model(TINY)
  prefix = tf.train.Checkpoint(model=model).write(str(path / 'ckpt-1'))
  with open(path / 'config.json', 'w', encoding='utf-8') as f:
    json.dump({'model': TINY.to_dict(),
               'pipeline': {'mixture': 'anaglyph', 'crop_height': 32, 'crop_width': 64}}, f)
  return prefix


def _cli(*args):
  env = dict(os.environ, TF_CPP_MIN_LOG_LEVEL='2')
  return subprocess.run([sys.executable, '-m', 'mixstereo_tf.evaluate', *args],
                        capture_output=True, text=True, env=env, cwd=REPO, timeout=300,
                        check=False)


def test_cli_kitti_partial_rule_csv_and_markdown(run_dir, tmp_path):
  root = runner_test.make_kitti2015(tmp_path / 'kitti')
  refused = _cli('--protocol=kitti2015', f'--data_dir={root}', f'--checkpoint={run_dir}')
  assert refused.returncode != 0
  assert '2 of 200' in refused.stderr and '--allow_partial' in refused.stderr
  assert 'EvalConfig' not in refused.stderr  # Config fields are named as flags.
  csv_path, md_path = tmp_path / 'rows.csv', tmp_path / 'table.md'
  done = _cli('--protocol=kitti2015', f'--data_dir={root}', f'--checkpoint={run_dir}',
              '--allow_partial', f'--output_csv={csv_path}', f'--output_markdown={md_path}')
  assert done.returncode == 0, done.stderr[-3000:]
  assert 'partial: 2 of 200 images' in done.stdout and 'KITTI 2015, anaglyph' in done.stdout
  assert '26.30' in done.stdout and 'paper: Williem et al.' in done.stdout
  with open(csv_path, newline='', encoding='utf-8') as f:
    rows = list(csv.DictReader(f))
  assert len(rows) == 2 and all(0.0 <= float(r['d1_all']) <= 1.0 for r in rows)
  assert float(rows[0]['psnr_left']) < 40.0  # Untrained: far from the true view.
  assert '| Method |' in md_path.read_text() and 'partial: 2 of 200' in md_path.read_text()


def test_cli_middlebury_and_flag_errors(run_dir, tmp_path):
  root = runner_test.make_middlebury(tmp_path / 'mb')
  done = _cli('--protocol=middlebury', f'--data_dir={root}', f'--checkpoint={run_dir}',
              '--max_images=1')
  assert done.returncode == 0, done.stderr[-3000:]
  assert done.stdout.startswith('Middlebury, anaglyph') and '1 of 2 images' in done.stdout
  assert 'Cones' in done.stdout and '26.31' in done.stdout and '10.44%' not in done.stdout
  mismatch = _cli('--protocol=middlebury', f'--data_dir={root}', f'--checkpoint={run_dir}',
                  '--mixture=diplopia')
  assert mismatch.returncode != 0 and "trained on 'anaglyph'" in mismatch.stderr
  bad_scale = _cli('--protocol=middlebury', f'--data_dir={root}', f'--checkpoint={run_dir}',
                   '--middlebury_scale=Cones')
  assert bad_scale.returncode != 0 and '--middlebury_scale' in bad_scale.stderr
  assert "'Cones'" in bad_scale.stderr
  # Report files in a folder not made yet: made; a folder given as the file: refused first.
  made = _cli('--protocol=middlebury', f'--data_dir={root}', f'--checkpoint={run_dir}',
              '--max_images=1', f'--output_csv={tmp_path}/new/mb.csv')
  assert made.returncode == 0 and os.path.isfile(tmp_path / 'new' / 'mb.csv'), made.stderr
  folder = _cli('--protocol=middlebury', f'--data_dir={root}', f'--checkpoint={run_dir}',
                f'--output_markdown={tmp_path}')
  assert folder.returncode != 0 and '--output_markdown=' in folder.stderr
  assert 'is a folder' in folder.stderr and '[1/' not in folder.stderr  # Nothing evaluated.


def _sample_rows_in_process(run_dir, restore_colour):
  """The sample protocol's rows for the run, evaluated in this process (the reference):
  the CLI feeds a model the images as they are (disparity_range.NETWORK)."""
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      checkpoint=run_dir, restore_colour=restore_colour,
      disparity_range=disparity_range.NETWORK))
  config = EvalConfig('sample', unmixer.mixture, heldout_scenes=1,
                      max_disparity=int(unmixer.max_disparity))
  return runner.evaluate(config, unmixer).rows


def _assert_csv_matches(path, expected):
  with open(path, newline='', encoding='utf-8') as f:
    rows = list(csv.DictReader(f))
  assert [r['name'] for r in rows] == [r['name'] for r in expected]
  for got, want in zip(rows, expected):
    for key in ('psnr_left', 'psnr_right', 'mixture_psnr_left'):
      assert float(got[key]) == pytest.approx(want[key], abs=0.05), key
    for key in ('bad1', 'bad3', 'epe'):
      assert float(got[key]) == pytest.approx(want[key], abs=1e-2), key


def test_cli_sample_protocol_on_a_checkpoint(run_dir, tmp_path):
  csv_path = tmp_path / 'rows.csv'
  done = _cli('--protocol=sample', f'--checkpoint={run_dir}', '--heldout_scenes=1',
              f'--output_csv={csv_path}')
  assert done.returncode == 0, done.stderr[-3000:]
  lines = done.stdout.splitlines()
  assert lines[0].startswith('Sample held-out set, anaglyph') and '2 of 2 images' in lines[0]
  # The ground truth is rendered below the model's range (8): Motorcycle shrunk 9 times.
  factor = sample.motorcycle_factor(TINY.max_disparity)
  assert factor == 9
  assert lines[3].startswith('synthetic_heldout_00000')
  assert lines[4].startswith(f'motorcycle_div{factor}')
  # Colour restoration is on by default for anaglyphs: the rows match that evaluation.
  _assert_csv_matches(csv_path, _sample_rows_in_process(run_dir, restore_colour=None))


def test_cli_sample_protocol_on_a_saved_model(run_dir, tmp_path):
  model, info = runs.load_run(run_dir)
  export_dir = serving.export_saved_model(graphs.serving_function(model), model.variables,
                                          info, str(tmp_path / 'export'))
  csv_path = tmp_path / 'rows.csv'
  done = _cli('--protocol=sample', f'--saved_model={export_dir}', '--heldout_scenes=1',
              '--norestore_colour', f'--output_csv={csv_path}')
  assert done.returncode == 0, done.stderr[-3000:]
  assert done.stdout.startswith('Sample held-out set, anaglyph') and 'mean' in done.stdout
  expected = _sample_rows_in_process(run_dir, restore_colour=False)
  _assert_csv_matches(csv_path, expected)
  # Without restoration the red channel is the network's, not the mixture's: a different
  # left view than the restored one (so the flag reached the predictor).
  restored = _sample_rows_in_process(run_dir, restore_colour=None)
  assert abs(restored[0]['psnr_left'] - expected[0]['psnr_left']) > 0.1


def test_code_version_names_the_commit_of_a_checkout(tmp_path):
  text = report.code_version()
  assert text.startswith('mixstereo_tf 0.1.0')
  checkout = os.path.dirname(os.path.dirname(report.__file__))
  if os.path.isdir(os.path.join(os.path.dirname(checkout), '.git')):  # CI: a fresh clone.
    head = subprocess.run(['git', '-C', checkout, 'rev-parse', '--short=8', 'HEAD'],
                          capture_output=True, text=True, check=True).stdout.strip()
    assert f'commit {head}' in text
