"""Known-answer tests of the evaluation metrics."""

import math

import numpy as np
import pytest

from mixstereo_tf.evaluation import metrics


def test_psnr_of_known_mse():
  gt = np.zeros((4, 5, 3), np.uint8)
  pred = np.full((4, 5, 3), 10, np.uint8)  # MSE = 100 (no uint8 wrap-around).
  assert metrics.psnr(pred, gt) == pytest.approx(10 * math.log10(255 ** 2 / 100))
  assert metrics.psnr(gt, pred) == pytest.approx(28.1308036, abs=1e-6)


def test_psnr_mask_selects_pixels():
  gt = np.zeros((2, 2, 3), np.uint8)
  pred = gt.copy()
  pred[0, 0] = 255  # The only wrong pixel.
  mask = np.array([[False, True], [True, True]])
  assert metrics.psnr(pred, gt, mask=mask) == 100.0
  assert metrics.psnr(pred, gt, mask=~mask) == pytest.approx(0.0)
  # Unmasked: MSE = 255² / 4 -> 10 log10(4).
  assert metrics.psnr(pred, gt) == pytest.approx(10 * math.log10(4))
  assert math.isnan(metrics.psnr(pred, gt, mask=np.zeros((2, 2), bool)))


def test_psnr_identical_images_capped_or_infinite():
  image = np.arange(24, dtype=np.uint8).reshape(2, 4, 3)
  assert metrics.psnr(image, image) == 100.0
  assert metrics.psnr(image, image, max_db=50) == 50.0
  assert metrics.psnr(image, image, max_db=None) == math.inf


def test_psnr_shape_mismatch_raises():
  with pytest.raises(ValueError, match='Shape mismatch'):
    metrics.psnr(np.zeros((2, 2, 3)), np.zeros((2, 3, 3)))
  with pytest.raises(ValueError, match='mask shape'):
    metrics.psnr(np.zeros((2, 2, 3)), np.zeros((2, 2, 3)), mask=np.ones((3, 2), bool))


def test_d1_boundaries_are_strict():
  # Pixel by pixel: gt 100 err 5 (= 5 %, not bad); gt 100 err 5.01 (bad); gt 40 err 3
  # (not > 3, not bad); gt 40 err 3.01 (> 3 and > 2, bad); gt 10 err 3.5 (bad);
  # gt 200 err 9 (> 3 but 4.5 %, not bad).
  gt = np.array([[100.0, 100.0, 40.0, 40.0, 10.0, 200.0]])
  pred = gt + np.array([[5.0, 5.01, 3.0, -3.01, 3.5, -9.0]])
  valid = np.ones_like(gt, bool)
  assert metrics.d1_error(pred, gt, valid) == pytest.approx(3 / 6)
  for i, bad in enumerate([False, True, False, True, True, False]):
    one = np.zeros_like(valid)
    one[0, i] = True
    assert metrics.d1_error(pred, gt, one) == float(bad), i


def test_disparity_metrics_perfect_prediction_and_masks():
  gt = np.array([[[1.0], [2.0]], [[0.0], [4.0]]])  # [2, 2, 1]; 0 = unknown.
  valid = np.ones_like(gt)
  assert metrics.d1_error(gt, gt, valid) == 0.0
  assert metrics.bad_pixel_rate(gt, gt, valid, 1.0) == 0.0
  assert metrics.end_point_error(gt, gt, valid) == 0.0
  pred = gt + np.array([[[0.5], [1.0]], [[50.0], [2.0]]])
  # The GT-0 pixel is never evaluated: errors 0.5, 1.0, 2.0.
  assert metrics.bad_pixel_rate(pred, gt, valid, 1.0) == pytest.approx(1 / 3)
  assert metrics.bad_pixel_rate(pred, gt, valid, 0.5) == pytest.approx(2 / 3)
  assert metrics.end_point_error(pred, gt, valid) == pytest.approx(3.5 / 3)
  valid[0, 1] = 0
  assert metrics.end_point_error(pred, gt, valid) == pytest.approx(2.5 / 2)


def test_disparity_metrics_nan_and_errors():
  gt = np.full((2, 3), 10.0)
  none = np.zeros((2, 3), bool)
  assert math.isnan(metrics.d1_error(gt, gt, none))
  assert math.isnan(metrics.bad_pixel_rate(gt, gt, none, 1.0))
  assert math.isnan(metrics.end_point_error(gt, np.zeros((2, 3)), np.ones((2, 3))))
  # A NaN prediction is bad, not ignored.
  pred = gt.copy()
  pred[0, 0] = np.nan
  assert metrics.d1_error(pred, gt, ~none) == pytest.approx(1 / 6)
  with pytest.raises(ValueError, match='Shape mismatch'):
    metrics.d1_error(gt, gt[..., None], ~none)


def test_middlebury_bad_per_region():
  gt = np.array([[1.0, 2.0, 3.0, 0.0]])
  pred = gt + np.array([[0.5, 1.5, 1.0, 9.0]])
  nonocc = np.array([[True, False, True, True]])
  out = metrics.middlebury_bad(pred, gt, {'all': np.ones_like(nonocc), 'nonocc': nonocc})
  assert out == pytest.approx({'all': 1 / 3, 'nonocc': 0.0})
  assert metrics.middlebury_bad(pred, gt) == pytest.approx({'valid': 1 / 3})


def test_disparity_to_depth():
  depth = metrics.disparity_to_depth(np.array([[721.5377 * 0.54 / 10, 0.0, -1.0]]), 721.5377)
  np.testing.assert_allclose(depth[0, 0], 10.0)
  assert np.isinf(depth[0, 1:]).all()
  assert metrics.disparity_to_depth(np.array([2.0]), 100.0, baseline_m=1.0)[0] == 50.0


def test_resize_disparity_scales_values_by_width_ratio():
  disparity = np.full((4, 8), 3.0, np.float32)
  out = metrics.resize_disparity(disparity, 6, 16)
  assert out.shape == (6, 16)
  np.testing.assert_allclose(out, 6.0)
  depth = metrics.prediction_to_kitti_depth(np.full((2, 4), 1242 / 4 * 2.0), 3, 1242,
                                           721.5377)
  np.testing.assert_allclose(depth, 721.5377 * 0.54 / (1242 / 4 * 2.0 * 1242 / 4))


@pytest.mark.parametrize('crop,top,bottom', [('garg', 0.40810811, 0.99189189),
                                             ('eigen', 0.3324324, 0.91351351)])
def test_eigen_crop_mask_on_kitti_grid(crop, top, bottom):
  h, w = 375, 1242
  mask = metrics.eigen_crop_mask(h, w, crop)
  rows = int(bottom * h) - int(top * h)
  cols = int(0.96405229 * w) - int(0.03594771 * w)
  assert mask.sum() == rows * cols
  ys, xs = np.nonzero(mask)
  assert (ys.min(), xs.min(), xs.max()) == (int(top * h), 44, 1196)
  assert ys.max() == int(bottom * h) - 1
  if crop == 'garg':
    assert (ys.min(), ys.max(), rows * cols) == (153, 370, 218 * 1153)


def test_eigen_crop_mask_none_and_unknown():
  assert metrics.eigen_crop_mask(3, 4, None).all()
  with pytest.raises(ValueError, match='garg'):
    metrics.eigen_crop_mask(3, 4, 'center')


def test_depth_metrics_hand_computed():
  gt = np.array([[10.0, 20.0], [40.0, 0.0]])  # The 0 is not evaluated.
  pred = np.array([[12.0, 20.0], [30.0, 5.0]])
  out = metrics.depth_metrics(pred, gt, crop=None)
  # |d - g| = 2, 0, 10; (d - g)² = 4, 0, 100; ratios 1.2, 1, 4/3.
  assert out['abs_rel'] == pytest.approx((0.2 + 0 + 0.25) / 3)
  assert out['sq_rel'] == pytest.approx((0.4 + 0 + 2.5) / 3)
  assert out['rmse'] == pytest.approx(math.sqrt(104 / 3))
  assert out['rmse_log'] == pytest.approx(
      math.sqrt((math.log(1.2) ** 2 + math.log(0.75) ** 2) / 3))
  assert out['a1'] == pytest.approx(2 / 3)
  assert out['a2'] == 1.0 and out['a3'] == 1.0


def test_depth_metrics_clamps_prediction_and_gt_range():
  gt = np.array([[50.0, 79.0, 80.0, 1e-3]])  # 80 and 1e-3 are outside (strict).
  pred = np.array([[np.inf, 0.0, 3.0, 3.0]])
  out = metrics.depth_metrics(pred, gt, crop=None)
  # Clamped predictions: 80 for 50, 1e-3 for 79.
  assert out['abs_rel'] == pytest.approx((30 / 50 + (79 - 1e-3) / 79) / 2)
  assert out['a3'] == 0.5
  empty = metrics.depth_metrics(pred, np.zeros_like(gt), crop=None)
  assert all(math.isnan(v) for v in empty.values())
  assert set(empty) == set(metrics.DEPTH_METRIC_NAMES)


def test_accumulators_ignore_nan():
  mean = metrics.MeanOf()
  assert math.isnan(mean.mean)
  for value in (1.0, math.nan, 3.0):
    mean.add(value)
  assert (mean.mean, mean.count, mean.nan_count) == (2.0, 2, 1)
  acc = metrics.Accumulator(['psnr'])
  acc.add({'psnr': 30.0, 'd1_all': math.nan})
  acc.add({'psnr': 20.0, 'd1_all': 0.1})
  assert acc.means() == {'psnr': 25.0, 'd1_all': 0.1}
  assert acc.counts() == {'psnr': 2, 'd1_all': 1}


def test_depth_caps_differ_exactly_where_points_lie_beyond_50_m():
  rng = np.random.default_rng(7)
  height, width = 40, 60
  near = rng.uniform(2.0, 39.0, (height, width))
  pred = near * rng.uniform(0.8, 1.25, (height, width))  # Below 50 m too (the cap clamps).
  # Every point nearer than 50 m: the two caps give identical metrics.
  cap50 = metrics.depth_metrics(pred, near, max_depth=50.0, crop=None)
  cap80 = metrics.depth_metrics(pred, near, max_depth=80.0, crop=None)
  assert cap50 == cap80
  # A band of points between 50 and 80 m: only the 80 m metrics see them, and the 50 m
  # metrics equal those of the frame without them.
  far = near.copy()
  far[:5] = rng.uniform(55.0, 75.0, (5, width))
  far_pred = pred.copy()
  far_pred[:5] = far[:5] * 0.4  # Off by a factor 2.5: beyond every delta threshold.
  with_far50 = metrics.depth_metrics(far_pred, far, max_depth=50.0, crop=None)
  with_far80 = metrics.depth_metrics(far_pred, far, max_depth=80.0, crop=None)
  without = metrics.depth_metrics(far_pred[5:], far[5:], max_depth=50.0, crop=None)
  for name in metrics.DEPTH_METRIC_NAMES:
    assert with_far50[name] == pytest.approx(without[name], rel=1e-12), name
    assert with_far80[name] != pytest.approx(with_far50[name], rel=1e-6), name


def test_view_difference_agreement_tells_order_where_psnr_to_each_eye_does_not():
  rng = np.random.default_rng(0)
  left, right = rng.uniform(0, 255, (2, 8, 12, 3))
  assert metrics.view_difference_agreement(left, right, left, right) == pytest.approx(1.0)
  assert metrics.view_difference_agreement(right, left, left, right) == pytest.approx(-1.0)
  # A weak separation of 0.3 L + 0.7 R: both views near the mixture, their difference a
  # tenth of the true one. Its left view is nearer to the true right view than to the
  # true left one, yet the eyes are in order.
  mixture = 0.3 * left + 0.7 * right
  weak_left, weak_right = mixture + 0.05 * (left - right), mixture - 0.05 * (left - right)
  assert metrics.psnr(weak_left, right) > metrics.psnr(weak_left, left)
  assert metrics.view_difference_agreement(weak_left, weak_right, left,
                                           right) == pytest.approx(1.0)
  assert math.isnan(metrics.view_difference_agreement(mixture, mixture, left, right))
  with pytest.raises(ValueError, match='Shape mismatch'):
    metrics.view_difference_agreement(left, right[:4], left, right)
