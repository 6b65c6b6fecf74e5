"""Known-answer tests of the mixture operators on constant-colour images."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.core import mixtures

# Constant colours in [0, 1], then mapped to the network range [-1, 1].
_L01 = np.array([0.8, 0.4, 0.2], np.float32)
_R01 = np.array([0.1, 0.6, 1.0], np.float32)


def _image(rgb01):
  return tf.constant(np.broadcast_to(rgb01 * 2 - 1, (2, 4, 6, 3)).copy())


def _y(rgb):
  return 0.299 * rgb[0] + 0.587 * rgb[1] + 0.114 * rgb[2]


_EXPECTED01 = {
    'anaglyph': [_L01[0], _R01[1], _R01[2]],
    'diplopia': (_L01 + _R01) / 2,
    'monocular': _L01,
    'gray': [_y(_L01), _y(_R01), _y(_R01)],
    'half_color': [_y(_L01), _R01[1], _R01[2]],
    'optimized': [0.7 * _L01[1] + 0.3 * _L01[2], _R01[1], _R01[2]],
    'dubois': np.clip(np.array(mixtures.DUBOIS_LEFT) @ _L01 +
                      np.array(mixtures.DUBOIS_RIGHT) @ _R01, 0, 1),
    'green_magenta': [_R01[0], _L01[1], _R01[2]],
    'amber_blue': [_L01[0], _L01[1], _R01[2]],
    'green_magenta_gray': [_y(_R01), _y(_L01), _y(_R01)],
    'green_magenta_half': [_R01[0], _y(_L01), _R01[2]],
    'amber_blue_gray': [_y(_L01), _y(_L01), _y(_R01)],
    'amber_blue_half': [_L01[0], _L01[1], _y(_R01)],
    'red_blue': [_y(_L01), 0.0, _y(_R01)],  # The empty channel black, not mid-gray.
    'red_green': [_y(_L01), _y(_R01), 0.0],
}
# FFmpeg's Dubois matrices (vf_stereo3d.c integers / 65536): the first row of each, left | right.
_FFMPEG_DUBOIS_ROW0 = {
    'dubois_ffmpeg': ((29884, 32768, 11534), (-2818, -5767, -131)),
    'green_magenta_dubois': ((-4063, -10354, -2556), (34669, 46203, 1573)),
    'amber_blue_dubois': ((69599, -13435, 19595), (-1048, -8061, -1114)),
}
for _name, (_left_row, _right_row) in _FFMPEG_DUBOIS_ROW0.items():
  _spec = mixtures.get_mixture(_name)
  _EXPECTED01[_name] = np.clip(np.array(_spec.left_matrix) @ _L01 +
                               np.array(_spec.right_matrix) @ _R01, 0, 1)


# {view channel: mixture channel} kept exactly, per view (0 = R, 1 = G, 2 = B).
_SURVIVING = {
    'anaglyph': ({0: 0}, {1: 1, 2: 2}),
    'diplopia': ({}, {}),
    'monocular': ({0: 0, 1: 1, 2: 2}, {}),
    'gray': ({}, {}),
    'half_color': ({}, {1: 1, 2: 2}),
    'optimized': ({}, {1: 1, 2: 2}),
    'dubois': ({}, {}),
    'green_magenta': ({1: 1}, {0: 0, 2: 2}),
    'amber_blue': ({0: 0, 1: 1}, {2: 2}),
    'dubois_ffmpeg': ({}, {}),
    'green_magenta_gray': ({}, {}),
    'green_magenta_half': ({}, {0: 0, 2: 2}),
    'green_magenta_dubois': ({}, {}),
    'amber_blue_gray': ({}, {}),
    'amber_blue_half': ({0: 0, 1: 1}, {}),
    'amber_blue_dubois': ({}, {}),
    'red_blue': ({}, {}),
    'red_green': ({}, {}),
}


def test_every_operator_has_a_known_answer():
  assert set(_EXPECTED01) == set(mixtures.MIXTURE_NAMES) == set(_SURVIVING)


@pytest.mark.parametrize('name', sorted(_EXPECTED01))
def test_constant_colour_mixture(name):
  out = mixtures.mix(name, _image(_L01), _image(_R01)).numpy()
  expected = np.asarray(_EXPECTED01[name], np.float32) * 2 - 1
  assert out.shape == (2, 4, 6, 3)
  np.testing.assert_allclose(out, np.broadcast_to(expected, out.shape), atol=1e-6)


def test_dubois_clips_to_range():
  white, black = _image(np.ones(3, np.float32)), _image(np.zeros(3, np.float32))
  out = mixtures.mix('dubois', white, black).numpy()
  assert out.min() >= -1.0 and out.max() <= 1.0
  # Row 1 of the left matrix sums to -0.148: clipped to 0, i.e. -1 in the network range.
  np.testing.assert_allclose(out[..., 1], -1.0)


@pytest.mark.parametrize('name', sorted(_EXPECTED01))
def test_surviving_channels_are_copied(name):
  spec = mixtures.get_mixture(name)
  rng = np.random.default_rng(0)
  left = tf.constant(rng.uniform(-1, 1, (1, 4, 5, 3)).astype(np.float32))
  right = tf.constant(rng.uniform(-1, 1, (1, 4, 5, 3)).astype(np.float32))
  out = spec.fn(left, right).numpy()
  for view, channels in ((left, spec.left_channels), (right, spec.right_channels)):
    for view_channel, mixture_channel in channels.items():
      np.testing.assert_array_equal(out[..., mixture_channel], view.numpy()[..., view_channel])


@pytest.mark.parametrize('name', sorted(_EXPECTED01))
def test_surviving_channel_maps_are_pinned(name):
  spec = mixtures.get_mixture(name)
  assert (dict(spec.left_channels), dict(spec.right_channels)) == _SURVIVING[name]


@pytest.mark.parametrize('name', sorted(_EXPECTED01))
def test_every_copied_channel_is_declared(name):
  spec = mixtures.get_mixture(name)
  rng = np.random.default_rng(1)
  views = [rng.uniform(-1, 1, (1, 4, 5, 3)).astype(np.float32) for _ in range(2)]
  out = spec.fn(tf.constant(views[0]), tf.constant(views[1])).numpy()
  for view, declared in zip(views, (spec.left_channels, spec.right_channels)):
    copied = {(c, m) for c in range(3) for m in range(3)
              if np.array_equal(out[..., m], view[..., c])}
    assert copied == set(declared.items())


def test_unknown_name_lists_valid_ones():
  with pytest.raises(ValueError, match='anaglyph.*diplopia.*monocular'):
    mixtures.get_mixture('polarised')


def test_unbatched_images_work():
  left, right = _image(_L01)[0], _image(_R01)[0]
  assert mixtures.mix('anaglyph', left, right).shape == (4, 6, 3)


def test_ffmpeg_dubois_matrices_are_the_published_integers():
  for name, (left_row, right_row) in _FFMPEG_DUBOIS_ROW0.items():
    spec = mixtures.get_mixture(name)
    np.testing.assert_allclose(np.array(spec.left_matrix[0]) * 65536, left_row, atol=1e-9)
    np.testing.assert_allclose(np.array(spec.right_matrix[0]) * 65536, right_row, atol=1e-9)
    assert spec.clip


@pytest.mark.parametrize('name, eyes', [
    ('anaglyph', ((0,), (1, 2))), ('gray', ((0,), (1, 2))), ('dubois', ((0,), (1, 2))),
    ('dubois_ffmpeg', ((0,), (1, 2))), ('green_magenta', ((1,), (0, 2))),
    ('green_magenta_dubois', ((1,), (0, 2))), ('amber_blue', ((0, 1), (2,))),
    ('amber_blue_dubois', ((0, 1), (2,))), ('amber_blue_half', ((0, 1), (2,))),
    ('red_blue', ((0,), (2,))), ('red_green', ((0,), (1,)))])  # The empty channel: no eye's.
def test_eye_channels(name, eyes):
  assert mixtures.get_mixture(name).eye_channels == eyes


def test_anaglyph_names_exclude_the_papers_other_operators():
  assert 'diplopia' not in mixtures.ANAGLYPH_NAMES and 'monocular' not in mixtures.ANAGLYPH_NAMES
  assert len(mixtures.ANAGLYPH_NAMES) == len(mixtures.MIXTURE_NAMES) - 2


def test_mix_double_weights_the_left_eye_by_a():
  left, right = np.full((2, 3, 3), 0.5, np.float32), np.full((2, 3, 3), -1.0, np.float32)
  np.testing.assert_allclose(mixtures.mix_double(left, right, 0.3).numpy(),
                             0.3 * 0.5 + 0.7 * -1.0, atol=1e-6)
  np.testing.assert_allclose(mixtures.mix_double(left, right, 0.5).numpy(),
                             mixtures.mix('diplopia', left, right).numpy(), atol=1e-6)


@pytest.mark.parametrize('name, empty', [('red_blue', 1), ('red_green', 2)])
def test_a_two_channel_anaglyph_is_served_as_the_gray_one(name, empty):
  """Its empty channel black (not the signed range's mid-gray), filled from the right
  eye's channel it is the gray red-cyan anaglyph; 'anaglyphs' (the recipes') leaves it out."""
  mixed = np.float32(mixtures.mix(name, _image(_L01), _image(_R01)).numpy()[0, 0, 0])
  np.testing.assert_allclose((mixed + 1) / 2, _EXPECTED01[name], atol=1e-6)
  assert mixtures.served_name(name) == 'gray' and mixtures.served_name('gray') == 'gray'
  u8 = np.uint8(np.round(255 * np.float32(_EXPECTED01[name])))[None, None]
  gray = np.uint8(np.round(255 * np.float32(_EXPECTED01['gray'])))
  np.testing.assert_array_equal(mixtures.served(u8, name)[0, 0], gray)
  assert u8[0, 0, empty] == 0 and name not in mixtures.parse_names('anaglyphs')
  assert mixtures.served(u8, 'gray') is u8
