"""Velodyne ground truth on hand-built calibration files with hand-computed pixels."""

import numpy as np
import pytest

from mixstereo_tf.evaluation import metrics
from mixstereo_tf.data import velodyne

# Velodyne (x forward, y left, z up) -> camera (x right, y down, z forward).
_VELO_TO_CAM_R = '0 -1 0 0 0 -1 1 0 0'
_FOCAL, _CX, _CY = 100.0, 32.0, 16.0
_HEIGHT, _WIDTH = 32, 64


def _write_raw_calib(directory, p2_tx=0.0):
  (directory / 'calib_velo_to_cam.txt').write_text(
      'calib_time: 15-Mar-2012 11:37:16\n'
      f'R: {_VELO_TO_CAM_R}\n'
      'T: 0 0 0\n'
      'delta_f: 0 0\n')
  p2 = f'{_FOCAL} 0 {_CX} {p2_tx} 0 {_FOCAL} {_CY} 0 0 0 1 0'
  (directory / 'calib_cam_to_cam.txt').write_text(
      'calib_time: 09-Jan-2012 13:57:47\n'
      'corner_dist: 9.950000e-02\n'
      'R_rect_00: 1 0 0 0 1 0 0 0 1\n'
      f'P_rect_00: {_FOCAL} 0 {_CX} 0 0 {_FOCAL} {_CY} 0 0 0 1 0\n'
      f'P_rect_02: {p2}\n\n')


def _write_scan(path, points):
  np.asarray(points, np.float32).tofile(path)
  return str(path)


def test_read_calib_file_parses_numbers_and_strings(tmp_path):
  _write_raw_calib(tmp_path)
  calib = velodyne.read_calib_file(str(tmp_path / 'calib_cam_to_cam.txt'))
  assert calib['calib_time'] == '09-Jan-2012 13:57:47'
  np.testing.assert_array_equal(calib['corner_dist'], [0.0995])
  assert calib['P_rect_02'].shape == (12,)


@pytest.mark.parametrize('text,line', [('R: 1 0 0\nno colon here\n', 2),
                                       ('T: 1 2 x\n', 1), (': 1 2\n', 1)])
def test_read_calib_file_rejects_bad_lines(tmp_path, text, line):
  path = tmp_path / 'calib.txt'
  path.write_text(text)
  with pytest.raises(ValueError, match=f'calib.txt:{line}:'):
    velodyne.read_calib_file(str(path))


def test_read_velodyne_round_trip_and_bad_size(tmp_path):
  points = np.arange(8, dtype=np.float32).reshape(2, 4)
  np.testing.assert_array_equal(
      velodyne.read_velodyne(_write_scan(tmp_path / 'a.bin', points)), points)
  bad = _write_scan(tmp_path / 'bad.bin', np.zeros(5))
  with pytest.raises(ValueError, match='bad.bin'):
    velodyne.read_velodyne(bad)


def test_projection_from_raw_calibration(tmp_path):
  _write_raw_calib(tmp_path, p2_tx=-5.0)
  projection = velodyne.velo_to_camera_projection(
      velodyne.read_calib_file(str(tmp_path / 'calib_cam_to_cam.txt')),
      velodyne.read_calib_file(str(tmp_path / 'calib_velo_to_cam.txt')))
  # Velodyne (10, -1, 0.5) = camera (1, -0.5, 10): u·z = 100·1 + 32·10 - 5 = 415.
  np.testing.assert_allclose(projection @ [10.0, -1.0, 0.5, 1.0], [415.0, 110.0, 10.0])
  with pytest.raises(ValueError, match='P_rect_03'):
    velodyne.velo_to_camera_projection(
        velodyne.read_calib_file(str(tmp_path / 'calib_cam_to_cam.txt')),
        velodyne.read_calib_file(str(tmp_path / 'calib_velo_to_cam.txt')), camera=3)


def test_eigen_ground_truth_known_pixels(tmp_path):
  _write_raw_calib(tmp_path)
  points = [
      [10.0, -1.0, 0.5, 0.3],   # u = 100·1/10 + 32 = 42, v = 100·(-0.5)/10 + 16 = 11.
      [20.0, 2.0, 0.0, 0.1],    # u = 100·(-2)/20 + 32 = 22, v = 16, depth 20.
      [10.0, 1.0, 0.0, 0.2],    # Same pixel as the previous one, nearer: kept.
      [8.0, 1.6, 0.0, 0.1],     # u = 100·(-1.6)/8 + 32 = 12, v = 16, depth 8.
      [-10.0, -1.0, 0.5, 0.9],  # Behind: would land on (u, v) = (22, 21) with z = -10.
      [1.0, -5.0, 0.0, 0.5],    # In front but u = 532: outside the image.
  ]
  depth = velodyne.eigen_ground_truth(str(tmp_path), _write_scan(tmp_path / 's.bin', points),
                                      _HEIGHT, _WIDTH)
  assert depth.shape == (_HEIGHT, _WIDTH) and depth.dtype == np.float32
  # 1-based calibration: pixel index = round(coordinate) - 1.
  expected = np.zeros((_HEIGHT, _WIDTH), np.float32)
  expected[10, 41] = 10.0
  expected[15, 21] = 10.0
  expected[15, 11] = 8.0
  np.testing.assert_array_equal(depth, expected)


def test_eigen_ground_truth_names_the_calibration_folder(tmp_path):
  _write_raw_calib(tmp_path)
  (tmp_path / 'calib_velo_to_cam.txt').write_text('R: 1 0 0 0 1 0 0 0 1\n')
  scan = _write_scan(tmp_path / 's.bin', np.zeros((1, 4)))
  with pytest.raises(ValueError, match=f"{tmp_path}: .*'T'"):
    velodyne.eigen_ground_truth(str(tmp_path), scan, _HEIGHT, _WIDTH)


def test_collisions_keep_the_nearest_point():
  projection = np.array([[_FOCAL, 0, _CX, 0], [0, _FOCAL, _CY, 0], [0, 0, 1, 0]])
  # Camera-frame points given through an identity "velodyne" frame: the x >= 0 rule then
  # tests camera x, so keep x >= 0. All three land on u = 32 + 100·x/z ≈ 42, v = 16.
  points = np.array([[1.0, 0.0, 10.0], [2.0, 0.0, 20.0], [0.5, 0.0, 5.0]])
  for order in ([0, 1, 2], [2, 1, 0], [1, 2, 0]):
    depth = velodyne.project_velodyne_to_depth(points[order], projection, _HEIGHT, _WIDTH)
    assert depth[15, 41] == 5.0
    assert np.count_nonzero(depth) == 1


def test_bad_shapes_raise():
  with pytest.raises(ValueError, match='points'):
    velodyne.project_velodyne_to_depth(np.zeros((3, 2)), np.zeros((3, 4)), 4, 4)
  with pytest.raises(ValueError, match='projection'):
    velodyne.project_velodyne_to_depth(np.zeros((3, 4)), np.zeros((4, 4)), 4, 4)


def test_focal_length_from_the_calibration_gives_depth_exactly(tmp_path):
  # The 2011_09_30 drives: 1226 x 370 images, a focal length no width table had.
  (tmp_path / 'calib_cam_to_cam.txt').write_text(
      'calib_time: 09-Jan-2012 13:57:47\n'
      'S_rect_02: 1.226000e+03 3.700000e+02\n'
      'P_rect_02: 7.070912e+02 0 6.018873e+02 4.688783e+01 0 7.070912e+02 1.831104e+02 '
      '1.178601e-01 0 0 1 6.203223e-03\n')
  focal = velodyne.rectified_focal_length(str(tmp_path), 370, 1226)
  assert focal == 707.0912
  disparity = np.full((370, 1226), 37.5, np.float32)
  disparity[0, :3] = [3.0, 0.25, 96.0]
  depth = metrics.prediction_to_kitti_depth(disparity, 370, 1226, focal)
  np.testing.assert_array_equal(depth, 707.0912 * 0.54 / disparity.astype(np.float64))
  assert depth[0, 0] == 707.0912 * 0.54 / 3.0


def test_focal_length_errors_name_the_file(tmp_path):
  path = tmp_path / 'calib_cam_to_cam.txt'
  path.write_text(f'S_rect_02: 1242 375\nP_rect_02: {_FOCAL} 0 {_CX} 0 0 {_FOCAL} {_CY} 0 '
                  '0 0 1 0\n')
  assert velodyne.rectified_focal_length(str(tmp_path), 375, 1242) == _FOCAL
  with pytest.raises(ValueError, match=r'calib_cam_to_cam.txt: S_rect_02 is 1242x375 but '
                                       r'the image is 1226x370'):
    velodyne.rectified_focal_length(str(tmp_path), 370, 1226)
  with pytest.raises(ValueError, match=r"calib_cam_to_cam.txt: .*'P_rect_03'"):
    velodyne.rectified_focal_length(str(tmp_path), 375, 1242, camera=3)
