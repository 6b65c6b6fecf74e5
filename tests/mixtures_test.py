"""Known-answer tests of the mixture operators on constant-colour images."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf import mixtures

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
}


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
  keeps_both = bool(_SURVIVING[name][0]) and bool(_SURVIVING[name][1])
  assert spec.is_channel_anaglyph == keeps_both


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
