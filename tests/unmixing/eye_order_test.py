"""Tests of unmixing.eye_order: swapped eyes detected (also window-aligned), and unmixed
mirrored into the right views and the left view's disparity, on a rendered pair."""

import io

import cv2
import numpy as np
import PIL.Image
import pytest

from mixstereo_tf.core import hints
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.unmixing import eye_order
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.unmixing import steps

# (top, height, left, width, disparity px, colour) of the boxes in front of a plane at 4 px.
BOXES = ((10, 30, 40, 50, 12, (0.3, 0.6, 1.0)), (50, 40, 120, 40, 18, (1.0, 0.4, 0.3)),
         (20, 30, 140, 30, 9, (0.4, 1.0, 0.5)))


def _pair(height=96, width=192):
  """(left, right uint8 [H, W, 3], left disparity float32 [H, W]): textured fronto-parallel
  boxes, each its own colour, z-buffered in both views (the nearest layer wins), so each view
  has the occlusions of a real pair."""
  rng = np.random.default_rng(0)
  margin = 48
  rows, columns = np.mgrid[:height, -margin:width + margin]

  def texture(colour):
    detail = cv2.GaussianBlur(rng.uniform(0, 1, rows.shape).astype(np.float32), (0, 0), 1.0)
    detail = (detail - detail.min()) / (detail.max() - detail.min())
    return (0.35 + 0.65 * detail)[..., None] * np.asarray(colour, np.float32)

  layers = [(4, np.ones(rows.shape, bool), texture((0.9, 0.8, 0.6)))]
  for top, tall, left, wide, disparity, colour in BOXES:
    inside = (rows >= top) & (rows < top + tall) & (columns >= left) & (columns < left + wide)
    layers.append((disparity, inside, texture(colour)))

  def render(in_right_view):
    view = np.zeros((height, width, 3), np.float32)
    depth = np.zeros((height, width), np.float32)
    for disparity, inside, colours in layers:
      source = np.arange(width) + margin + (disparity if in_right_view else 0)  # x_L.
      cover = inside[:, source] & (disparity > depth)
      view[cover], depth[cover] = colours[:, source][cover], disparity
    return image_range.unit_to_u8(view), depth

  left, disparity = render(False)
  return left, render(True)[0], disparity


def _mix(name, left, right):
  mixed = mixtures.mix(name, image_range.u8_to_signed(left), image_range.u8_to_signed(right))
  return image_range.signed_to_u8(mixed.numpy())


def _psnr(a, b):
  return 10 * np.log10(255.0 ** 2 / np.mean((a.astype(float) - b.astype(float)) ** 2))


@pytest.mark.parametrize('name', ['anaglyph', 'gray'])
def test_detect_swapped_eyes_also_when_window_aligned(name):
  left, right, _ = _pair()
  shift = 10  # Window-aligned: disparities d - 10, from -6 to +8 px.
  cases = {'given': (left, right), 'window-aligned': (left[:, shift:], right[:, :-shift])}
  for case, (first, second) in cases.items():
    given = eye_order.detect(_mix(name, first, second), name)
    swapped = eye_order.detect(_mix(name, second, first), name)
    assert not given.swapped and given.score > 2.5, (case, given)
    assert swapped.swapped and swapped.score < -2.5, (case, swapped)


def test_swap_eyes_gives_the_views_in_order_and_the_left_disparity():
  left, right, disparity = _pair()
  image = _mix('anaglyph', right, left)  # Cyan-red: the left eye in G and B.
  outputs = {}
  for swap in (False, True, 'auto'):
    unmixer = predictors.build_unmixer(predictors.PredictorConfig(
        'classical', mixture='anaglyph', swap_eyes=swap))
    outputs[swap] = unmixer(image)
  as_given, swapped = outputs[False], outputs[True]
  # As given, the views come out exchanged, the disparities negative (the right view's).
  assert _psnr(as_given['left'], right) > _psnr(as_given['left'], left) + 10
  assert np.median(as_given['disparity_left']) == pytest.approx(-4, abs=0.5)
  assert as_given['info']['eye_order'] == 'as_given'
  # Swapped: the views in order (exchanged they score ~18 dB; the colour-line pass costs
  # these flat-coloured boxes 2-4 dB of the 33-35 dB an exact match restores without
  # it), the left view's disparity, positive for near.
  assert _psnr(swapped['left'], left) > 28 and _psnr(swapped['right'], right) > 28
  assert np.mean(np.abs(swapped['disparity_left'] - disparity) > 1) < 0.05
  assert swapped['info']['eye_order'] == 'swapped'
  assert swapped['consistent_left'].mean() > 0.8
  detected = outputs['auto']
  assert detected['info']['eye_order'] == 'swapped' and detected['info']['eye_order_score'] < -2
  np.testing.assert_array_equal(detected['disparity_left'], swapped['disparity_left'])


def test_unmirror_maps_the_mirrored_pair_back_exactly():
  left, right, disparity = _pair()
  d_right = np.full_like(disparity, 4.0)  # Not consistent with the left: any map will do.
  flip = lambda x: x[:, ::-1]
  mirrored = {'left': flip(right), 'right': flip(left), 'disparity_left': flip(d_right),
              'disparity_right': flip(disparity), 'info': {'x': 1}}
  back = eye_order.unmirror(mirrored)
  for key, want in (('left', left), ('right', right), ('disparity_left', disparity),
                    ('disparity_right', d_right)):
    np.testing.assert_array_equal(back[key], want)
  assert back['info'] == {'x': 1} and 'consistent_left' not in back


def test_right_disparity_forward_warped_from_the_left():
  # Left row: background at 1 px, an object at 3 px in columns 4..6. The object lands on
  # right columns 1..3, where left background columns 2 and 3 land too (the nearer wins);
  # no left pixel lands on right columns 4, 5, 8, 9 (NaN).
  left = np.array([[1, 1, 1, 1, 3, 3, 3, 1, 1, np.nan]], np.float32)
  want = np.array([[1, 3, 3, 3, np.nan, np.nan, 1, 1, np.nan, np.nan]], np.float32)
  np.testing.assert_array_equal(eye_order.right_from_left(left), want)
  hint = eye_order.mirror_hint(hints.FrameHint(prior=left, mixture='gray'))
  np.testing.assert_array_equal(hint.prior, want[:, ::-1])
  assert hint.mixture == 'gray'


def test_a_mirrored_hint_leaves_out_the_other_eyes_output():
  for unread, mirrored in (('disparity_right', 'disparity_left'), ('left', 'right'), (None, None)):
    assert eye_order.mirror_hint(hints.FrameHint(unread=unread)).unread == mirrored


def test_auto_keeps_the_order_of_undetectable_encodings_and_refuses_a_single_view():
  image = np.zeros((32, 32, 3), np.uint8)
  assert eye_order.decide(image, 'diplopia', eye_order.AUTO, False) == (
      False, {'eye_order': 'as_given'})
  assert eye_order.decide(image, 'gray', False, True, shot=True) == (
      True, {'eye_order': 'swapped'})
  with pytest.raises(ValueError, match='swap_eyes.*one view'):
    steps.run(image, 'monocular', ('monocular',), (0, 8), lambda _: (0, 8), 'model',
              None, swap_eyes=True)


def test_a_bad_swap_eyes_value_is_named():
  with pytest.raises(ValueError, match=r"PredictorConfig.swap_eyes='yes'"):
    predictors.build_unmixer(predictors.PredictorConfig(
        'classical', mixture='anaglyph', swap_eyes='yes'))


def test_a_mirrored_hint_tells_the_disparities_mapped_back():
  told = []
  hint = eye_order.mirror_hint(hints.FrameHint(on_disparity=told.append))
  d_left = np.tile(np.array([[2, 2, 2, 5, 5, 2, 2, 2]], np.float32), (3, 1))
  d_right = eye_order.right_from_left(d_left)
  flip = lambda x: x[:, ::-1]
  hint.on_disparity({'disparity_left': flip(d_right), 'disparity_right': flip(d_left),
                     'consistent_left': np.ones_like(d_left, bool)})
  (back,) = told
  np.testing.assert_array_equal(back['disparity_left'], d_left)
  np.testing.assert_array_equal(back['disparity_right'], d_right)
  assert 'left' not in back  # No views yet.


def test_a_jpeg_is_analysed_at_its_colours_resolution(monkeypatch):
  """A 4:2:0 JPEG's luminance detail mixes both eyes; at half its width its colour steps are
  the eyes' own: the swapped Dubois anaglyph is found there (scores measured: -2.43, and
  -1.99 at full width), its original kept. The tools pass the file's chroma_halved on."""
  left, right, _ = _pair(192, 384)
  def jpeg(image):
    buffer = io.BytesIO()
    PIL.Image.fromarray(image).save(buffer, 'JPEG', quality=90)  # 4:2:0.
    return np.asarray(PIL.Image.open(buffer).convert('RGB'))
  swapped, given = jpeg(_mix('dubois', right, left)), jpeg(_mix('dubois', left, right))
  assert eye_order.detect(swapped, 'dubois', chroma_halved=True).swapped
  assert eye_order.detect(given, 'dubois', chroma_halved=True).score > 1.0
  seen = []
  detect = eye_order.detect
  monkeypatch.setattr(eye_order, 'detect', lambda *a, **k: seen.append(k) or detect(*a, **k))
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='dubois', swap_eyes='auto', disparity_range=(0, 24)))
  assert unmixer(swapped, **hints.stored(True))['info']['eye_order'] == 'swapped'
  unmixer(swapped)
  assert [k.get('chroma_halved') for k in seen] == [True, False]
