"""Tests for mixstereo_tf.evaluation.runner on tiny benchmark folders written here."""

import os

import cv2
import numpy as np
import pytest

from mixstereo_tf.data import sources
from mixstereo_tf.data import split_lists
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import protocol
from mixstereo_tf.evaluation import results
from mixstereo_tf.evaluation import runner
from mixstereo_tf.unmixing import predictors

EvalConfig = results.EvalConfig

HEIGHT, WIDTH = 32, 64


def _views(rng, height=HEIGHT, width=WIDTH):
  return [rng.randint(0, 256, (height, width, 3)).astype(np.uint8) for _ in range(2)]


def _write_rgb(path, image):
  os.makedirs(os.path.dirname(path), exist_ok=True)
  assert cv2.imwrite(str(path), image[..., ::-1])


def make_kitti2015(root, frames=2, seed=0):
  """A KITTI 2015 training folder: image_2/3, disp_occ_0 / disp_noc_0 (uint16, d * 256)."""
  rng = np.random.RandomState(seed)
  for i in range(frames):
    name = f'{i:06d}_10.png'
    left, right = _views(rng)
    _write_rgb(os.path.join(root, 'training', 'image_2', name), left)
    _write_rgb(os.path.join(root, 'training', 'image_3', name), right)
    disparity = rng.uniform(5.0, 20.0, (HEIGHT, WIDTH))
    disparity[:, :4] = 0.0  # Unknown.
    occ = np.round(disparity * 256).astype(np.uint16)
    noc = occ.copy()
    noc[:, 4:10] = 0  # Occluded: in disp_occ only.
    for folder, image in (('disp_occ_0', occ), ('disp_noc_0', noc)):
      path = os.path.join(root, 'training', folder, name)
      os.makedirs(os.path.dirname(path), exist_ok=True)
      assert cv2.imwrite(path, image)
  return str(root)


def make_middlebury(root, seed=0):
  """Tsukuba (2001 names, GT / 16) and Cones (2003 im2 / im6, GT / 4, a non-occluded mask)
  scene folders."""
  rng = np.random.RandomState(seed)
  scenes = (('tsukuba', 'scene1.row3.col3.ppm', 'scene1.row3.col4.ppm',
             'truedisp.row3.col3.pgm', 16), ('Cones', 'im2.png', 'im6.png', 'disp2.png', 4))
  for folder, left_name, right_name, gt_name, scale in scenes:
    left, right = _views(rng)
    _write_rgb(os.path.join(root, folder, left_name), left)
    _write_rgb(os.path.join(root, folder, right_name), right)
    gt = rng.randint(2, 15, (HEIGHT, WIDTH)) * scale
    gt[0] = 0  # Unknown row.
    assert cv2.imwrite(os.path.join(root, folder, gt_name), gt.astype(np.uint8))
  nonocc = np.full((HEIGHT, WIDTH), 255, np.uint8)
  nonocc[:, :8] = 0  # Occluded: left out of bad-1 nonocc.
  assert cv2.imwrite(os.path.join(root, 'Cones', 'nonocc.png'), nonocc)
  return str(root)


def test_middlebury_scale_overrides_reach_the_loaded_ground_truth(tmp_path):
  root = make_middlebury(tmp_path / 'mb')
  default = {s.name: s for s in runner.list_samples(
      EvalConfig('middlebury', 'anaglyph', root))}
  halved = {s.name: s for s in runner.list_samples(
      EvalConfig('middlebury', 'anaglyph', root, middlebury_scales=(('Cones', 8.0),)))}
  cones = [name for name in default if 'cones' in name.lower()][0]
  tsukuba = [name for name in default if 'tsukuba' in name.lower()][0]
  # Cones' layout scale is 4: overriding it with 8 halves every known disparity.
  np.testing.assert_allclose(sources.load_sample(halved[cones])['disparity_left'],
                             sources.load_sample(default[cones])['disparity_left'] / 2)
  np.testing.assert_array_equal(sources.load_sample(halved[tsukuba])['disparity_left'],
                                sources.load_sample(default[tsukuba])['disparity_left'])
  with pytest.raises(ValueError, match="middlebury_scales apply to dataset 'middlebury' only"):
    runner.list_samples(EvalConfig('kitti2015', 'anaglyph', root,
                                   middlebury_scales=(('Cones', 8.0),)))


def unmixer(fn, mixture='anaglyph', takes_pair=False, method='model'):
  """An Unmixer around a test function."""
  return predictors.Unmixer(fn, method, mixture, 8.0, takes_pair=takes_pair)


def oracle(config, offset=0.0):
  """An Unmixer returning each pair's true views and its GT disparity + offset, in order."""
  loaded = iter([sources.load_sample(s) for s in runner.list_samples(config)])

  def predict(mixture):
    data = next(loaded)
    assert mixture.shape == data['left'].shape and mixture.dtype == np.uint8
    return {'left': data['left'], 'right': data['right'],
            'disparity_left': data['disparity_left'] + offset,
            'disparity_right': data['disparity_right']}

  return unmixer(predict, config.mixture)


def test_kitti_oracle_is_perfect_and_shifted_disparities_hit_the_d1_rule(tmp_path):
  root = make_kitti2015(tmp_path / 'kitti')
  config = EvalConfig('kitti2015', 'anaglyph', root, allow_partial=True)
  result = runner.evaluate(config, oracle(config))
  assert [r['name'] for r in result.rows] == ['000000_10', '000001_10']
  assert result.coverage == 'partial: 2 of 200 images'
  assert result.averages['d1_all'] == 0.0 and result.averages['epe'] < 1e-6
  assert result.averages['psnr_left'] == result.averages['psnr_right'] == 100.0
  # 2 px off is within 3 px: not bad; 4 px off is > 3 px and > 5 % of gt <= 20: all bad.
  assert runner.evaluate(config, oracle(config, 2.0)).averages['d1_all'] == 0.0
  shifted = runner.evaluate(config, oracle(config, 4.0))
  assert shifted.averages['d1_all'] == 1.0 and shifted.averages['d1_noc'] == 1.0
  assert shifted.averages['epe'] == pytest.approx(4.0, abs=1e-4)
  # A frame without its disp_noc file has no D1-noc (not D1-all under that name).
  os.remove(os.path.join(root, 'training', 'disp_noc_0', '000001_10.png'))
  partial = runner.evaluate(config, oracle(config, 4.0))
  assert np.isnan(partial.rows[1]['d1_noc']) and partial.counts['d1_noc'] == 1
  (title, *_), = protocol.get('kitti2015').tables(partial)[:1]
  assert 'D1-noc over the 1 with a non-occluded map' in title


def test_mixture_is_the_quantised_anaglyph_and_the_trivial_baseline(tmp_path):
  root = make_kitti2015(tmp_path / 'kitti', frames=1)
  config = EvalConfig('kitti2015', 'anaglyph', root, allow_partial=True)
  data = sources.load_sample(runner.list_samples(config)[0])
  mixture = runner.synthesise_mixture('anaglyph', data['left'], data['right'])
  expected = np.concatenate([data['left'][..., :1], data['right'][..., 1:]], axis=-1)
  np.testing.assert_array_equal(mixture, expected)  # Lossless for 8-bit views.
  row = runner.evaluate(config, oracle(config)).rows[0]
  assert row['mixture_psnr_left'] == pytest.approx(metrics.psnr(expected, data['left']))
  assert row['mixture_psnr_left'] < 40.0
  mono = EvalConfig('kitti2015', 'monocular', root, allow_partial=True)
  assert runner.evaluate(mono, oracle(mono)).rows[0]['mixture_psnr_left'] == 100.0


def test_kitti2015_partial_run_is_refused_before_any_prediction(tmp_path):
  root = make_kitti2015(tmp_path / 'kitti')
  config = EvalConfig('kitti2015', 'anaglyph', root)

  def never(mixture):
    raise AssertionError('predicted although the run is refused')

  with pytest.raises(ValueError, match=r'2 of 200.*EvalConfig.allow_partial'):
    runner.evaluate(config, unmixer(never))
  # max_images keeps the first pairs; allow_partial lets the short run through.
  one = EvalConfig('kitti2015', 'diplopia', root, allow_partial=True, max_images=1)
  assert runner.evaluate(one, oracle(one)).coverage == 'partial: 1 of 200 images'


def test_middlebury_bad1_known_answers(tmp_path):
  root = make_middlebury(tmp_path / 'mb')
  config = EvalConfig('middlebury', 'anaglyph', root)
  assert [s.name for s in runner.list_samples(config)] == ['Cones', 'tsukuba']
  result = runner.evaluate(config, oracle(config))
  assert result.coverage == '2 of 2 images'
  assert result.averages['bad1_all'] == 0.0 and result.averages['bad1_nonocc'] == 0.0
  # Tsukuba has no non-occluded mask: its nonocc bad-1 is not its all-pixel one, relabelled.
  assert np.isnan(result.rows[1]['bad1_nonocc']) and result.counts['bad1_nonocc'] == 1
  (title, _, _, _, _), = protocol.get('middlebury').tables(result)
  assert 'bad-1 nonocc over the 1 with a non-occluded mask' in title
  # The GT is integer pixels after its scale: 0.9 px off is good, 1.1 px off is bad.
  assert runner.evaluate(config, oracle(config, 0.9)).averages['bad1_all'] == 0.0
  assert runner.evaluate(config, oracle(config, 1.1)).averages['bad1_all'] == 1.0


def test_middlebury_paper_mean_only_beside_the_same_four_scenes(tmp_path):
  """Cones and Tsukuba are two of the paper's four scenes: its per-scene rows are shown,
  its mean (over Tsukuba, Venus, Cones, Teddy) is not set beside a two-scene mean."""
  config = EvalConfig('middlebury', 'anaglyph', make_middlebury(tmp_path / 'mb'))
  result = runner.evaluate(config, oracle(config))
  (title, _, rows, _, _), = protocol.get('middlebury').tables(result)
  mean_at = [row['Scene'] for row in rows].index('mean')
  assert len(rows) == mean_at + 1  # Our mean only.
  paper = set(protocol.PAPER_LABELS.values())
  assert sum(row['Method'] in paper for row in rows[:mean_at]) >= 2  # Its scene rows.
  assert "the paper's means" in title and 'left out' in title


def test_middlebury_paper_mean_beside_a_mean_over_its_four_scenes():
  row = {'psnr_left': 30.0, 'psnr_right': 30.0, 'bad1_all': 0.1, 'bad1_nonocc': 0.1,
         'mixture_psnr_left': 20.0, 'mixture_psnr_right': 20.0}
  rows = [dict(row, name=name) for name in ('tsukuba', 'venus', 'cones', 'teddy')]
  result = results.EvalResult(EvalConfig('middlebury', 'anaglyph', 'mb'), 'model', True,
                              rows, {'bad1_all': 0.1}, {'bad1_all': 4}, 4)
  (title, _, table, _, _), = protocol.get('middlebury').tables(result)
  mean_at = [r['Scene'] for r in table].index('mean')
  assert table[mean_at + 1]['bad-1'] == 5.93 and 'left out' not in title
  # One of the four without ground truth: a three-scene mean, not beside the paper's.
  rows[1] = dict(rows[1], bad1_all=float('nan'), bad1_nonocc=float('nan'))
  three = results.EvalResult(EvalConfig('middlebury', 'anaglyph', 'mb'), 'model', True,
                             rows, {'bad1_all': 0.1}, {'bad1_all': 3, 'bad1_nonocc': 3}, 4)
  (title, _, table, _, _), = protocol.get('middlebury').tables(three)
  assert [r['Scene'] for r in table][-1] == 'mean'
  assert 'bad-1 over the 3 scenes with ground truth' in title and 'left out' in title


def test_sample_protocol_oracle(tmp_path):
  config = EvalConfig('sample', 'diplopia', max_disparity=8, heldout_scenes=1)
  result = runner.evaluate(config, oracle(config))
  assert result.count == 2 and result.rows[-1]['name'].startswith('motorcycle')
  assert result.averages['bad1'] == 0.0 and result.averages['bad3'] == 0.0
  assert result.averages['epe'] == 0.0 and result.averages['psnr'] == 100.0
  assert result.averages['mixture_psnr_left'] < 60.0
  assert all(r['seconds'] >= 0.0 for r in result.rows)


def _write_eigen(root, width=1242, focal=100.0, rect_size=''):
  """KITTI raw layout, one frame 16 x `width`; P_rect_02 has the given focal length.

  `rect_size`: an optional 'W H' S_rect_02 entry.
  """
  date, drive = '2011_09_26', '2011_09_26_drive_0001_sync'
  calib = os.path.join(root, date)
  os.makedirs(calib)
  with open(os.path.join(calib, 'calib_velo_to_cam.txt'), 'w') as f:
    f.write('R: 0 -1 0 0 0 -1 1 0 0\nT: 0 0 0\n')
  with open(os.path.join(calib, 'calib_cam_to_cam.txt'), 'w') as f:
    f.write(f'R_rect_00: 1 0 0 0 1 0 0 0 1\nP_rect_02: {focal} 0 {width / 2} 0 0 {focal} 10 0 '
            '0 0 1 0\n' + (f'S_rect_02: {rect_size}\n' if rect_size else ''))
  views = _views(np.random.RandomState(3), 16, width)
  for camera, view in zip(('image_02', 'image_03'), views):
    _write_rgb(os.path.join(root, date, drive, camera, 'data', '0000000000.png'), view)
  # Ten points 10 m ahead, spread across the image centre (inside the Garg crop).
  points = np.array([[10.0, y, 0.0, 1.0] for y in np.linspace(-5, 5, 10)], np.float32)
  scans = os.path.join(root, date, drive, 'velodyne_points', 'data')
  os.makedirs(scans)
  points.tofile(os.path.join(scans, '0000000000.bin'))
  list_path = os.path.join(root, 'eigen_test.txt')
  with open(list_path, 'w') as f:
    f.write(f'{date}/{drive}/image_02/data/0000000000.jpg '
            f'{date}/{drive}/image_03/data/0000000000.jpg\n')
  return list_path


# 1226 px wide with 707.0912 px focal: the 2011_09_30 drives, which no width table covered.
@pytest.mark.parametrize('width, focal, rect_size', [(1242, 100.0, ''),
                                                     (1226, 707.0912, '1226 16')])
@pytest.mark.parametrize('depth, abs_rel, a1', [(10.0, 0.0, 1.0), (20.0, 1.0, 0.0)])
def test_eigen_depth_from_velodyne_uses_the_calibration_focal_length(
    tmp_path, width, focal, rect_size, depth, abs_rel, a1):
  list_path = _write_eigen(str(tmp_path), width, focal, rect_size)
  config = EvalConfig('eigen', 'monocular', str(tmp_path), split_list=list_path)
  disparity = focal * 0.54 / depth

  def predict(mixture):
    return {'left': mixture, 'right': mixture,
            'disparity_left': np.full(mixture.shape[:2], disparity, np.float32)}

  row = runner.evaluate(config, unmixer(predict, 'monocular')).rows[0]
  assert row['width'] == width
  for cap in (50, 80):  # All points are 10 m ahead: both caps agree.
    assert row[f'abs_rel_cap{cap}'] == pytest.approx(abs_rel, abs=1e-5)
    assert row[f'a1_cap{cap}'] == a1
  assert row['mixture_psnr_left'] == 100.0


def test_eigen_refuses_images_of_another_size_than_the_calibration(tmp_path):
  list_path = _write_eigen(str(tmp_path), 1226, 707.0912, '1242 375')
  config = EvalConfig('eigen', 'monocular', str(tmp_path), split_list=list_path)
  with pytest.raises(ValueError, match=r'calib_cam_to_cam.txt: S_rect_02 is 1242x375'):
    runner.evaluate(config, unmixer(lambda m: {
        'left': m, 'right': m, 'disparity_left': np.ones(m.shape[:2], np.float32)}))


def test_bad_configs_and_outputs_raise(tmp_path):
  never = unmixer(lambda m: None)
  with pytest.raises(ValueError, match='Unknown EvalConfig.protocol'):
    runner.evaluate(EvalConfig('kitti', 'anaglyph', 'x'), never)
  with pytest.raises(ValueError, match='valid mixtures'):
    runner.evaluate(EvalConfig('middlebury', 'nope', 'x'), never)
  with pytest.raises(ValueError, match='needs EvalConfig.data_dir'):
    runner.evaluate(EvalConfig('middlebury', 'anaglyph'), never)
  with pytest.raises(ValueError, match='Split list not found'):
    runner.list_samples(EvalConfig('eigen', 'monocular', 'x', split_list='no.txt'))
  with pytest.raises(ValueError, match='EvalConfig.max_images'):
    EvalConfig('sample', 'anaglyph', max_images=0)
  root = make_middlebury(tmp_path / 'mb')
  config = EvalConfig('middlebury', 'anaglyph', root)
  with pytest.raises(ValueError, match=r"Cones: predictor output 'disparity_left'"):
    runner.evaluate(config, unmixer(lambda m: {'left': m, 'right': m,
                                               'disparity_left': np.zeros((2, 2))}))
  nan_prediction = runner.evaluate(config, unmixer(lambda m: {
      'left': m, 'right': m, 'disparity_left': np.full(m.shape[:2], np.nan, np.float32)}))
  assert nan_prediction.averages['bad1_all'] == 1.0  # NaN counts as bad, not as missing.


def test_classical_baseline_runs_through_the_harness(tmp_path):
  root = make_middlebury(tmp_path / 'mb')
  config = EvalConfig('middlebury', 'anaglyph', root, max_images=1)
  classical = predictors.build_unmixer(predictors.PredictorConfig('classical',
                                                                mixture='anaglyph'))
  result = runner.evaluate(config, classical)
  assert result.method == 'classical' and result.restore_colour
  row = result.rows[0]
  assert 0.0 <= row['bad1_all'] <= 1.0 and row['psnr_left'] > 0.0


def test_default_eigen_list_is_the_shipped_copy():
  path = split_lists.resolve('kitti/eigen_test_files.txt')
  with open(path, encoding='utf-8') as f:
    assert len([line for line in f if line.strip()]) == 697
  assert runner.data_config(EvalConfig('eigen', 'monocular', 'x')).split_list == path


def test_oracle_method_feeds_the_clean_pair(tmp_path):
  root = make_kitti2015(tmp_path / 'kitti')
  config = EvalConfig('kitti2015', 'diplopia', root, allow_partial=True)
  truth = iter([sources.load_sample(s) for s in runner.list_samples(config)])

  def pair_predictor(left, right):
    data = next(truth)
    np.testing.assert_array_equal(left, data['left'])
    np.testing.assert_array_equal(right, data['right'])
    return {'disparity_left': data['disparity_left']}

  result = runner.evaluate(config, unmixer(pair_predictor, 'diplopia', takes_pair=True,
                                           method='oracle'))
  assert result.averages['d1_all'] == 0.0 and 'psnr_left' not in result.averages
  assert result.averages['mixture_psnr_left'] < 40.0 and result.method == 'oracle'


@pytest.mark.parametrize('missing', ['calib_velo_to_cam.txt', 'scan'])
def test_eigen_refuses_a_frame_without_ground_truth_files_before_predicting(tmp_path, missing):
  list_path = _write_eigen(str(tmp_path))
  date, drive = '2011_09_26', '2011_09_26_drive_0001_sync'
  gone = (os.path.join(tmp_path, date, missing) if missing != 'scan' else
          os.path.join(tmp_path, date, drive, 'velodyne_points', 'data', '0000000000.bin'))
  os.remove(gone)
  calls = []
  config = EvalConfig('eigen', 'monocular', str(tmp_path), split_list=list_path)
  with pytest.raises(ValueError, match=rf'eigen_test.txt:1: .* needs {gone}, not found'):
    runner.evaluate(config, unmixer(lambda m: calls.append(m)))
  assert not calls


def test_partial_run_skips_missing_pairs_of_a_list(tmp_path):
  list_path = _write_eigen(str(tmp_path))
  with open(list_path, 'a', encoding='utf-8') as f:
    f.write('2011_09_26/gone/image_02/data/1.png 2011_09_26/gone/image_03/data/1.png\n')
  config = EvalConfig('eigen', 'monocular', str(tmp_path), split_list=list_path)
  with pytest.raises(ValueError, match='eigen_test.txt:2: Image not found'):
    runner.list_samples(config)
  partial = EvalConfig('eigen', 'monocular', str(tmp_path), split_list=list_path,
                       allow_partial=True)
  assert [s.source[-2:] for s in runner.list_samples(partial)] == [':1']


def test_data_dir_with_the_generated_protocol_is_refused():
  with pytest.raises(ValueError, match=r"data_dir is given but EvalConfig.protocol='sample' "
                                       r'reads no files; .*\(eigen, .*middlebury\)'):
    runner.data_config(EvalConfig('sample', 'anaglyph', 'data/kitti'))
