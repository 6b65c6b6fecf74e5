"""Tests of detection: anaglyphs made by FFmpeg's stereo3d filter (imageio-ffmpeg's binary,
where installed) and by our operators from a synthetic stereo pair with known disparities."""

import dataclasses
import subprocess

import cv2
import numpy as np
import pytest
import skimage.data

from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import sample
from mixstereo_tf.evaluation import ffmpeg_encoder
from mixstereo_tf.restoration import dubois_leak
from mixstereo_tf.unmixing import channel_matching
from mixstereo_tf.unmixing import detection
from mixstereo_tf.unmixing import margins

# FFmpeg stereo3d output modes (from a left-first side-by-side input) -> our encodings.
FFMPEG_MODES = {'arcg': 'gray', 'arcc': 'anaglyph', 'arch': 'half_color',
                'arcd': 'dubois_ffmpeg', 'agmg': 'green_magenta_gray',
                'agmc': 'green_magenta', 'agmh': 'green_magenta_half',
                'agmd': 'green_magenta_dubois', 'aybg': 'amber_blue_gray', 'aybc': 'amber_blue',
                'aybh': 'amber_blue_half', 'aybd': 'amber_blue_dubois', 'arbg': 'red_blue',
                'argg': 'red_green'}


def _pair(height=150, width=240):
  """A textured colour pair: luminance detail times smooth colours (channels correlated, as
  in photographs); disparities 4 px (background), 14 px (a box), 9 px (a disc)."""
  rng = np.random.default_rng(3)
  def smooth(cells, channels):
    noise = rng.uniform(0, 1, (height // cells + 1, (width + 40) // cells + 1, channels))
    return cv2.resize(noise.astype(np.float32), (width + 40, height),
                      interpolation=cv2.INTER_CUBIC).reshape(height, width + 40, channels)
  texture = np.clip((0.3 + 0.7 * smooth(3, 1)) * (0.2 + 0.8 * smooth(40, 3)), 0, 1)
  disparity = np.full((height, width), 4, int)
  disparity[30:100, 40:120] = 14
  yy, xx = np.mgrid[:height, :width]
  disparity[(yy - 100) ** 2 + (xx - 180) ** 2 < 30 ** 2] = 9
  left = texture[:, 20:20 + width]
  right = texture[yy, 20 + xx + disparity]  # Right pixel x shows the left pixel x + d.
  return image_range.unit_to_u8(left), image_range.unit_to_u8(right), disparity


def _ours(name, left, right):
  mixed = mixtures.mix(name, image_range.u8_to_signed(left), image_range.u8_to_signed(right))
  return image_range.signed_to_u8(mixed.numpy())


def _ffmpeg(tmp_path, left, right, mode):
  imageio_ffmpeg = pytest.importorskip('imageio_ffmpeg')
  sbs = tmp_path / 'sbs.png'
  out = tmp_path / f'{mode}.png'
  cv2.imwrite(str(sbs), cv2.cvtColor(np.concatenate([left, right], 1), cv2.COLOR_RGB2BGR))
  subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), '-y', '-loglevel', 'error', '-i', str(sbs),
                  '-vf', f'stereo3d=sbsl:{mode}', str(out)], check=True)
  return cv2.cvtColor(cv2.imread(str(out)), cv2.COLOR_BGR2RGB)


@pytest.mark.parametrize('name', mixtures.ANAGLYPH_NAMES)
def test_every_encoding_of_our_operators(name):
  left, right, _ = _pair()
  found = detection.detect(_ours(name, left, right))
  # The two red-cyan Dubois matrices differ by < 0.03: both are reported as dubois_ffmpeg.
  assert found.name == ('dubois_ffmpeg' if name == 'dubois' else name), found
  assert found.confidence > 0.6, found


@pytest.mark.parametrize('name, also_fits', [
    ('half_color', 'anaglyph'), ('optimized', 'anaglyph'),
    ('green_magenta_half', 'green_magenta'), ('amber_blue_half', 'amber_blue'),
    ('anaglyph', None), ('gray', None), ('dubois_ffmpeg', None)])
def test_a_smaller_set_names_the_colour_encoding_that_fits_as_well(name, also_fits):
  left, right, _ = _pair()
  found = detection.detect(_ours(name, left, right))
  assert found.name == name and found.also_fits == also_fits, found


@pytest.mark.parametrize('mode', sorted(FFMPEG_MODES))
def test_ffmpeg_stereo3d_anaglyphs(tmp_path, mode):
  left, right, _ = _pair()
  found = detection.detect(_ffmpeg(tmp_path, left, right, mode))
  assert found.name == FFMPEG_MODES[mode], found
  dubois = FFMPEG_MODES[mode].endswith('dubois') or FFMPEG_MODES[mode] == 'dubois_ffmpeg'
  # Two-channel anaglyphs (red-blue, red-green) have no leak to measure: no ghost score.
  ghost = next((v for k, v in found.scores.items() if k.startswith('ghost:')), 0.0)
  # Dubois leaks the odd eye into the other channels as its matrices say; the others not.
  assert (ghost > 0.6) if dubois else (abs(ghost) < 0.15), found.scores


@pytest.mark.parametrize('kind', ['left view', 'diplopia', 'gray photo'])
def test_images_that_are_not_anaglyphs_are_refused(kind):
  left, right, _ = _pair()
  image = {'left view': left,
           'diplopia': ((left.astype(np.float32) + right) / 2).round().astype(np.uint8),
           'gray photo': np.repeat(left.mean(-1, keepdims=True), 3, -1).astype(np.uint8)}[kind]
  found = detection.detect(image)
  assert found.name is None and found.confidence > 0.5, found
  assert 'displaced' in found.reason


def test_colour_red_cyan_of_a_saturated_scene_is_not_half_colour():
  """Half-colour needs R - 0.587 G - 0.114 B in [0, 0.299] (R = luma of the left view): a
  saturated colour anaglyph breaks that, so the colour encoding wins there."""
  left, right, _ = _pair()
  found = detection.detect(_ours('anaglyph', left, right))
  assert found.name == 'anaglyph', found


@pytest.mark.parametrize('half, colour', [('half_color', 'anaglyph'),
                                           ('green_magenta_half', 'green_magenta'),
                                           ('amber_blue_half', 'amber_blue')])
def test_a_half_colour_anaglyph_is_the_colour_anaglyph_of_a_scene_whose_odd_channel_is_luma(
    half, colour):
  """Why no detector can always tell them apart: the half-colour anaglyph of a scene is,
  pixel for pixel, the colour anaglyph of the scene whose odd channel (R for red-cyan) is
  replaced by luma in both views. Only the colours of that second scene, less saturated,
  can make one reading likelier, so a colour anaglyph of a scene without saturated colours
  is read as half-colour (`Detection.also_fits` names the colour encoding)."""
  left, right, _ = _pair()
  odd = detection.FAMILY_ODD_CHANNEL[mixtures.get_mixture(half).family]
  def odd_is_luma(view):
    view = view.astype(np.float64)
    view[..., odd] = view @ np.asarray(mixtures.LUMA)
    return np.clip(np.round(view), 0, 255).astype(np.uint8)
  made_half = _ours(half, left, right)
  made_colour = _ours(colour, odd_is_luma(left), odd_is_luma(right))
  assert np.abs(made_half.astype(int) - made_colour).max() <= 1
  found = detection.detect(made_colour)
  assert found.name == half and found.also_fits == colour, found


def test_a_blue_scene_leaks_nothing_into_its_colour_anaglyph():
  """A realistic training scene, mostly dark blue with smooth textures: its red channel,
  seen a few pixels apart, repeats itself, so without the collinearity filter the leak
  regression read 1.5x the Dubois leak in its colour anaglyph and chose Dubois."""
  record = sample.sample_records('train', max_disparity=64, num_scenes=10, height=240,
                                 width=480, realistic=True)[9]
  scene = sample.load_virtual(record)
  # Window-aligned by 16 px, as the scene was measured.
  left, right = scene['left'][:, 16:], np.roll(scene['right'], 16, axis=1)[:, 16:]
  found = {name: detection.detect(_ours(name, left, right)) for name in
           ('anaglyph', 'half_color', 'dubois_ffmpeg')}
  for name, result in found.items():
    assert result.name == name, result
  assert abs(found['anaglyph'].scores['ghost:dubois_ffmpeg']) < 0.15, found['anaglyph']
  assert found['dubois_ffmpeg'].scores['ghost:dubois_ffmpeg'] > 0.6, found['dubois_ffmpeg']


def test_small_or_malformed_images_are_errors():
  with pytest.raises(ValueError, match='RGB'):
    detection.detect(np.zeros((40, 40), np.uint8))
  with pytest.raises(ValueError, match='16x16'):
    detection.detect(np.zeros((8, 8, 3), np.uint8))


@pytest.mark.parametrize('name', ['anaglyph', 'gray', 'half_color', 'dubois_ffmpeg'])
def test_a_strip_is_read_as_a_row_of_frames(name):
  """A 48 x 1200 strip (25 : 1): its copy is 320 px a 4 : 1 frame (`planning_copies`),
  1200 x 48 here; 320 px wide in all it was 13 px high, and refused."""
  left, right, _ = _pair(height=48, width=1200)
  assert detection.detect(_ours(name, left, right)).name == name


@pytest.mark.parametrize('name, low, high', [('dubois_ffmpeg', 0.6, 1.3), ('anaglyph', -0.15, 0.15)])
def test_the_leak_is_measured_on_a_copy_up_to_ghost_width_and_half_the_image(name, low, high):
  left, right, _ = _pair(height=360, width=1440)  # 4 : 1, one frame (`planning_copies`).
  image = _ours(name, left, right)
  config = detection.DetectConfig()
  small = channel_matching.downsampled(image, config.width)
  matched = channel_matching.eye_match(small, 0,
                                       channel_matching.span(small, config.reach_fraction))
  ghost = detection.ghost_leak(image, small, 0, matched, config)
  expected = dubois_leak.expected('dubois_ffmpeg', 0)
  assert low < ghost @ expected / (expected @ expected) < high
  # The copy is 720 px wide: half the image's (< ghost_width); at 320 px the leak differs.
  half = dataclasses.replace(config, ghost_width=720, ghost_max_fraction=1.0)
  np.testing.assert_array_equal(ghost, detection.ghost_leak(image, small, 0, matched, half))
  narrow = detection.ghost_leak(image, small, 0, matched,
                                detection.DetectConfig(ghost_width=config.width))
  assert not np.allclose(ghost, narrow)


@pytest.mark.parametrize('name', ['gray', 'green_magenta_gray', 'anaglyph'])
def test_gray_anaglyphs_stay_gray_through_h264(name):
  """4:2:0 chroma leaves G - B of a gray red-cyan anaglyph off by several levels: a fixed
  tolerance on single pixels (the detection before) read it as half-colour."""
  left, right, _ = _pair()
  pytest.importorskip('imageio_ffmpeg')
  image = ffmpeg_encoder.round_trip(_ours(name, left, right), 'h264')
  assert detection.detect(image).name == name
  before = dataclasses.replace(detection.DetectConfig(), gray_blur=1, gray_relative=0.0)
  if name != 'anaglyph':
    assert detection.detect(image, before).name != name


def test_a_dubois_decision_is_as_sure_as_its_leak_is_far_from_the_threshold():
  left, right, _ = _pair()
  image = _ours('dubois_ffmpeg', left, right)
  found = detection.detect(image)
  leak = found.scores['ghost:dubois_ffmpeg']
  assert found.name == 'dubois_ffmpeg' and found.confidence > 0.9, found
  at_threshold = detection.detect(image, detection.DetectConfig(ghost_fraction=leak - 1e-3))
  assert at_threshold.name == 'dubois_ffmpeg'
  assert at_threshold.confidence == pytest.approx(found.confidence / 2, abs=0.05)


def test_a_dark_frame_is_too_dark_to_tell_and_a_dim_one_is_read():
  """A fade from black: at 6% of its brightness a colour anaglyph read as 'optimized' (and
  a video's shot kept that); such frames now name no encoding."""
  left, right, _ = _pair()
  mixture = _ours('anaglyph', left, right)
  dark = detection.detect(np.round(mixture * 0.06).astype(np.uint8))
  assert dark.name is None and 'too dark' in dark.reason
  assert detection.detect(np.round(mixture * 0.2).astype(np.uint8)).name == 'anaglyph'


def test_uniform_margins_are_left_out_of_detection():
  left, right, _ = _pair()
  image = _ours('anaglyph', left, right)
  framed = np.full((image.shape[0] + 60, image.shape[1] + 40, 3), 255, np.uint8)
  framed[30:-30, 20:-20] = image
  framed[:30] = 0  # A black bar above, a white frame elsewhere, JPEG-like noise on both.
  framed[:30] += np.random.default_rng(0).integers(0, 6, framed[:30].shape, np.uint8)
  assert margins.content_box(framed) == (30, 30 + image.shape[0], 20, 20 + image.shape[1])
  assert detection.detect(framed).name == detection.detect(image).name == 'anaglyph'
  flat = np.full((40, 50, 3), 90, np.uint8)
  assert margins.content_box(flat) == (0, 40, 0, 50)  # Nothing varies: all of it.


def test_gray_surroundings_with_text_are_left_out_of_detection():
  """A colour anaglyph of Motorcycle in a screenshot of a page (a gray sidebar, title bar
  and text around it) read as half-colour (0.71; a user's as optimized, its views 16.8 dB
  against 26.6 named); a gray anaglyph keeps its whole box."""
  left, right, _ = skimage.data.stereo_motorcycle()
  left, right = (cv2.resize(v, (370, 250), interpolation=cv2.INTER_AREA) for v in (left, right))
  image = np.dstack([left[..., 0], right[..., 1], right[..., 2]])
  page = np.full((400, 640, 3), 236, np.uint8)
  page[:, :106], page[:20] = 210, 60  # A sidebar and a title bar.
  for row in range(50, 400, 16):  # Gray text, anti-aliased: no colour.
    cv2.putText(page, 'lorem ipsum dolor sit amet 123 lorem ipsum', (116, row),
                cv2.FONT_HERSHEY_SIMPLEX, 0.4, (40, 40, 40), 1, cv2.LINE_AA)
  page[57:307, 116:486] = image
  assert margins.content_box(page) == (57, 307, 116, 486)
  assert detection.detect(page).name == 'anaglyph'
  gray = _ours('gray', *_pair()[:2])
  assert margins.content_box(gray) == (0, gray.shape[0], 0, gray.shape[1])


def _weakly_displaced(rows):
  """An amber-blue anaglyph whose views differ only in their top `rows` of 150 (elsewhere
  the right view is the left one): about rows / 150 of the pixels displaced."""
  left, right, _ = _pair()
  right = np.concatenate([right[:rows], left[rows:]])
  return _ours('amber_blue', left, right)


def test_weakly_displaced_channels_are_detected_with_a_doubt():
  """Photographs with saturated colours read as amber-blue at family scores up to 0.13
  (GreenMeadow: 0.128), accepted without a word."""
  weak = detection.detect(_weakly_displaced(18))  # 12% of the pixels displaced.
  assert weak.name == 'amber_blue' and 0.08 <= weak.scores['family:amber_blue'] < 0.15
  assert 'displaced only weakly (score 0.1' in weak.doubt
  assert detection.detect(_weakly_displaced(30)).doubt is None  # 20%: above 0.15.
  assert detection.detect(_weakly_displaced(8)).name is None  # Refused, as before.
  left, right, _ = _pair()
  assert detection.detect(_ours('amber_blue', left, right)).doubt is None
