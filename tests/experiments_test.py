"""Every experiment flagfile parses into valid configs of the training binary; the Middlebury
fine-tuning one runs on a tiny layout."""

import glob
import json
import os
import subprocess
import sys

import cv2
import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf import models
from tests import data_helpers
from tests import training_helpers

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Runs in a fresh interpreter: the binaries define absl flags with the same names.
_PARSE_ALL = r'''
import dataclasses, json, sys
from absl import flags
from mixstereo_tf import train
out = {}
for path in sys.argv[1:]:
  flags.FLAGS.unparse_flags()
  flags.FLAGS(['train', '--flagfile=' + path, '--model_dir=/tmp/unused',
               '--data_dir=/tmp/unused'])
  if flags.FLAGS.dataset == 'sample':  # Generated: a --data_dir is refused.
    flags.FLAGS.data_dir = None
  data, pipe, model, loss = train.build_configs()
  out[path] = {'data': dataclasses.asdict(data), 'pipeline': dataclasses.asdict(pipe),
               'model': model.to_dict(), 'loss': dataclasses.asdict(loss),
               'num_steps': flags.FLAGS.num_steps, 'num_epochs': flags.FLAGS.num_epochs,
               'mode': flags.FLAGS.mode, 'init_checkpoint': flags.FLAGS.init_checkpoint,
               'optimizer': flags.FLAGS.optimizer, 'architecture': flags.FLAGS.architecture,
               'weighted_probability': flags.FLAGS.weighted_probability,
               'refiner_base': flags.FLAGS.refiner_base}
print(json.dumps(out))
'''


def _parse(paths):
  env = dict(os.environ, TF_CPP_MIN_LOG_LEVEL='3', CUDA_VISIBLE_DEVICES='',
             PYTHONPATH=REPO + os.pathsep + os.environ.get('PYTHONPATH', ''))
  result = subprocess.run([sys.executable, '-c', _PARSE_ALL, *paths], cwd=REPO, env=env,
                          capture_output=True, text=True, timeout=300, check=False)
  assert result.returncode == 0, result.stderr[-3000:]
  return json.loads(result.stdout.strip().splitlines()[-1])


def test_every_flagfile_builds_valid_configs():
  paths = sorted(glob.glob(os.path.join(REPO, 'experiments', '*.flags')))
  parsed = {os.path.basename(k): v for k, v in _parse(paths).items()}
  assert {'demo.flags', 'kitti_anaglyph.flags', 'kitti_diplopia.flags',
          'eigen_monocular.flags', 'kitti_anaglyph_separation_only.flags',
          'middlebury_anaglyph_finetune.flags'} <= set(parsed)
  for name, run in parsed.items():
    assert (run['num_steps'] is None) != (run['num_epochs'] is None), name
    if name == 'demo.flags' or run['architecture'] in ('refiner', 'features'):
      continue
    # Paper configuration: 96 levels, batch 1, the paper's loss weights, full widths.
    assert run['model']['max_disparity'] == 96, name
    assert run['model']['separation_widths'] == [32, 64, 128, 256, 512, 512], name
    assert run['pipeline']['batch_size'] == 1, name
    assert run['loss']['alpha_p'] == 0.2 and run['loss']['omega_s'] == 0.05, name
    # Issue 14's measured choices (experiments/results/fidelity.md).
    assert run['optimizer'] == 'rmsprop_tf1', name
    assert run['loss']['smoothness_scale'] == 'width', name
  assert parsed['kitti_anaglyph.flags']['pipeline']['crop_width'] == 512
  assert parsed['middlebury_anaglyph_finetune.flags']['pipeline']['crop_height'] == 384
  assert parsed['eigen_monocular.flags']['pipeline']['mixture'] == 'monocular'
  # The shipped models' recipes: the hybrid refiner (not the paper's network).
  for name, mixture in (('pretrained_anaglyph.flags', 'anaglyphs'),
                        ('pretrained_diplopia.flags', 'diplopia'),
                        ('pretrained_diplopia_weighted.flags', 'diplopia')):
    assert parsed[name]['architecture'] == 'refiner'
    assert parsed[name]['pipeline']['mixture'] == mixture
  # The weighted recipe is the a = 1/2 one with half of its examples mixed unequally, twice
  # the examples (as many at a = 1/2) and 1.5x the steps.
  half, weighted = (parsed[f'pretrained_diplopia{s}.flags'] for s in ('', '_weighted'))
  assert half['weighted_probability'] == 0.0 and weighted['weighted_probability'] == 0.5
  assert weighted['data']['sample_scenes'] == 2 * half['data']['sample_scenes']
  assert weighted['num_steps'] == 1.5 * half['num_steps']
  same = lambda run: {k: v for k, v in run.items()
                      if k not in ('weighted_probability', 'num_steps', 'data')}
  assert same(weighted) == same(half)
  # The refiner on the learned stage: trained on that stage's results, photograph textures.
  learned, plain = (parsed[f'pretrained_anaglyph{s}.flags'] for s in ('_learned', ''))
  assert (learned['refiner_base'], plain['refiner_base']) == ('anaglyph_matching', '')
  assert learned['data']['texture_dir'] == 'photos/warps' and learned['architecture'] == 'refiner'
  assert learned['pipeline']['mixture'] == plain['pipeline']['mixture']
  assert parsed['pretrained_features.flags']['architecture'] == 'features'
  assert parsed['eigen_monocular.flags']['num_epochs'] == 10
  assert parsed['kitti_anaglyph_separation_only.flags']['mode'] == 'separation_only'


def test_train_lists_named_by_the_flagfiles_exist_with_the_papers_sizes():
  sizes = {'kitti_train_files.txt': 29000, 'eigen_train_files.txt': 22600,
           'eigen_val_files.txt': 888, 'eigen_test_files.txt': 697,
           'kitti_stereo_2015_test_files.txt': 200}
  for name, lines in sizes.items():
    with open(os.path.join(REPO, 'data_lists', 'kitti', name)) as f:
      assert sum(1 for line in f if line.strip()) == lines, name


def _scene_2014(folder, disparity, shape=(40, 80)):
  """A Middlebury 2014-layout scene of constant disparity (textured views, PFM GT)."""
  os.makedirs(folder)
  texture = np.random.default_rng(len(folder)).integers(0, 256, (*shape, 3), np.uint8)
  cv2.imwrite(os.path.join(folder, 'im0.png'), texture)
  cv2.imwrite(os.path.join(folder, 'im1.png'), np.roll(texture, -int(disparity), axis=1))
  data_helpers.write_pfm(os.path.join(folder, 'disp0.pfm'),
                         np.full(shape, disparity, np.float32))


def test_the_middlebury_finetune_flagfile_runs_on_a_tiny_layout(tmp_path):
  """As shipped (its scene list, fit, guard), with a tiny network, crop and step count."""
  data = tmp_path / 'middlebury'
  _scene_2014(str(data / 'Adirondack-perfect'), 30)  # Deeper than 8 levels: shrunk by 5.
  _scene_2014(str(data / 'Piano-imperfect'), 5)
  _scene_2014(str(data / 'Motorcycle-perfect'), 5)  # Held out, and not in the list.
  _scene_2014(str(data / 'MyOwnScene'), 5)  # Not in the list.
  init = tf.train.Checkpoint(model=models.build_model(training_helpers.MINI)).write(
      str(tmp_path / 'init' / 'ckpt'))
  env = dict(os.environ, TF_CPP_MIN_LOG_LEVEL='2', CUDA_VISIBLE_DEVICES='',
             PYTHONPATH=REPO + os.pathsep + os.environ.get('PYTHONPATH', ''))
  result = subprocess.run(
      [sys.executable, '-m', 'mixstereo_tf.train',
       '--flagfile=experiments/middlebury_anaglyph_finetune.flags', f'--data_dir={data}',
       f'--init_checkpoint={init}', f'--model_dir={tmp_path / "run"}', '--num_steps=2',
       '--crop_height=32', '--crop_width=64', '--max_disparity=8', '--unet_widths=4,4',
       '--stereo_features=4', '--num_res_blocks=1', '--volume_features=4'],
      cwd=REPO, env=env, capture_output=True, text=True, timeout=300, check=False)
  assert result.returncode == 0, result.stderr[-3000:]
  assert 'Training on 2 pairs from middlebury for 2 steps.' in result.stderr
  assert '24 scene(s) of' in result.stderr  # The list's scenes this layout lacks.
  assert 'Initialised the model from' in result.stderr
  assert tf.train.latest_checkpoint(str(tmp_path / 'run')).endswith('ckpt-2')


def test_the_matching_features_flagfile_runs_on_a_tiny_photo_folder(tmp_path):
  """As shipped, with a tiny crop, width and step count, on two random 'photographs'; a
  folder holding an evaluation image is refused, naming it."""
  photos = tmp_path / 'photos'
  photos.mkdir()
  rng = np.random.default_rng(0)
  for name in ('a.jpg', 'b.png'):
    cv2.imwrite(str(photos / name), cv2.GaussianBlur(
        rng.integers(0, 256, (80, 120, 3), np.uint8), (0, 0), 1.5))
  env = dict(os.environ, TF_CPP_MIN_LOG_LEVEL='2', CUDA_VISIBLE_DEVICES='',
             PYTHONPATH=REPO + os.pathsep + os.environ.get('PYTHONPATH', ''))
  command = [sys.executable, '-m', 'mixstereo_tf.train',
             '--flagfile=experiments/pretrained_features.flags', f'--texture_dir={photos}',
             f'--model_dir={tmp_path / "run"}', '--num_steps=2', '--crop_height=32',
             '--crop_width=64', '--max_disparity=16', '--feature_width=4',
             '--batch_size=1']
  result = subprocess.run(command, cwd=REPO, env=env, capture_output=True, text=True,
                          timeout=300, check=False)
  assert result.returncode == 0, result.stderr[-3000:]
  assert tf.train.latest_checkpoint(str(tmp_path / 'run')).endswith('ckpt-2')
  cv2.imwrite(str(photos / 'teddy.png'), np.zeros((40, 40, 3), np.uint8))
  result = subprocess.run(command, cwd=REPO, env=env, capture_output=True, text=True,
                          timeout=300, check=False)
  assert result.returncode != 0 and 'teddy.png looks like an evaluation image' in result.stderr


def test_matching_validation_variants_parse_and_bad_ones_name_the_flag():
  from experiments import matching_validation  # pylint: disable=import-outside-toplevel
  label, model, config = matching_validation.parse_variant(
      'census 0.3=runs/x@census_weight=0.3@p2=64')
  assert (label, model, config.census_weight, config.p2, config.p1) == (
      'census 0.3', 'runs/x', 0.3, 64, 12)
  assert isinstance(config.p2, int)
  _, model, config = matching_validation.parse_variant('c=census@p1=20@census_width=7')
  assert (model, type(config).__name__, config.p1, config.census_width) == (
      'census', 'MatcherConfig', 20, 7)
  for bad in ('noequals', '=runs/x', 'a=runs/x@nofield=1', 'a=runs/x@p1='):
    with pytest.raises(ValueError, match='--variants'):
      matching_validation.parse_variant(bad)


def test_diplopia_validation_variants_parse_and_bad_ones_name_the_flag():
  from experiments import diplopia_validation  # pylint: disable=import-outside-toplevel
  label, config = diplopia_validation.parse_variant('wide=window_radius=9@p1=12@p2=120')
  assert (label, config.window_radius, config.matching.p1, config.matching.p2) == (
      'wide', 9, 12, 120)
  assert config.matching.min_disparity == 1  # The rest is the shipped config's.
  _, config = diplopia_validation.parse_variant('loose=cg_tolerance=0.001@smoothness=0.02')
  assert (config.layers.cg_tolerance, config.layers.smoothness) == (0.001, 0.02)
  assert config.layers.fidelity == diplopia_validation.diplopia.DiplopiaConfig().layers.fidelity
  _, config = diplopia_validation.parse_variant('echo=cepstrum_weight=1.5@cepstrum_step=4')
  assert (config.cepstrum.weight, config.cepstrum.step, config.cepstrum.rows) == (1.5, 4, 8)
  _, config = diplopia_validation.parse_variant('warp=right_from_mixture=False')
  assert config.layers.right_from_mixture is False
  for bad in ('nolabel', 'a=', 'a=matching=3', 'a=window_radius=x', 'a=p1', 'a=layers=1',
              'a=right_from_mixture=maybe'):
    with pytest.raises(ValueError, match='--diplopia_variants'):
      diplopia_validation.parse_variant(bad)


def test_camera_difference_finds_a_known_gain_and_what_it_costs_the_views():
  from experiments import camera_difference  # pylint: disable=import-outside-toplevel
  left = np.random.default_rng(0).integers(10, 240, (12, 40, 3)).astype(np.uint8)
  right = np.zeros_like(left)
  right[:, :-3] = left[:, 3:]  # The left x matches the right x - 3,
  right[..., 1] += 5  # and the right camera is 5 levels brighter in green.
  pair = {'left': left, 'right': right, 'disparity_left': np.full((12, 40), 3.0, np.float32),
          'valid_left': np.ones((12, 40), bool)}
  out = camera_difference.camera_difference(pair)
  assert out['pixels'] == 12 * 37  # Columns 0-2 match outside the right image.
  np.testing.assert_allclose(out['bias'], [0, -5, 0], atol=1e-4)
  np.testing.assert_allclose(out['rms'], [0, 5, 0], atol=1e-4)
  # The left view's green and blue come from the right camera: MSE 25 / 3 over channels.
  assert out['psnr_left'] == pytest.approx(10 * np.log10(255 ** 2 * 3 / 25), abs=1e-3)
  assert out['psnr_right'] == out['psnr_left_unbiased'] == np.inf  # Red is equal.
  pair['valid_left'][:] = False
  with pytest.raises(ValueError, match='no valid ground truth'):
    camera_difference.camera_difference(pair)


def test_colouriser_prototype_degrades_each_view_apart():
  from experiments import colouriser_prototype as proto  # pylint: disable=import-outside-toplevel
  flat = np.zeros((8, 12, 3), np.uint8) + np.array([200, 50, 10], np.uint8)
  np.testing.assert_array_equal(proto.demosaicked(flat), flat)  # Flat colour survives.
  pair = {'left': flat, 'right': flat.copy(), 'disparity_left': np.ones((8, 12))}
  for camera in (False, True):
    out = proto.degraded_apart(pair, 3, camera)
    assert out['disparity_left'] is pair['disparity_left']
    assert out['left'].shape == flat.shape and out['left'].dtype == np.uint8
    assert not np.array_equal(out['left'], out['right'])  # Each view its own noise.
    assert np.abs(out['left'].astype(int) - flat).mean() < 6
  np.testing.assert_array_equal(pair['left'], flat)  # The pair given is not changed.


def test_colouriser_prototype_inputs_and_copied_channels():
  from experiments import colouriser_prototype as proto  # pylint: disable=import-outside-toplevel
  rng = np.random.default_rng(1)
  left, right = (rng.integers(0, 256, (6, 20, 3)).astype(np.uint8) for _ in range(2))
  disparity = np.full((6, 20), 2.0, np.float32)
  consistent = np.zeros((6, 20), bool)
  consistent[:, 5:] = True
  x = proto.features(left, right, disparity, consistent, 'left')
  assert x.shape == (6, 20, 10)
  np.testing.assert_allclose(x[..., :3], left / 255 - 0.5, atol=1e-6)
  # The right view warped by the left disparity: the left x sees the right x - 2.
  np.testing.assert_allclose(x[:, 2:, 3:6], right[:, :-2] / 255 - 0.5, atol=1e-5)
  np.testing.assert_array_equal(x[0, 0, 6:9], [1, 0, 0])  # The colour anaglyph keeps red.
  np.testing.assert_array_equal(x[..., 9], consistent)
  right_x = proto.features(right, left, disparity, consistent, 'right')
  np.testing.assert_array_equal(right_x[0, 0, 6:9], [0, 1, 1])
  model = proto.Colouriser()
  out = model(x[None]).numpy()[0]  # Zero head: the restored view itself.
  np.testing.assert_allclose(out, left / 255, atol=1e-6)
  for weight in model.head.weights:
    weight.assign(tf.ones_like(weight))
  out = model(x[None]).numpy()[0]
  np.testing.assert_allclose(out[..., 0], left[..., 0] / 255, atol=1e-6)  # Copied: kept.
  assert np.abs(out[..., 1:] - left[..., 1:] / 255).max() > 0.01


def test_same_channel_scores_a_pair_without_ground_truth_on_its_views_alone():
  from experiments import same_channel  # pylint: disable=import-outside-toplevel
  from mixstereo_tf.evaluation import realworld  # pylint: disable=import-outside-toplevel
  rng = np.random.default_rng(2)
  left = cv2.GaussianBlur(rng.integers(0, 256, (40, 96, 3)).astype(np.uint8), (3, 3), 0)
  right = np.roll(left, -6, axis=1)  # The left x matches the right x - 6 everywhere.
  data = same_channel.views_only_scene(left, right)
  inner = data['valid_left'][:, 20:80]
  assert inner.mean() > 0.8
  np.testing.assert_allclose(data['disparity_left'][:, 20:80][inner], 6, atol=0.5)
  assert realworld.window_align(data, 0.3)['shift'] == 6  # Every disparity is 6.
  # Those estimated disparities place the window and score nothing; a true one passes.
  pair = realworld.window_align(data, 0.3)
  assert not same_channel.without_estimated_truth(data, pair)['valid_left'].any()
  truth = dict(data, views_only=False)
  assert same_channel.without_estimated_truth(truth, pair)['valid_left'].sum() > 0
  rows = [dict(group='g', encoding=name, method='classical', bad1=np.nan, bad3=np.nan,
               epe=np.nan, psnr_left=30.0, psnr_right=31.0)
          for name in same_channel.ENCODINGS]
  table = same_channel._table(rows)  # pylint: disable=protected-access
  assert '| g | anaglyph | classical | - | - | - | 30.00 / 31.00 | - |' in table
  assert '| g | gray | classical | - | - | - | 30.00 / 31.00 | - |' in table


def test_same_channel_scenes_without_ground_truth_only_when_asked(tmp_path, monkeypatch):
  from experiments import same_channel  # pylint: disable=import-outside-toplevel
  monkeypatch.setattr(same_channel.realworld, 'scenes', lambda shared_dir: iter(()))
  folder = tmp_path / same_channel.KITTI_2015_FRAME[0]
  folder.mkdir()
  image = cv2.GaussianBlur(np.random.default_rng(4).integers(0, 256, (40, 96, 3)).astype(
      np.uint8), (3, 3), 0)
  for name in same_channel.KITTI_2015_FRAME[1:]:
    cv2.imwrite(str(folder / name), image)
  names = lambda **kw: [n for n, _ in same_channel.scenes(str(tmp_path), **kw)]
  # Other experiments read the scenes as ground truth: the estimated one stays out of them.
  assert not names()
  assert names(views_only=True) == [same_channel.KITTI_2015_FRAME[0]]


def test_channel_information_local_fit_recovers_a_linear_channel_mix():
  from experiments import channel_information  # pylint: disable=import-outside-toplevel
  rng = np.random.default_rng(0)
  green, blue = (rng.uniform(0, 255, (24, 40)).astype(np.float32) for _ in range(2))
  red = 2.0 * green - 0.5 * blue + 7.0
  np.testing.assert_allclose(channel_information.local_fit(red, green, blue, 3), red,
                             atol=0.05)
  # A red independent of green and blue is not predicted: the fit stays near its mean.
  other = rng.uniform(0, 255, (24, 40)).astype(np.float32)
  assert np.corrcoef(channel_information.local_fit(other, green, blue, 3).ravel(),
                     other.ravel())[0, 1] < 0.6


def test_channel_information_pairings_and_noise():
  from experiments import channel_information  # pylint: disable=import-outside-toplevel
  rng = np.random.default_rng(1)
  left, right = (rng.uniform(0, 255, (16, 24, 3)).astype(np.float32) for _ in range(2))
  eyes = {p: f(left, right) for p, f in channel_information.PAIRINGS.items()}
  np.testing.assert_array_equal(eyes['R vs R'][1], right[..., 0])
  assert eyes['R vs G, B'][1].shape == (16, 24, 2)
  pair = {'left': left.astype(np.uint8), 'right': right.astype(np.uint8)}
  noisy = channel_information.validation.noisy(pair, 3)
  difference = noisy['left'].astype(float) - pair['left']
  assert 1.5 < difference.std() < 2.5
  np.testing.assert_array_equal(noisy['right'],
                                channel_information.validation.noisy(pair, 3)['right'])


def test_channel_information_learned_pairings_give_the_stage_those_eyes():
  from experiments import channel_information  # pylint: disable=import-outside-toplevel
  from mixstereo_tf.classical import anaglyph  # pylint: disable=import-outside-toplevel
  rng = np.random.default_rng(2)
  left, right = (rng.integers(0, 256, (8, 12, 3)).astype(np.float32) for _ in range(2))
  eyes = {}
  for pairing, mixture in channel_information.LEARNED_PAIRINGS.items():
    image, name = mixture(left, right)
    assert image.shape == (8, 12, 3) and 0.0 <= image.min() and image.max() <= 1.0
    eyes[pairing] = anaglyph.eye_images(image, name)
  np.testing.assert_allclose(eyes['R vs R'][0][..., 0], left[..., 0], atol=1e-3)
  np.testing.assert_allclose(eyes['R vs R'][1][..., 0], right[..., 0], atol=1e-3)
  np.testing.assert_allclose(eyes['G vs G'][1][..., 0], right[..., 1], atol=1e-3)
  np.testing.assert_allclose(eyes['R vs G, B'][1], right[..., 1:], atol=1e-3)
  np.testing.assert_allclose(eyes[channel_information.REFERENCE][0][..., 0],
                             left @ channel_information.LUMA, atol=1e-3)


def test_real_pairs_loso_scores_each_source_by_the_runs_that_never_saw_it(tmp_path):
  from experiments import real_pairs_loso as loso  # pylint: disable=import-outside-toplevel
  assert [loso.source_of(s) for s in ('motorcycle_div1', 'sceneflow_A-0032-0006',
                                      'kitti_object_velodyne', 'kitti2015_aanet_000151',
                                      'synthetic_heldout_00003')] == [
                                          'motorcycle', 'sceneflow', 'kitti', 'kitti',
                                          'procedural']
  assert loso.parse_runs([f'kitti={tmp_path}']) == {'kitti': str(tmp_path)}
  for bad in (f'middlebury={tmp_path}', f'kitti={tmp_path}/missing', 'kitti'):
    with pytest.raises(ValueError, match='--loso_runs'):
      loso.parse_runs([bad])
  row = lambda method, name, bad1, left: dict(
      scene='motorcycle_div1', encoding=name, method=method, bad1=bad1,
      psnr_left=left, psnr_right=30.0)
  rows = [row('classical', 'anaglyph', 0.2, 28.0), row('classical', 'gray', 0.1, 20.0),
          row('without motorcycle', 'anaglyph', 0.15, 28.5),
          row('without motorcycle', 'gray', 0.1, 20.0)]
  table = loso.table(rows)  # The anaglyph family's.
  assert ('| motorcycle_div1 | classical | 20.0% | 10.0% | 2.00x | 28.00 / 30.00 | '
          '+0.00 / +0.00 |') in table
  assert ('| motorcycle_div1 | without motorcycle | 15.0% | 10.0% | 1.50x | 28.50 / 30.00 | '
          '+0.50 / +0.00 |') in table


def test_real_pairs_loso_gives_double_images_their_ratio_to_classical():
  from experiments import real_pairs_loso as loso  # pylint: disable=import-outside-toplevel
  rows = [dict(scene='sceneflow_A-0032-0006', encoding='diplopia', method=method, bad1=bad1,
               psnr_left=left, psnr_right=20.0)
          for method, bad1, left in (('classical', 0.6, 21.0), ('without sceneflow', 0.45, 21.5))]
  table = loso.table(rows, loso.FAMILIES['diplopia'])
  assert table[0].startswith('| scenes | method | bad-1 double image | bad-1 classical |')
  assert ('| sceneflow_A-0032-0006 | without sceneflow | 45.0% | 60.0% | 0.75x | '
          '21.50 / 20.00 | +0.50 / +0.00 |') in table


def test_a_markdown_report_ends_with_one_newline_in_a_new_folder(tmp_path, capsys):
  from experiments import markdown  # pylint: disable=import-outside-toplevel
  path = tmp_path / 'results' / 'report.md'
  for lines in (['# Title', '', 'a line'], ['# Title', '', 'a line', '', '']):
    markdown.write(str(path), lines)
    assert path.read_text() == '# Title\n\na line\n'
    assert capsys.readouterr().out == '# Title\n\na line\n'


def test_weight_validation_scores_the_estimates_and_the_true_weight():
  """On the drawn echo scene (known shift) both estimates land near a = 0.3 and the true a's
  views are the reference the others are read against."""
  from experiments import weight_validation  # pylint: disable=import-outside-toplevel
  from tests.classical import double_images  # pylint: disable=import-outside-toplevel
  left, right = (np.rint(view * 255).astype(np.uint8) for view in double_images.steps_pair())
  found = weight_validation.score(left, right, 0.3)
  assert set(found) == set(weight_validation.ESTIMATES)
  assert found['true a'][0] == 0.3
  assert found['fitted peak (shipped)'][0] == pytest.approx(0.3, abs=0.03)
  assert found['true a'][1] >= found['mode (before)'][1] - 0.5


def test_panoramas_score_a_strip_under_both_plans():
  """A 20 x 480 strip (24 : 1) of the detection scenes: planned by frames it is read as the
  anaglyph it is; by the whole width its 320-px copy is 13 px high, and refused."""
  from experiments import panoramas  # pylint: disable=import-outside-toplevel
  from mixstereo_tf.core import planning_copies  # pylint: disable=import-outside-toplevel
  from tests.unmixing import detection_test  # pylint: disable=import-outside-toplevel
  left, right, truth = detection_test._pair(height=20, width=480)  # pylint: disable=protected-access
  pair = {'left': left, 'right': right, 'disparity_left': truth.astype(np.float32),
          'nonocc_left': np.ones(truth.shape, bool)}
  try:
    table = panoramas.detections([pair])
  finally:
    planning_copies.WIDEST_ASPECT = panoramas.PLANS['by frame (shipped)']
  assert '| anaglyph | 1 / 0 / 0 | 0 / 1 / 0 |' in table
  cell = panoramas.score(pair, 'auto', 'classical')
  assert cell.startswith('anaglyph, [') and cell.endswith(' s'), cell


def test_halftone_settings_smooth_at_the_true_period_or_pass_the_setting_on():
  from experiments import halftone as experiment  # pylint: disable=import-outside-toplevel
  rows = experiment.settings(4.0)
  assert rows['none'] == 'off' and rows['auto (shipped)'] == 'auto'
  image = np.zeros((20, 20, 3), np.uint8)
  image[10, 10] = 255
  smooth, setting = experiment._smoothed(image, rows['blur 0.5 x period'])  # pylint: disable=protected-access
  assert setting == 'off' and smooth[10, 10, 0] < 40 and smooth[10, 12, 0] > 0  # Sigma 2 px.
  assert experiment._smoothed(image, 'auto') == (image, 'auto')  # pylint: disable=protected-access
  assert {'ours, 3 px', 'ours, 5 px'} <= set(experiment.printers())


def test_tilt_turns_the_mixture_and_its_truth_alike():
  from experiments import tilt as experiment  # pylint: disable=import-outside-toplevel
  from tests.unmixing import detection_test  # pylint: disable=import-outside-toplevel
  left, right, truth = detection_test._pair(height=60, width=80)  # pylint: disable=protected-access
  pair = {'left': left, 'right': right, 'disparity_left': truth.astype(np.float32),
          'nonocc_left': np.ones(truth.shape, bool)}
  mixture, same = experiment.tilted(pair, 'anaglyph', 0.0, 0.0)
  np.testing.assert_array_equal(mixture[..., 0], left[..., 0])  # Level: the anaglyph itself.
  np.testing.assert_array_equal(same['disparity_left'], truth)
  _, turned = experiment.tilted(pair, 'anaglyph', 10.0, 0.0)
  assert not turned['known'].all() and turned['known'][25:35, 35:45].all()  # Corners lost.
  lowered, _ = experiment.tilted(pair, 'anaglyph', 0.0, 1.0)
  np.testing.assert_array_equal(lowered[1:, :, 0], left[:-1, :, 0])  # The left eye 1 px low.
  np.testing.assert_array_equal(lowered[..., 1:], mixture[..., 1:])
  double, _ = experiment.tilted(pair, 'diplopia', 0.0, 0.0)  # Part 4: no offset to move.
  assert np.abs(double - (left / 2 + right / 2)).max() <= 1
