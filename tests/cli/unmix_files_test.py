"""Tests for unmixing files: images, folders, globs and videos (mixstereo_tf.cli.unmix_files)."""

import dataclasses
import errno
import io
import json
import os
import shutil
import subprocess
import threading
import time
import zlib

import av
import cv2
import imageio_ffmpeg
import numpy as np
from PIL import Image
import pillow_heif
import pytest
import tensorflow as tf

from mixstereo_tf import models
from mixstereo_tf.artifacts import graphs
from mixstereo_tf.artifacts import runs
from mixstereo_tf.cli import info_file
from mixstereo_tf.cli import input_images
from mixstereo_tf.cli import media
from mixstereo_tf.cli import stereo_formats
from mixstereo_tf.cli import input_failures
from mixstereo_tf.cli import unmix_files
from mixstereo_tf.cli import video_files
from mixstereo_tf.core import colormap
from mixstereo_tf.core import hints
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import halftone_print
from mixstereo_tf.data import image_io
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.unmixing import unmixer
from mixstereo_tf.video import frame_pipeline
from mixstereo_tf.video import jobs
from mixstereo_tf.video import temporal
from tests.unmixing import predictors_test
from tests.video import streams_test

INFO = runs.RunInfo('anaglyph', 64, 128, predictors_test.TINY)


@pytest.fixture(scope='module')
def model():
  tf.keras.utils.set_random_seed(5)
  return models.build_model(predictors_test.TINY)


@pytest.fixture(scope='module')
def setup(model):
  graph = tf.function(graphs.serving_function(model))
  return unmixer.model_unmixer(graph, INFO, predictors.PredictorConfig(
      mixture='anaglyph', disparity_range=(0, 7)))


def _image(path, shape=(40, 50, 3), seed=0):
  image = np.random.RandomState(seed).randint(0, 256, shape).astype(np.uint8)
  media.write_image(str(path), image)
  return image


def test_an_inputs_colour_profile_is_kept_in_the_views(setup, tmp_path):
  from PIL import ImageCms  # pylint: disable=import-outside-toplevel
  profile = ImageCms.ImageCmsProfile(ImageCms.createProfile('sRGB')).tobytes()
  image = np.random.RandomState(3).randint(0, 256, (40, 50, 3)).astype(np.uint8)
  Image.fromarray(image).save(tmp_path / 'p3.png', icc_profile=profile)
  report = unmix_files.unmix_inputs(setup, str(tmp_path / 'p3.png'), str(tmp_path / 'out'),
                                    media.OutputOptions('separate', formats=('mpo', 'jps')))
  assert report.failures == []
  out = tmp_path / 'out'
  for name in ('p3_left.png', 'p3_right.png', 'p3.jps'):
    with Image.open(out / name) as written:
      assert written.info.get('icc_profile') == profile, name
  with Image.open(out / 'p3.mpo') as mpo:
    assert mpo.n_frames == 2
    for index in range(2):
      mpo.seek(index)
      assert mpo.info.get('icc_profile') == profile
  with Image.open(out / 'p3_disparity.png') as colour_map:  # Its colours are the map's.
    assert 'icc_profile' not in colour_map.info
  with open(out / 'p3_info.json', encoding='utf-8') as f:
    assert f'{len(profile)} bytes' in json.load(f)['icc_profile']
  # Without a profile the views carry none (sRGB, as viewers assume).
  _image(tmp_path / 'plain.png')
  unmix_files.unmix_inputs(setup, str(tmp_path / 'plain.png'), str(tmp_path / 'out2'),
                           media.OutputOptions('separate'))
  with Image.open(tmp_path / 'out2' / 'plain_left.png') as written:
    assert 'icc_profile' not in written.info


def test_an_inputs_depth_and_transparency_are_kept_in_its_views(setup, tmp_path):
  rng = np.random.RandomState(4)
  bgra = rng.randint(0, 65536, (40, 50, 4)).astype(np.uint16)
  bgra[..., 3] = 65535
  cv2.imwrite(str(tmp_path / 'scan16.png'), bgra)  # 16-bit, opaque.
  bgra[:5, :5, 3] = 0
  cv2.imwrite(str(tmp_path / 'logo.png'), (bgra // 257).astype(np.uint8))  # 8-bit, clear.
  _image(tmp_path / 'plain.png')
  report = unmix_files.unmix_inputs(setup, str(tmp_path), str(tmp_path / 'out'),
                                    media.OutputOptions('separate'))
  assert report.failures == []
  infos = {}
  for name in ('scan16', 'logo', 'plain'):
    with open(tmp_path / 'out' / f'{name}_info.json', encoding='utf-8') as f:
      infos[name] = json.load(f)
  assert infos['scan16']['views_bit_depth'] == 16
  assert not {'alpha', 'bit_depth'} & set(infos['scan16'])
  view = cv2.imread(str(tmp_path / 'out' / 'scan16_left.png'), cv2.IMREAD_UNCHANGED)
  np.testing.assert_array_equal(view[..., 2], bgra[..., 2])  # Its red, 16-bit samples.
  assert 'transparency' in infos['logo']['views_alpha']
  assert not {'alpha', 'bit_depth'} & set(infos['logo'])
  assert not {'alpha', 'bit_depth', 'views_bit_depth', 'views_alpha'} & set(infos['plain'])
  for side in ('left', 'right'):
    with Image.open(tmp_path / 'out' / f'logo_{side}.png') as view:
      assert view.mode == 'RGBA'
      np.testing.assert_array_equal(np.asarray(view)[..., 3], bgra[..., 3] // 257)
  with Image.open(tmp_path / 'out' / 'scan16_left.png') as view:
    assert view.mode != 'RGBA'  # Opaque everywhere: no alpha to keep.


def test_a_scanned_print_is_descreened_and_its_screen_recorded(tmp_path):
  """A printed anaglyph saved as a JPEG: the screen found through the JPEG and recorded in
  the info JSON; an ordinary image records none."""
  from tests.unmixing import detection_test  # pylint: disable=import-outside-toplevel
  left, right, _ = detection_test._pair(height=192, width=288)  # pylint: disable=protected-access
  clean = detection_test._ours('anaglyph', left, right)  # pylint: disable=protected-access
  Image.fromarray(halftone_print.halftone_print(clean, 4.0)).save(tmp_path / 'scan.jpg',
                                                                  quality=90)
  Image.fromarray(clean).save(tmp_path / 'plain.png')
  classical = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='anaglyph', descreen='auto'))
  report = unmix_files.unmix_inputs(classical, str(tmp_path), str(tmp_path / 'out'),
                                    media.OutputOptions('separate'))
  assert report.failures == []
  read = lambda name: json.loads((tmp_path / 'out' / f'{name}_info.json').read_text())
  assert read('scan')['screen_period'] == pytest.approx(4.0, rel=0.03)
  assert 'screen_period' not in read('plain')


def test_a_rerun_into_the_same_folder_leaves_only_its_own_results(setup, tmp_path):
  _image(tmp_path / 'scene.png')
  out = tmp_path / 'out'
  (out / 'keep').mkdir(parents=True)
  (out / 'scene_notes.txt').write_text('not ours: no info lists it')
  unmix_files.unmix_inputs(setup, str(tmp_path / 'scene.png'), str(out),
                           media.OutputOptions('separate', formats=('jps',)))
  assert (out / 'scene_left.png').exists() and (out / 'scene.jps').exists()
  report = unmix_files.unmix_inputs(setup, str(tmp_path / 'scene.png'), str(out),
                                    media.OutputOptions('sbs'))
  assert report.failures == []
  info = json.loads((out / 'scene_info.json').read_text())
  assert sorted(os.listdir(out)) == sorted(info['files'] + ['scene_info.json', 'keep',
                                                            'scene_notes.txt'])
  assert 'scene_sbs.png' in info['files'] and not (out / 'scene_left.png').exists()


def test_a_rerun_over_a_grown_archive_keeps_every_earlier_name(setup, tmp_path):
  """Names came from the whole input list: an input added beside one of the same file name
  renamed the earlier one's results and overwrote them with its own."""
  os.makedirs(tmp_path / 'scans' / 'b')
  _image(tmp_path / 'scans' / 'b' / 'x.png', seed=1)
  pattern, out = str(tmp_path / 'scans' / '**' / '*.png'), tmp_path / 'out'
  unmix_files.unmix_inputs(setup, pattern, str(out))
  before = (out / 'x_left.png').read_bytes()
  os.makedirs(tmp_path / 'scans' / 'a')
  _image(tmp_path / 'scans' / 'a' / 'x.png', seed=2)
  report = unmix_files.unmix_inputs(setup, pattern, str(out))
  assert (report.processed, report.failures) == (2, [])
  assert (out / 'x_left.png').read_bytes() == before
  info = lambda name: json.loads((out / f'{name}_info.json').read_text())['input']
  assert info('x').endswith(os.path.join('b', 'x.png'))
  assert info('x_png').endswith(os.path.join('a', 'x.png'))
  assert sorted(f for f in os.listdir(out) if f.endswith('_info.json')) == [
      'x_info.json', 'x_png_info.json']  # b's results were not made again as x_png_2.


def test_a_rerun_from_another_folder_knows_the_earlier_inputs(setup, tmp_path, monkeypatch):
  """The info recorded the input's path as typed, read back against the rerun's own folder:
  another folder's photo.png overwrote the first one's results, and the same file run from
  the parent folder was redone as photo_2."""
  out = tmp_path / 'out'
  for folder, seed in (('a', 1), ('b', 2)):
    (tmp_path / folder).mkdir()
    _image(tmp_path / folder / 'photo.png', seed=seed)
  monkeypatch.chdir(tmp_path / 'a')
  unmix_files.unmix_inputs(setup, 'photo.png', str(out))
  first = (out / 'photo_left.png').read_bytes()
  monkeypatch.chdir(tmp_path / 'b')
  unmix_files.unmix_inputs(setup, 'photo.png', str(out))
  assert (out / 'photo_left.png').read_bytes() == first  # b's photo is photo_2.
  monkeypatch.chdir(tmp_path)
  unmix_files.unmix_inputs(setup, os.path.join('a', 'photo.png'), str(out))
  assert sorted(f for f in os.listdir(out) if f.endswith('_info.json')) == [
      'photo_2_info.json', 'photo_info.json']


def test_results_written_inside_the_input_tree_are_no_inputs_of_a_rerun(setup, tmp_path):
  (tmp_path / 'scans').mkdir()
  _image(tmp_path / 'scans' / 'a.png')
  pattern, out = str(tmp_path / 'scans' / '**' / '*'), tmp_path / 'scans' / 'out'
  assert unmix_files.unmix_inputs(setup, pattern, str(out)).processed == 1
  written = sorted(os.listdir(out))
  report = unmix_files.unmix_inputs(setup, pattern, str(out))  # Was refused: "holds the input".
  assert (report.processed, report.failures) == (1, [])
  assert sorted(os.listdir(out)) == written


class _Terminal(io.StringIO):
  """A stream that says it is a terminal, so progress is drawn on it."""

  def isatty(self):
    return True


def test_every_layout_for_one_image(setup, tmp_path):
  _image(tmp_path / 'scene.png')
  expected = {'separate': ['scene_left.png', 'scene_right.png'], 'sbs': ['scene_sbs.png'],
              'sbs_half': ['scene_sbs_half.png'], 'tb': ['scene_tb.png']}
  shapes = {'scene_left.png': (40, 50, 3), 'scene_right.png': (40, 50, 3),
            'scene_sbs.png': (40, 100, 3), 'scene_sbs_half.png': (40, 50, 3),
            'scene_tb.png': (80, 50, 3)}
  for layout, names in expected.items():
    out = tmp_path / layout
    report = unmix_files.unmix_inputs(setup, str(tmp_path / 'scene.png'), str(out),
                                      media.OutputOptions(layout))
    assert (report.processed, report.frames, report.failures) == (1, 1, [])
    common = ['scene_disparity.png', 'scene_disparity16.png', 'scene_disparity.npy',
              'scene_info.json']
    assert sorted(os.listdir(out)) == sorted(names + common)
    for name in names:
      assert input_images.read_image(str(out / name)).shape == shapes[name]
  # The three disparity files agree with each other and with the unmixer.
  disparity = np.load(tmp_path / 'tb' / 'scene_disparity.npy')
  direct = setup(input_images.read_image(str(tmp_path / 'scene.png')))['disparity_left']
  np.testing.assert_allclose(disparity, direct, atol=1e-5)
  raw = cv2.imread(str(tmp_path / 'tb' / 'scene_disparity16.png'), cv2.IMREAD_UNCHANGED)
  assert raw.dtype == np.uint16
  np.testing.assert_allclose(raw / 256.0, disparity, atol=1 / 512 + 1e-6)
  colour = input_images.read_image(str(tmp_path / 'tb' / 'scene_disparity.png'))
  low, high = media.display_range(disparity)  # The range the map covers.
  np.testing.assert_array_equal(colour, colormap.colorize(disparity, high, low))
  info = json.loads((tmp_path / 'tb' / 'scene_info.json').read_text())
  assert (info['method'], info['mixture'], info['disparity_range']) == (
      'model', 'anaglyph', [0, 7])
  assert info['display_range'] == pytest.approx([low, high], abs=1e-3) and info['seconds'] > 0


def test_folder_with_a_corrupt_file_and_a_gray_image(setup, tmp_path):
  folder = tmp_path / 'in'
  folder.mkdir()
  _image(folder / 'a.png')
  (folder / 'b.png').write_bytes(b'\x89PNG\r\n\x1a\n truncated')
  cv2.imwrite(str(folder / 'c.jpg'), np.full((33, 47), 90, np.uint8))  # Gray.
  terminal = _Terminal()
  report = unmix_files.unmix_inputs(setup, str(folder), str(tmp_path / 'out'),
                                    media.OutputOptions('sbs_half'), progress_stream=terminal)
  assert report.processed == 2 and report.frames == 2
  assert '[##########] 3/3' in terminal.getvalue() and terminal.getvalue().endswith('\n')
  assert [os.path.basename(p) for p, _ in report.failures] == ['b.png']
  assert 'b.png' in report.failures[0][1]
  assert input_failures.failure_message(report) == (
      f'error: 1 of 3 input(s) failed: {folder / "b.png"}')
  assert input_images.read_image(str(tmp_path / 'out' / 'c_sbs_half.png')).shape == (33, 47, 3)
  assert not os.path.exists(tmp_path / 'out' / 'b_disparity.npy')
  # Nothing readable: the report asks for a non-zero exit.
  os.remove(folder / 'a.png')
  os.remove(folder / 'c.jpg')
  report = unmix_files.unmix_inputs(setup, str(folder), str(tmp_path / 'out2'))
  assert report.processed == 0 and len(report.failures) == 1
  assert '1 of 1 input(s) failed' in input_failures.failure_message(report)


def _correlated(texture):
  """A texture whose channels vary together, as a photograph's do (a colour anaglyph of
  independent random channels shows no displaced channel to detect)."""
  luma = texture.mean(-1, keepdims=True)
  return np.clip(luma * 1.3 - 0.5 + 0.35 * (texture - luma) + 0.15 + 0.5
                 + np.array([0.1, 0.0, -0.1], np.float32), 0, 1)


def _anaglyph_clip(path, mixture, frames=24, rotation=0, black=(), fade=0):
  """A stereo clip (a textured plane 3 px behind a box 6 px, both moving) encoded as
  `mixture` anaglyph frames, with a sine audio track; returns the path. With `rotation`
  (degrees counter-clockwise, a multiple of 90) the frames are stored turned back by it
  and the display matrix turns them upright, as a phone filming in portrait stores them.
  The frames of `black` (indices) are black; the first `fade` frames fade in from black
  (the texture's channels then vary together: `_correlated`)."""
  texture = cv2.resize(np.random.RandomState(4).rand(20, 60, 3).astype(np.float32), (240, 64),
                       interpolation=cv2.INTER_CUBIC)
  texture = _correlated(texture) if fade else texture
  images = []
  for index in range(frames):
    shift = 2 * index
    left = texture[:, shift + 20:shift + 116].copy()
    right = texture[:, shift + 23:shift + 119].copy()  # Right x shows left x + 3.
    left[20:44, 30:60] = right[20:44, 24:54] = texture[:24, 100 - shift:130 - shift]
    left_u8, right_u8 = (image_range.unit_to_u8(np.clip(v, 0, 1)) for v in (left, right))
    mixed = mixtures.mix(mixture, image_range.u8_to_signed(left_u8),
                         image_range.u8_to_signed(right_u8))
    images.append(np.ascontiguousarray(np.rot90(image_range.signed_to_u8(mixed.numpy()),
                                                -(rotation // 90))))
    if index in black:
      images[-1][:] = 0
    if index < fade:
      images[-1] = np.round(images[-1] * (index / fade)).astype(np.uint8)
  return streams_test.make_video(path, images, rotation=rotation)


class Interrupted(Exception):
  """Stands in for Ctrl-C or a crash while unmixing."""


def _failing_after(unmixer, frames):
  """The unmixer, raising Interrupted once it has unmixed `frames` frames."""
  count = [0]

  def unmix(image, **hint):
    if count[0] == frames:
      raise Interrupted()
    count[0] += 1
    return unmixer(image, **hint)
  return dataclasses.replace(unmixer, fn=unmix)


@pytest.mark.parametrize('mixture, extension, layout', [('anaglyph', '.mp4', 'tb'),
                                                        ('gray', '.mkv', 'separate')])
def test_video_resumes_after_interruption_with_audio(tmp_path, mixture, extension, layout):
  source = _anaglyph_clip(tmp_path / f'clip{extension}', mixture)
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture=mixture, disparity_range=(0, 8)))
  config = jobs.VideoConfig(segment_frames=10)
  keys = ['left', 'right'] if layout == 'separate' else [layout]
  names = [f'clip_{key}{extension}' for key in keys + ['disparity']]
  terminal = _Terminal()
  report = unmix_files.unmix_inputs(unmixer, source, str(tmp_path / 'once'),
                                    media.OutputOptions(layout, video_config=config),
                                    progress_stream=terminal)
  assert (report.processed, report.frames, report.failures) == (1, 24, [])
  assert f'clip{extension}  [##########] 24/24  ' in terminal.getvalue() or (
      extension == '.mkv')  # Matroska gives no frame count: '24 done'.
  assert sorted(os.listdir(tmp_path / 'once')) == sorted(names + ['clip_info.json'])
  source_info, _ = streams_test.read_all(source)
  for name in names:
    info, frames = streams_test.read_all(tmp_path / 'once' / name)
    assert len(frames) == 24 and info.frame_rate == source_info.frame_rate == 12
    assert frames[0].image.shape == ((128, 96, 3) if name.endswith(f'tb{extension}')
                                     else (64, 96, 3))
    np.testing.assert_array_equal(streams_test.audio_samples(tmp_path / 'once' / name),
                                  streams_test.audio_samples(source))
  info = json.loads((tmp_path / 'once' / 'clip_info.json').read_text())
  assert (info['frames'], info['frame_rate'], info['audio_streams']) == (24, '12', 1)
  assert info['method'] == 'classical' and info['files'] == names
  # A shot starts at each segment (10 frames): each listed with its decisions.
  assert [(s['first_frame'], s['mixture'], s['disparity_range']) for s in info['shots']] == [
      (0, mixture, [0, 8]), (10, mixture, [0, 8]), (20, mixture, [0, 8])]
  assert 'shots_from_frame' not in info
  # Interrupted after 13 frames: nothing under a final name; the re-run resumes at 10.
  with pytest.raises(Interrupted):
    unmix_files.unmix_inputs(_failing_after(unmixer, 13), source, str(tmp_path / 'again'),
                             media.OutputOptions(layout, video_config=config))
  assert not any(os.path.exists(tmp_path / 'again' / name) for name in names)
  report = unmix_files.unmix_inputs(unmixer, source, str(tmp_path / 'again'),
                                    media.OutputOptions(layout, video_config=config))
  assert (report.processed, report.frames) == (1, 14)
  resumed = json.loads((tmp_path / 'again' / 'clip_info.json').read_text())
  assert resumed['resumed_frames'] == 10 and resumed['shots_from_frame'] == 10
  # The top level describes the video's first frame, as an uninterrupted run's does, not
  # the resumed part's first.
  for key in ('mixture', 'disparity_range', 'detected', 'confidence'):
    assert resumed[key] == info[key], key
  assert [s['first_frame'] for s in resumed['shots']] == [10, 20]
  assert sorted(os.listdir(tmp_path / 'again')) == sorted(names + ['clip_info.json'])
  for name in names:
    _, once = streams_test.read_all(tmp_path / 'once' / name)
    _, again = streams_test.read_all(tmp_path / 'again' / name)
    assert [f.time for f in once] == [f.time for f in again]
    for a, b in zip(once, again):
      np.testing.assert_array_equal(a.image, b.image)


@pytest.mark.parametrize('rotation', [90, -90])
def test_portrait_video_is_unmixed_upright(tmp_path, rotation):
  """A phone's portrait clip: the eyes lie side by side only as a player shows the frames,
  so they are turned upright before unmixing and written so, with no rotation left."""
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='anaglyph', disparity_range=(0, 8)))
  outputs = {}
  for turn in (0, rotation):
    source = _anaglyph_clip(tmp_path / f'clip{turn}.mp4', 'anaglyph', frames=6,
                            rotation=turn)
    unmix_files.unmix_inputs(unmixer, source, str(tmp_path / f'out{turn}'),
                             media.OutputOptions('sbs'))
    outputs[turn] = streams_test.read_all(tmp_path / f'out{turn}' / f'clip{turn}_sbs.mp4',
                                          upright=False)
    info = json.loads((tmp_path / f'out{turn}' / f'clip{turn}_info.json').read_text())
    assert (info['rotation'], info['turned_upright']) == (0, turn) and 'padding' not in info
  (info, turned), (_, plain) = outputs[rotation], outputs[0]
  assert info.rotation == 0 and turned[0].image.shape == plain[0].image.shape == (64, 192, 3)
  # The same views but for the chroma subsampling of the turned grid; flipped ones differ.
  for a, b in zip(turned, plain):
    assert np.abs(a.image.astype(int) - b.image).mean() < 8
    assert np.abs(a.image.astype(int) - b.image[::-1, ::-1]).mean() > 30


def test_an_odd_sized_video_says_its_outputs_are_padded(tmp_path):
  def unmix(image, **hint):
    del hint
    return {'left': image, 'right': image, 'info': {},
            'disparity_left': np.zeros(image.shape[:2], np.float32)}

  source = streams_test.make_video(tmp_path / 'odd.avi',  # MJPEG takes odd sizes.
                                   [streams_test.pattern(i, 33, 47) for i in range(3)])
  unmixer = predictors.Unmixer(unmix, 'test', 'anaglyph', 8.0)
  unmix_files.unmix_inputs(unmixer, source, str(tmp_path / 'out'),
                           media.OutputOptions('sbs_half'))
  info = json.loads((tmp_path / 'out' / 'odd_info.json').read_text())
  assert info['padding'].startswith('47x33 frames')
  out_info, _ = streams_test.read_all(tmp_path / 'out' / 'odd_sbs_half.avi')
  assert (out_info.width, out_info.height) == (48, 34)


def test_a_16_bit_double_image_file_gives_16_bit_views(tmp_path):
  """Its layers are solved from the file's 16-bit samples: nothing lost to say."""
  rng = np.random.RandomState(6)
  texture = rng.randint(0, 65536, (40, 70, 3)).astype(np.uint16)
  double = ((texture[:, 6:].astype(np.uint32) + texture[:, :-6]) // 2).astype(np.uint16)
  cv2.imwrite(str(tmp_path / 'double16.png'), double[..., ::-1])
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='diplopia', disparity_range=(1, 10)))
  report = unmix_files.unmix_inputs(unmixer, str(tmp_path / 'double16.png'),
                                    str(tmp_path / 'out'), media.OutputOptions('separate'))
  assert report.failures == []
  info = json.loads((tmp_path / 'out' / 'double16_info.json').read_text())
  assert info['views_bit_depth'] == 16 and 'bit_depth' not in info
  view = cv2.imread(str(tmp_path / 'out' / 'double16_left.png'), cv2.IMREAD_UNCHANGED)
  assert view.dtype == np.uint16 and (view % 257 != 0).mean() > 0.9


def test_a_10_bit_heic_anaglyph_gives_16_bit_views(tmp_path):
  """A phone's HEIC is an input (`input_listing`); one of 10 bits is read at 16
  (`image_io._deep_heif`) and its views restored from those samples, as a 16-bit PNG's."""
  y, x = np.mgrid[:48, :80]
  texture = np.random.default_rng(7).random((48, 96))
  left = np.dstack([0.3 + 0.4 * texture[:, 8:88], 0.2 + 0.3 * x / 80, 0.5 + 0.2 * y / 48])
  right = np.dstack([0.3 + 0.4 * texture[:, 4:84], 0.2 + 0.3 * x / 80, 0.5 + 0.2 * y / 48])
  anaglyph = np.rint(np.dstack([left[..., 0], right[..., 1], right[..., 2]]) * 65535)
  pillow_heif.from_bytes(mode='RGB;16', size=(80, 48),
                         data=anaglyph.astype(np.uint16).tobytes()).save(
                             str(tmp_path / 'phone.heic'), quality=-1)
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='anaglyph', disparity_range=(0, 8)))
  report = unmix_files.unmix_inputs(unmixer, str(tmp_path), str(tmp_path / 'out'),
                                    media.OutputOptions('separate'))
  assert report.failures == [] and report.processed == 1
  info = json.loads((tmp_path / 'out' / 'phone_info.json').read_text())
  assert info['views_bit_depth'] == 16 and info['matched_at_colour_resolution']
  view = cv2.imread(str(tmp_path / 'out' / 'phone_left.png'), cv2.IMREAD_UNCHANGED)
  assert view.dtype == np.uint16 and (view % 257 != 0).mean() > 0.9


def test_half_resolution_colour_of_a_jpeg_or_video_reaches_the_unmixer(tmp_path):
  halved = []

  def unmix(image, hint=None):
    halved.append(hint is not None and hint.chroma_halved)
    return {'left': image, 'right': image, 'info': {},
            'disparity_left': np.zeros(image.shape[:2], np.float32)}

  unmixer = predictors.Unmixer(unmix, 'test', 'anaglyph', 8.0)
  image = Image.fromarray(np.random.default_rng(0).integers(0, 256, (40, 50, 3), np.uint8))
  image.save(tmp_path / 'web.jpg', quality=90)
  image.save(tmp_path / 'full.jpg', quality=90, subsampling=0)
  image.save(tmp_path / 'plain.png')
  streams_test.make_video(tmp_path / 'clip.mp4', [streams_test.pattern(i) for i in range(2)])
  for name in ('web.jpg', 'full.jpg', 'plain.png', 'clip.mp4'):
    unmix_files.unmix_inputs(unmixer, str(tmp_path / name), str(tmp_path / 'out'))
  # The video: its 2 frames, the first unmixed once (`video_files.opening`, its outputs
  # taken by the frame pipeline).
  assert halved == [True, False, False, True, True]


def test_a_cut_video_is_written_as_far_as_it_decodes_and_says_so(tmp_path):
  def unmix(image, **hint):
    del hint
    return {'left': image, 'right': image, 'info': {},
            'disparity_left': np.zeros(image.shape[:2], np.float32)}

  whole = streams_test.make_video(tmp_path / 'whole.mp4',
                                  [streams_test.pattern(i) for i in range(40)])
  moved = str(tmp_path / 'moved.mp4')  # Index first (as for the web): a cut keeps it.
  subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), '-v', 'error', '-i', whole, '-c', 'copy',
                  '-movflags', 'faststart', moved], check=True)
  data = open(moved, 'rb').read()
  with open(tmp_path / 'cut.mp4', 'wb') as f:
    f.write(data[:len(data) * 2 // 3])
  report = unmix_files.unmix_inputs(predictors.Unmixer(unmix, 'test', 'anaglyph', 8.0),
                                    str(tmp_path / 'cut.mp4'), str(tmp_path / 'out'),
                                    media.OutputOptions('sbs'))
  assert report.failures == []
  info = json.loads((tmp_path / 'out' / 'cut_info.json').read_text())
  assert 0 < info['frames'] < 38 and f'ended after {info["frames"]} of the 40 frames' in (
      info['ended_early'])
  _, frames = streams_test.read_all(tmp_path / 'out' / 'cut_sbs.mp4')
  assert len(frames) == info['frames']


def _ten_bit_anaglyph_video(path, frames=3, colour=(2, 2)):
  """A red-cyan anaglyph video of 10-bit samples (through PyAV directly: H.264 High 10, AVI
  FFV1): its red a smooth ramp of about 500 10-bit levels, green and blue other ramps
  (smooth: 4:2:0 colour lends the red no texture), tagged with `colour` (primaries,
  transfer). Returns the red, uint16 [64, 96]."""
  y, x = np.mgrid[:64, :96]
  ramps = [(0.25 + 0.5 * (x + 7 * y) / (95 + 7 * 63)), 0.3 + 0.4 * y / 63, 0.6 - 0.3 * x / 95]
  image = np.rint(np.dstack(ramps) * 65535).astype(np.uint16)
  avi = str(path).endswith('.avi')
  with av.open(str(path), 'w') as out:
    # Not x265: PyAV's MP4 muxing of it fails at random ('Not yet implemented', encoders.py).
    stream = out.add_stream('ffv1' if avi else 'libx264', rate=12,
                            options={} if avi else {'crf': '4'})
    stream.width, stream.height, stream.pix_fmt = 96, 64, 'yuv420p10le'
    stream.codec_context.color_primaries, stream.codec_context.color_trc = colour
    for index in range(frames):
      frame = av.VideoFrame.from_ndarray(image, format='rgb48le')
      frame = frame.reformat(format='yuv420p10le', dst_colorspace=1, dst_color_range=1)
      frame.pts = index
      out.mux(stream.encode(frame))
    out.mux(stream.encode(None))
  return image[..., 0]


@pytest.mark.parametrize('extension', ['.mp4', '.avi'])
def test_a_10_bit_video_keeps_its_bits_in_the_views(tmp_path, extension):
  """A 10-bit video's frames reach the unmixer at 16 bits and its views' video keeps 10
  (H.264 High 10): the left view's red, the anaglyph's red
  copied, takes the input's ~500 levels where 8 bits hold 128 of them; the disparity video
  stays 8-bit H.264. AVI's Motion JPEG has 8 bits: written so, and said."""
  ramp = _ten_bit_anaglyph_video(tmp_path / f'hdr{extension}')
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='anaglyph', disparity_range=(-4, 4)))
  report = unmix_files.unmix_inputs(unmixer, str(tmp_path / f'hdr{extension}'),
                                    str(tmp_path / 'out'), media.OutputOptions('sbs'))
  assert report.failures == []
  info = json.loads((tmp_path / 'out' / 'hdr_info.json').read_text())
  sbs = str(tmp_path / 'out' / f'hdr_sbs{extension}')
  with av.open(sbs) as video:
    stream = video.streams.video[0]
    codec, pix_fmt = stream.codec_context.name, stream.codec_context.pix_fmt
    left = next(video.decode(stream)).to_ndarray(format='rgb48le')[:, :96, 0]
  levels = len(np.unique(left[:, 8:-8] >> 6))  # In 10-bit steps.
  error = np.abs(left.astype(float) - ramp)[:, 8:-8] / 64
  if extension == '.mp4':
    assert info['views_bit_depth'] == 10 and 'written at 10 (H.264 High 10)' in info['bit_depth']
    assert (codec, pix_fmt) == ('h264', 'yuv420p10le') and levels > 300, (pix_fmt, levels)
    assert np.median(error) <= 4, np.median(error)  # Two lossy encodes: < 1 8-bit step.
  else:
    assert info['views_bit_depth'] == 8 and 'written at 8' in info['bit_depth']
    assert "codec, Motion JPEG, has no more" in info['bit_depth']
    assert codec == 'mjpeg' and levels <= 140, levels
  with av.open(str(tmp_path / 'out' / f'hdr_disparity{extension}')) as video:
    assert video.streams.video[0].codec_context.pix_fmt in ('yuv420p', 'yuvj420p')


def test_a_10_bit_videos_views_are_written_at_8_bits_when_asked(tmp_path):
  """--nokeep_video_bits (`jobs.VideoConfig.keep_bits`): 8-bit H.264 views, which every
  player plays, and the info says why."""
  _ten_bit_anaglyph_video(tmp_path / 'hdr.mp4', frames=2)
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='anaglyph', disparity_range=(-4, 4)))
  options = media.OutputOptions('sbs', video_config=jobs.VideoConfig(keep_bits=False))
  report = unmix_files.unmix_inputs(unmixer, str(tmp_path / 'hdr.mp4'), str(tmp_path / 'out'),
                                    options)
  assert report.failures == []
  info = json.loads((tmp_path / 'out' / 'hdr_info.json').read_text())
  assert info['views_bit_depth'] == 8 and '--nokeep_video_bits' in info['bit_depth']
  with av.open(str(tmp_path / 'out' / 'hdr_sbs.mp4')) as video:
    assert video.streams.video[0].codec_context.pix_fmt == 'yuv420p'


def test_an_hdr_videos_views_keep_its_colour_tags_and_its_colour_map_is_tagged_srgb(
    tmp_path):
  """An HLG video (BT.2020 primaries, transfer 18): its views' RGB is the input's, so they
  keep its tags; the disparity's colour map is drawn in sRGB colours, which the input's
  tags made HDR players misshow: tagged BT.709 (`jobs.SRGB_TAGS`)."""
  _ten_bit_anaglyph_video(tmp_path / 'hlg.mp4', frames=2, colour=(9, 18))
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='anaglyph', disparity_range=(-4, 4)))
  report = unmix_files.unmix_inputs(unmixer, str(tmp_path / 'hlg.mp4'), str(tmp_path / 'out'),
                                    media.OutputOptions('sbs', formats=('rgbd',)))
  assert report.failures == []
  tags = {}
  for key in ('sbs', 'rgbd', 'disparity'):
    with av.open(str(tmp_path / 'out' / f'hlg_{key}.mp4')) as video:
      context = video.streams.video[0].codec_context
      tags[key] = (int(context.color_primaries), int(context.color_trc))
  assert tags == {'sbs': (9, 18), 'rgbd': (9, 18), 'disparity': jobs.SRGB_TAGS}


def test_a_10_bit_video_whose_method_makes_8_bit_views_says_so(tmp_path):
  """A method whose views come at 8 bits from 16-bit frames (a single view's models):
  every frame reaches it at 16 bits, as the opening frame did, so that frame is not unmixed
  a second time; its views' video is 8-bit, and the info says why."""
  frames = []

  def unmix(image, **hint):
    del hint
    frames.append(image.dtype)
    return {'left': image_range.eight_bits(image), 'right': image_range.eight_bits(image),
            'info': {}, 'disparity_left': np.zeros(image.shape[:2], np.float32)}

  _ten_bit_anaglyph_video(tmp_path / 'hdr.mkv', frames=2)
  report = unmix_files.unmix_inputs(predictors.Unmixer(unmix, 'test', 'anaglyph', 8.0),
                                    str(tmp_path / 'hdr.mkv'), str(tmp_path / 'out'),
                                    media.OutputOptions('sbs'))
  assert report.failures == [] and frames == [np.dtype(np.uint16)] * 2  # Once a frame.
  info = json.loads((tmp_path / 'out' / 'hdr_info.json').read_text())
  assert info['views_bit_depth'] == 8
  assert info['bit_depth'].endswith('its views were written at 8 bits (this method makes '
                                    '8-bit views)')
  with av.open(str(tmp_path / 'out' / 'hdr_sbs.mkv')) as video:
    assert video.streams.video[0].codec_context.pix_fmt == 'yuv420p'


def test_an_input_too_large_for_memory_fails_alone(tmp_path):
  """NumPy / numba raise MemoryError (not TensorFlow's error) for an allocation too large:
  that input fails, the others are unmixed."""
  def unmix(image, **hint):
    del hint
    if image.shape[0] == 41:
      raise MemoryError('Unable to allocate 90.1 GiB for an array')
    return {'left': image, 'right': image, 'info': {},
            'disparity_left': np.zeros(image.shape[:2], np.float32)}

  os.makedirs(tmp_path / 'in')
  _image(tmp_path / 'in' / 'a.png')
  _image(tmp_path / 'in' / 'b.png', shape=(41, 50, 3))
  report = unmix_files.unmix_inputs(predictors.Unmixer(unmix, 'test', 'anaglyph', 8.0),
                                    str(tmp_path / 'in'), str(tmp_path / 'out'))
  assert report.processed == 1 and len(report.failures) == 1
  assert report.failures[0][1] == 'MemoryError: Unable to allocate 90.1 GiB for an array'


@pytest.mark.parametrize('config, base', [(temporal.TemporalConfig(), True),
                                          (temporal.TemporalConfig(use_prior=False), False),
                                          (temporal.TemporalConfig(enabled=False), False)])
def test_video_frames_tell_the_unmixer_that_the_right_disparity_is_unread(tmp_path, config,
                                                                         base):
  """Videos write the views and the left disparity: each frame's hint says so, which lets a
  refiner leave out its right disparity correction, and with the shot's prior asks for the
  base's disparities (a double image's refiner then runs its views' network alone;
  tests/unmixing/shipped_test.py); matched whole, frames are refined as stills are."""
  source = _anaglyph_clip(tmp_path / 'clip.mp4', 'gray', frames=3)
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='gray', disparity_range=(0, 8)))
  seen = []

  def unmix(image, hint=None):
    seen.append(hint and (hint.unread, hint.base_disparities))
    return unmixer(image, hint=hint)

  report = unmix_files.unmix_inputs(dataclasses.replace(unmixer, fn=unmix), source,
                                    str(tmp_path / 'out'),
                                    media.OutputOptions('sbs', temporal_config=config))
  # Each frame once: the first for the colour maps' range, as the first of its shot (its
  # outputs taken by the frame pipeline), then the others.
  assert report.frames == 3 and seen == [('disparity_right', base)] * 3
  # The colour maps span that range (0..8 px here), not the method's largest disparity.
  info = json.loads((tmp_path / 'out' / 'clip_info.json').read_text())
  assert info['display_range'] == [0.0, 8.0] and unmixer.max_disparity != 8.0
  _, frames = streams_test.read_all(tmp_path / 'out' / 'clip_disparity.mp4')
  assert max(frame.image.max() for frame in frames) > 200  # Near shows bright (255: 8 px).


def test_the_opening_frame_is_handed_to_its_frame_once():
  """`video_files.Opening`: its call goes to the frame it unmixed, once (not held after),
  and its info stays for the video's info file."""
  image = np.zeros((4, 6, 3), np.uint8)
  call = frame_pipeline.Unmixed(image, hints.FrameHint(), {'info': {'mixture': 'gray'}})
  opened = video_files.Opening(5, call)
  assert opened.take(4) is None and opened.take(5) is call and opened.take(5) is None
  assert opened.info == {'mixture': 'gray'}


def test_unreadable_video_is_named(setup, tmp_path):
  (tmp_path / 'broken.mp4').write_bytes(b'not a video' * 100)
  report = unmix_files.unmix_inputs(setup, str(tmp_path / 'broken.mp4'), str(tmp_path / 'out'))
  assert report.processed == 0 and report.failures[0][0] == str(tmp_path / 'broken.mp4')
  assert report.failures[0][1].startswith('ValueError: Cannot open video file ')
  assert 'broken.mp4' in report.failures[0][1]


def test_classical_method(tmp_path):
  setup = predictors.build_unmixer(predictors.PredictorConfig('classical', mixture='anaglyph'))
  mixture = _image(tmp_path / 'x.png', (30, 44, 3))
  report = unmix_files.unmix_inputs(setup, str(tmp_path / 'x.png'), str(tmp_path / 'out'))
  assert report.processed == 1 and not report.failures
  left = input_images.read_image(str(tmp_path / 'out' / 'x_left.png'))
  right = input_images.read_image(str(tmp_path / 'out' / 'x_right.png'))
  np.testing.assert_array_equal(left[..., 0], mixture[..., 0])  # Red-cyan channels kept.
  np.testing.assert_array_equal(right[..., 1:], mixture[..., 1:])
  assert np.load(tmp_path / 'out' / 'x_disparity.npy').shape == (30, 44)


def test_an_input_that_is_no_anaglyph_names_the_flag(tmp_path):
  setup = predictors.build_unmixer(predictors.PredictorConfig('classical', mixture='auto'))
  _image(tmp_path / 'noise.png', (24, 32, 3))  # No colour channel displaced: no anaglyph.
  report = unmix_files.unmix_inputs(setup, str(tmp_path / 'noise.png'), str(tmp_path / 'out'))
  assert report.processed == 0 and len(report.failures) == 1
  reason = report.failures[0][1]
  assert reason.startswith('ValueError: This image does not look like an anaglyph')
  assert 'name it (--mixture=diplopia)' in reason and 'PredictorConfig' not in reason


@pytest.mark.parametrize('temporal_on', [True, False])
def test_black_frames_of_a_video_take_its_detected_encoding(tmp_path, temporal_on):
  """A fade from black, a black pause: detection finds no anaglyph there, and the whole
  video failed. They are read as the video's encoding, found further on."""
  source = _anaglyph_clip(tmp_path / 'clip.mp4', 'gray', frames=30,
                          black=set(range(8)) | {15, 16, 17})
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='auto', disparity_range=(0, 8)))
  report = unmix_files.unmix_inputs(
      unmixer, source, str(tmp_path / 'out'),
      media.OutputOptions(temporal_config=temporal.TemporalConfig(enabled=temporal_on)))
  assert (report.processed, report.frames, report.failures) == (1, 30, [])
  info = json.loads((tmp_path / 'out' / 'clip_info.json').read_text())
  assert info['mixture'] == 'gray' and info['detected'] is None  # The first frame: black.
  assert info['read_as'] == "gray: no anaglyph found, the video's encoding"
  _, frames = streams_test.read_all(tmp_path / 'out' / 'clip_left.mp4')
  assert len(frames) == 30 and frames[3].image.max() < 24  # Black stays black.
  assert frames[10].image.mean() > 60


def test_a_colour_video_fading_in_from_black_is_unmixed_in_colour(tmp_path):
  """End to end through a fade (its darkest frames too dark to tell, read as the video's
  encoding; unit tests: detection_test, temporal_test): colour views at the end."""
  source = _anaglyph_clip(tmp_path / 'fade.mp4', 'anaglyph', frames=36, fade=20)
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='auto', disparity_range=(0, 8)))
  report = unmix_files.unmix_inputs(unmixer, source, str(tmp_path / 'out'))
  assert (report.processed, report.frames, report.failures) == (1, 36, [])
  info = json.loads((tmp_path / 'out' / 'fade_info.json').read_text())
  assert info['shots'][-1]['mixture'] == 'anaglyph'
  assert 'gray' not in [shot['mixture'] for shot in info['shots']]
  _, frames = streams_test.read_all(tmp_path / 'out' / 'fade_left.mp4')
  last = frames[-1].image.astype(float)
  assert (last.max(-1) - last.min(-1)).mean() > 20  # Colour views, not gray ones.


def test_shots_list_each_change_of_decision_frame_by_frame():
  shots = []
  for frame, (mixture, starts) in enumerate([('gray', True), ('gray', False),
                                             ('anaglyph', False), ('anaglyph', True)]):
    video_files.record_shot(shots, frame, {'mixture': mixture, 'disparity_range': [0, frame],
                                           'seconds': 1.0}, starts)
  assert shots == [{'first_frame': 0, 'mixture': 'gray', 'disparity_range': [0, 0]},
                   {'first_frame': 2, 'mixture': 'anaglyph', 'disparity_range': [0, 2]},
                   {'first_frame': 3, 'mixture': 'anaglyph', 'disparity_range': [0, 3]}]


def test_a_video_resumed_after_its_last_segment_records_what_was_done(tmp_path,
                                                                     monkeypatch):
  """Writing failed after every segment was done (a full disk): the rerun only assembles,
  and its info file still says how the video was unmixed."""
  source = _anaglyph_clip(tmp_path / 'clip.mp4', 'gray', frames=12)
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='auto', disparity_range=(0, 8)))
  options = media.OutputOptions(video_config=jobs.VideoConfig(segment_frames=6))
  first = unmix_files.unmix_inputs(unmixer, source, str(tmp_path / 'once'), options)
  expected = json.loads((tmp_path / 'once' / 'clip_info.json').read_text())
  assemble = jobs.assembly.assemble

  def disk_full(*args, **kwargs):
    raise OSError(28, 'No space left on device')
  monkeypatch.setattr(jobs.assembly, 'assemble', disk_full)
  with pytest.raises(input_failures.OutputFull, match='No space left'):  # Ends the run.
    unmix_files.unmix_inputs(unmixer, source, str(tmp_path / 'out'), options)
  monkeypatch.setattr(jobs.assembly, 'assemble', assemble)
  report = unmix_files.unmix_inputs(unmixer, source, str(tmp_path / 'out'), options)
  assert (first.frames, report.frames, report.failures) == (12, 0, [])
  info = json.loads((tmp_path / 'out' / 'clip_info.json').read_text())
  assert info['resumed_frames'] == 12
  for key in ('method', 'mixture', 'detected', 'confidence', 'disparity_range'):
    assert info[key] == expected[key], key


def test_a_webm_video_is_unmixed_into_matroska_with_its_audio(tmp_path):
  """WebM holds no H.264: its results go in Matroska, WebM's parent format."""
  _anaglyph_clip(tmp_path / 'clip.webm', 'gray', frames=6)
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='gray', disparity_range=(0, 8)))
  report = unmix_files.unmix_inputs(unmixer, str(tmp_path), str(tmp_path / 'out'))
  assert (report.processed, report.frames, report.failures) == (1, 6, [])
  for key in ('left', 'right', 'disparity'):
    info, frames = streams_test.read_all(tmp_path / 'out' / f'clip_{key}.mkv')
    assert len(frames) == 6 and (info.width, info.height) == (96, 64)
    assert info.audio_streams == 1


def test_m4v_videos_and_jfif_images_are_inputs(tmp_path):
  """Apple's .m4v (MP4) and the .jfif name some browsers save JPEGs under: in a folder
  they were skipped without a word, named directly refused as images."""
  source = _anaglyph_clip(tmp_path / 'clip.mp4', 'gray', frames=6)
  os.rename(source, tmp_path / 'clip.m4v')
  image = _image(tmp_path / 'photo.png')
  (tmp_path / 'photo.jfif').write_bytes(cv2.imencode('.jpg', image[..., ::-1])[1].tobytes())
  os.remove(tmp_path / 'photo.png')
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='gray', disparity_range=(0, 8)))
  report = unmix_files.unmix_inputs(unmixer, str(tmp_path), str(tmp_path / 'out'))
  assert (report.processed, report.frames, report.failures) == (2, 7, [])
  _, frames = streams_test.read_all(tmp_path / 'out' / 'clip_left.mp4')
  assert len(frames) == 6 and (tmp_path / 'out' / 'photo_left.png').exists()


def _claimed_png(path, width, height):
  """A PNG whose header claims width x height gray pixels, with one row of data."""
  def chunk(kind, data):
    return (len(data).to_bytes(4, 'big') + kind + data +
            (zlib.crc32(kind + data) & 0xffffffff).to_bytes(4, 'big'))
  header = width.to_bytes(4, 'big') + height.to_bytes(4, 'big') + bytes([8, 0, 0, 0, 0])
  path.write_bytes(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', header) +
                   chunk(b'IDAT', zlib.compress(b'\x00' * (width + 1))) + chunk(b'IEND', b''))


def test_an_image_too_large_for_pillow_fails_alone(setup, tmp_path):
  """Pillow's decompression-bomb error is no ValueError or OSError: one forged or huge
  scan ended the whole run (a batch: no summary, no dead letters)."""
  (tmp_path / 'in').mkdir()
  _image(tmp_path / 'in' / 'ok.png')
  _claimed_png(tmp_path / 'in' / 'huge.png', 19000, 19000)
  report = unmix_files.unmix_inputs(setup, str(tmp_path / 'in'), str(tmp_path / 'out'))
  assert report.processed == 1 and (tmp_path / 'out' / 'ok_left.png').exists()
  assert len(report.failures) == 1 and 'huge.png' in report.failures[0][0]
  assert 'exceeds limit' in report.failures[0][1]


def test_a_transport_stream_is_a_video_input_unmixed_into_matroska_with_its_audio(tmp_path):
  """Broadcast and camcorder (AVCHD .mts) files: an MPEG transport stream was read as an
  image ('Cannot decode image file'); its MP2 audio goes in Matroska."""
  _anaglyph_clip(tmp_path / 'clip.ts', 'gray', frames=6)
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='gray', disparity_range=(0, 8)))
  report = unmix_files.unmix_inputs(unmixer, str(tmp_path), str(tmp_path / 'out'))
  assert (report.processed, report.frames, report.failures) == (1, 6, [])
  info, frames = streams_test.read_all(tmp_path / 'out' / 'clip_left.mkv')
  assert len(frames) == 6 and info.audio_streams == 1


def test_a_video_without_any_anaglyph_names_itself(tmp_path):
  source = _anaglyph_clip(tmp_path / 'dark.mp4', 'gray', frames=6, black=set(range(6)))
  unmixer = predictors.build_unmixer(predictors.PredictorConfig('classical', mixture='auto'))
  report = unmix_files.unmix_inputs(unmixer, source, str(tmp_path / 'out'))
  assert report.processed == 0
  assert f'No frame of {source} looks like an anaglyph' in report.failures[0][1]


def test_inputs_sharing_a_stem_keep_their_own_outputs(setup, tmp_path):
  folder = tmp_path / 'in'
  folder.mkdir()
  _image(folder / 'a.png', seed=1)
  _image(folder / 'a.jpg', seed=2)
  out = tmp_path / 'out'
  report = unmix_files.unmix_inputs(setup, str(folder / 'a.*'), str(out))
  assert report.processed == 2 and not report.failures
  assert sorted(os.listdir(out)) == sorted(
      f'a_{ext}_{suffix}' for ext in ('png', 'jpg') for suffix in (
          'left.png', 'right.png', 'disparity.png', 'disparity16.png', 'disparity.npy',
          'info.json'))
  for ext in ('png', 'jpg'):
    path = str(folder / f'a.{ext}')  # The JPEG is 4:2:0 (OpenCV's default).
    hint = hints.FrameHint(chroma_halved=image_io.chroma_halved(path))
    expected = setup(input_images.read_image(path), hint=hint)['disparity_left']
    np.testing.assert_allclose(np.load(out / f'a_{ext}_disparity.npy'), expected, atol=1e-5)


def test_tensorflow_and_file_system_errors_skip_only_their_input(tmp_path):
  def unmix(image):
    value = int(image[0, 0, 0])
    if value == 10:
      raise tf.errors.ResourceExhaustedError(None, None, 'OOM when allocating\n  (trace)')
    if value == 20:
      raise OSError(5, 'Input/output error')  # A bad sector (a full disk ends the run).
    if value == 40:
      raise KeyError('a bug, not a bad input')
    return {'left': image, 'right': image,
            'disparity_left': np.zeros(image.shape[:2], np.float32)}

  folder = tmp_path / 'in'
  folder.mkdir()
  for name, value in (('a', 10), ('b', 20), ('c', 30)):
    media.write_image(str(folder / f'{name}.png'), np.full((8, 8, 3), value, np.uint8))
  unmixer = predictors.Unmixer(unmix, 'test', 'anaglyph', 8.0)
  report = unmix_files.unmix_inputs(unmixer, str(folder), str(tmp_path / 'out'))
  assert report.processed == 1 and os.path.exists(tmp_path / 'out' / 'c_left.png')
  assert report.failures == [
      (str(folder / 'a.png'), 'ResourceExhaustedError: OOM when allocating'),
      (str(folder / 'b.png'), 'OSError: [Errno 5] Input/output error')]
  assert input_failures.failure_message(report).startswith('error: 2 of 3 input(s) failed: ')
  # Anything else is a bug and stops the run rather than being reported as a bad input.
  media.write_image(str(folder / 'd.png'), np.full((8, 8, 3), 40, np.uint8))
  with pytest.raises(KeyError):
    unmix_files.unmix_inputs(unmixer, str(folder), str(tmp_path / 'out2'))


def _recording_unmixer(calls):
  """An Unmixer that appends each image to `calls` and returns it as both views."""

  def unmix(image):
    calls.append(image)
    return {'left': image, 'right': image,
            'disparity_left': np.zeros(image.shape[:2], np.float32)}

  return predictors.Unmixer(unmix, 'test', 'anaglyph', 8.0)


def test_results_into_the_input_folder_never_overwrite_an_input(tmp_path):
  calls = []
  unmixer = _recording_unmixer(calls)
  media.write_image(str(tmp_path / 'pic.png'), np.full((8, 8, 3), 10, np.uint8))
  media.write_image(str(tmp_path / 'pic_left.png'), np.full((8, 8, 3), 20, np.uint8))
  before = (tmp_path / 'pic_left.png').read_bytes()
  with pytest.raises(ValueError, match='pic_left.png'):
    unmix_files.unmix_inputs(unmixer, str(tmp_path), str(tmp_path))
  assert not calls and (tmp_path / 'pic_left.png').read_bytes() == before
  # Alone, pic.png writes its results beside itself (pic_left.png is no input then).
  report = unmix_files.unmix_inputs(unmixer, str(tmp_path / 'pic.png'), str(tmp_path))
  assert report.processed == 1 and len(calls) == 1


class _Killed(BaseException):
  """A kill between an input's results and its info file."""


def test_a_rerun_redoes_an_input_whose_results_a_kill_left_unlisted(tmp_path, monkeypatch):
  """Killed after writing pic's views but before its info: the views are no inputs of a
  rerun over the tree holding the output folder (refused as inputs its results could
  overwrite before); pic is unmixed again and its marker removed."""
  calls = []
  unmixer = _recording_unmixer(calls)
  media.write_image(str(tmp_path / 'pic.png'), np.full((8, 8, 3), 10, np.uint8))
  out = tmp_path / 'out'
  pattern = str(tmp_path / '**' / '*.png')
  assert unmix_files.unmix_inputs(unmixer, pattern, str(out)).processed == 1
  assert not list(out.glob('*unfinished*'))
  os.remove(out / 'pic_info.json')  # As if killed before the info was written.
  with pytest.raises(ValueError, match=r'holds the input .*pic_\w+\.png, which the outputs'):
    unmix_files.unmix_inputs(unmixer, pattern, str(out))
  shutil.rmtree(out)

  def killed(*args):
    raise _Killed()

  with monkeypatch.context() as patch, pytest.raises(_Killed):
    patch.setattr(info_file, 'write_info', killed)
    unmix_files.unmix_inputs(unmixer, pattern, str(out))
  assert (out / 'pic_left.png').exists() and (out / 'pic_unfinished.json').exists()
  report = unmix_files.unmix_inputs(unmixer, pattern, str(out))
  assert report.processed == 1 and not report.failures and len(calls) == 3
  assert (out / 'pic_info.json').exists() and not list(out.glob('*unfinished*'))


def test_stereo_formats_of_an_image_are_listed_in_its_info(tmp_path):
  setup = predictors.build_unmixer(predictors.PredictorConfig('classical', mixture='anaglyph'))
  _image(tmp_path / 'x.png', (24, 32, 3))
  options = media.OutputOptions('sbs', formats=stereo_formats.FORMAT_NAMES)
  report = unmix_files.unmix_inputs(setup, str(tmp_path / 'x.png'), str(tmp_path / 'out'),
                                    options)
  assert report.processed == 1 and not report.failures
  formats = ['x.mpo', 'x.jps', 'x_wiggle.gif', 'x_rgbd.png', 'x_viewer.html'] + [
      f'x_anaglyph_{n}.png' for n in ('dubois', 'optimized', 'gray', 'colour', 'red_blue')]
  info = json.loads((tmp_path / 'out' / 'x_info.json').read_text())
  assert info['files'][-len(formats):] == formats
  assert sorted(os.listdir(tmp_path / 'out')) == sorted(info['files'] + ['x_info.json'])


def _stereo_tags(path):
  """{'tag': the stream's stereo_mode tag, 'stream': its Stereo 3D side data type (Matroska's
  StereoMode), 'frame': whether the first frame has Stereo 3D side data (the SEI)}: by
  ffprobe when installed, else the tag alone by FFmpeg's libraries through PyAV."""
  if shutil.which('ffprobe') is None:
    print('ffprobe not installed (apt-get install ffmpeg): reading the tag with PyAV')
    with av.open(path) as container:
      return {'tag': container.streams.video[0].metadata.get('stereo_mode')}
  text = subprocess.run(['ffprobe', '-v', 'error', '-show_streams', '-show_frames',
                         '-read_intervals', '%+#1', '-of', 'json', path],
                        capture_output=True, text=True, check=True).stdout
  probe = json.loads(text)
  stream = probe['streams'][0]
  return {'tag': stream.get('tags', {}).get('stereo_mode'),
          'stream': [d.get('type') for d in stream.get('side_data_list', [])
                     if d.get('side_data_type') == 'Stereo 3D'],
          'frame': any(d.get('side_data_type') == 'Stereo 3D'
                       for d in probe['frames'][0].get('side_data_list', []))}


def test_side_by_side_video_is_tagged_and_draws_rgbd(tmp_path):
  source = _anaglyph_clip(tmp_path / 'clip.mkv', 'anaglyph', frames=4)
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      'classical', mixture='anaglyph', disparity_range=(0, 8)))
  report = unmix_files.unmix_inputs(unmixer, source, str(tmp_path / 'out'), media.OutputOptions(
      'sbs', formats=('wiggle', 'rgbd')))
  assert (report.processed, report.frames, report.failures) == (1, 4, [])
  info = json.loads((tmp_path / 'out' / 'clip_info.json').read_text())
  assert info['files'] == ['clip_sbs.mkv', 'clip_disparity.mkv', 'clip_rgbd.mkv']
  assert 'wiggle' in info['skipped_formats']
  # The Matroska StereoMode, and x264's frame-packing SEI (seen by ffprobe only).
  tags = _stereo_tags(str(tmp_path / 'out' / 'clip_sbs.mkv'))
  assert tags.pop('tag') == 'left_right'
  probed = shutil.which('ffprobe') is not None
  assert tags == ({'stream': ['side by side'], 'frame': True} if probed else {})
  plain = _stereo_tags(str(tmp_path / 'out' / 'clip_disparity.mkv'))
  assert plain == ({'tag': None, 'stream': [], 'frame': False} if probed else {'tag': None})
  _, frames = streams_test.read_all(tmp_path / 'out' / 'clip_rgbd.mkv')
  assert len(frames) == 4 and frames[0].image.shape == (64, 192, 3)
  depth = frames[0].image[:, 96:].astype(int)
  assert np.abs(depth[..., 0] - depth[..., 2]).max() <= 6  # Gray (after 4:2:0 chroma).


def test_warnings_while_an_input_runs_name_it(caplog):
  from absl import logging  # pylint: disable=import-outside-toplevel
  with caplog.at_level('WARNING'):
    with unmix_files.naming_input('scans/a.jpg'):
      logging.warning('Detected %s, the smallest encoding', 'half_color')
      logging.warning('%s: --output_format=mpo not written', 'scans/a.jpg')  # Named once.
    logging.warning('after it')
  assert [r.getMessage() for r in caplog.records] == [
      'scans/a.jpg: Detected half_color, the smallest encoding',
      'scans/a.jpg: --output_format=mpo not written', 'after it']
  caplog.clear()
  latin = os.fsdecode(b'scans/caf\xe9.jpg')  # A Latin-1 name: printed as \\xNN.
  with caplog.at_level('WARNING'):
    with unmix_files.naming_input(latin):
      logging.warning('%s: clipped', latin)
  assert [r.getMessage() for r in caplog.records] == ['scans/caf\\xe9.jpg: clipped']


def test_warnings_name_the_input_of_their_thread_while_several_run(caplog):
  """Beam's threads each run an input: every naming filter prefixed every warning, so a
  warning carried the other inputs' names too."""
  from absl import logging  # pylint: disable=import-outside-toplevel
  started, done = threading.Barrier(2), threading.Event()

  def run(path):
    with unmix_files.naming_input(path):
      started.wait()
      logging.warning('clipped')
      done.wait()
  threads = [threading.Thread(target=run, args=(f'{name}.jpg',)) for name in 'ab']
  with caplog.at_level('WARNING'):
    for thread in threads:
      thread.start()
    while len(caplog.records) < 2:
      time.sleep(0.01)
    other = threading.Thread(target=logging.warning, args=('from elsewhere',))
    other.start()
    other.join()
    done.set()
    for thread in threads:
      thread.join()
    with unmix_files.naming_input('c.jpg'):  # Alone: a helper thread's warning is named.
      helper = threading.Thread(target=logging.warning, args=('helper',))
      helper.start()
      helper.join()
  assert sorted(r.getMessage() for r in caplog.records) == [
      'a.jpg: clipped', 'b.jpg: clipped', 'c.jpg: helper', 'from elsewhere']


def test_a_line_that_names_its_input_is_not_named_after_another_threads(caplog):
  """Beam's thread whose input failed logged 'failed b.jpg: ...' after leaving it, while
  one other thread ran a.jpg: the line came out as 'a.jpg: failed b.jpg: ...'."""
  from absl import logging  # pylint: disable=import-outside-toplevel
  running, done = threading.Event(), threading.Event()

  def other():
    with unmix_files.naming_input('a.jpg'):
      running.set()
      done.wait()

  def worker():
    with unmix_files.naming_input('b.jpg'):
      pass
    running.wait()
    logging.error('failed %s: unreadable', 'b.jpg',
                  extra={unmix_files.NAMES_ITS_INPUT: True})  # As beam_batch logs it.
  threads = [threading.Thread(target=other), threading.Thread(target=worker)]
  with caplog.at_level('WARNING'):
    for thread in threads:
      thread.start()
    threads[1].join()
    done.set()
    threads[0].join()
  assert [r.getMessage() for r in caplog.records] == ['failed b.jpg: unreadable']


def test_a_cut_jpeg_that_fails_is_named_as_cut(tmp_path):
  image = np.random.RandomState(0).randint(0, 256, (40, 50, 3)).astype(np.uint8)
  cv2.imwrite(str(tmp_path / 'whole.jpg'), image)
  data = (tmp_path / 'whole.jpg').read_bytes()
  (tmp_path / 'cut.jpg').write_bytes(data[:len(data) * 2 // 3])  # Decodes, rows gray.

  def undetectable(image, **kwargs):
    raise ValueError('The encoding cannot be detected on it.')
  report = unmix_files.unmix_inputs(undetectable, str(tmp_path / '*.jpg'),
                                    str(tmp_path / 'out'))
  reasons = dict(report.failures)
  assert 'ends before its end marker' in reasons[str(tmp_path / 'cut.jpg')]
  assert 'end marker' not in reasons[str(tmp_path / 'whole.jpg')]


def test_a_full_output_disk_ends_the_run_instead_of_failing_every_input(setup, tmp_path,
                                                                        monkeypatch):
  """Writes failing on a full disk were recorded as bad inputs, one after the other."""
  for name in ('a.png', 'b.png'):
    _image(tmp_path / name)
  usage = shutil.disk_usage(tmp_path)

  def full(*args, **kwargs):
    raise OSError('4800 requested and 3040 written')  # NumPy's tofile on a full disk.
  monkeypatch.setattr(media, 'write_image_outputs', full)
  monkeypatch.setattr(input_failures.shutil, 'disk_usage', lambda path: usage._replace(free=4096))
  with pytest.raises(input_failures.OutputFull, match='is on a full disk .4096 bytes free'):
    unmix_files.unmix_inputs(setup, str(tmp_path / '*.png'), str(tmp_path / 'out'))
  monkeypatch.setattr(input_failures.shutil, 'disk_usage', lambda path: usage)  # Room: per input.
  report = unmix_files.unmix_inputs(setup, str(tmp_path / '*.png'), str(tmp_path / 'out'))
  assert len(report.failures) == 2 and 'requested' in report.failures[0][1]


@pytest.mark.parametrize('error', [
    OSError(errno.EDQUOT, os.strerror(errno.EDQUOT), 'out/a_left.png'),
    OSError(errno.EROFS, os.strerror(errno.EROFS)),
    av.error.OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), 'out/clip.mkv'),  # PyAV's.
    ValueError('out/a_left.png: ' + os.strerror(errno.EDQUOT)),  # By its text.
])
def test_a_quota_or_read_only_output_ends_the_run_with_room_left(setup, tmp_path,
                                                                 monkeypatch, error):
  """Write errors that every later input meets, with more than a MiB free (a quota, a
  disk remounted read-only), were recorded as bad inputs one after the other, each
  after its unmixing."""
  for name in ('a.png', 'b.png'):
    _image(tmp_path / name)
  calls = []

  def refused(*args, **kwargs):
    calls.append(args)
    raise error
  monkeypatch.setattr(media, 'write_image_outputs', refused)
  reason = os.strerror(getattr(error, 'errno', None) or errno.EDQUOT)
  with pytest.raises(input_failures.OutputFull, match=reason):
    unmix_files.unmix_inputs(setup, str(tmp_path / '*.png'), str(tmp_path / 'out'))
  assert len(calls) == 1


def test_other_write_errors_stay_the_inputs_own(setup, tmp_path, monkeypatch):
  _image(tmp_path / 'a.png')

  def too_large(*args, **kwargs):
    raise OSError(errno.EFBIG, os.strerror(errno.EFBIG))  # One file over a FAT32 limit.
  monkeypatch.setattr(media, 'write_image_outputs', too_large)
  report = unmix_files.unmix_inputs(setup, str(tmp_path / '*.png'), str(tmp_path / 'out'))
  assert len(report.failures) == 1 and 'too large' in report.failures[0][1]


def test_a_multi_page_tiff_says_in_its_info_that_only_its_first_page_was_unmixed(setup,
                                                                                  tmp_path):
  pages = [Image.fromarray(_image(tmp_path / f'{seed}.png', seed=seed)) for seed in (0, 1)]
  pages[0].save(tmp_path / 'scans.tif', save_all=True, append_images=pages[1:])
  report = unmix_files.unmix_inputs(setup, str(tmp_path / 'scans.tif'), str(tmp_path / 'out'))
  assert report.processed == 1
  info = json.loads((tmp_path / 'out' / 'scans_info.json').read_text())
  assert info['warning'] == 'the file holds 2 pages: only the first was unmixed'
