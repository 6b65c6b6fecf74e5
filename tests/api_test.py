"""Tests for the public face, `mixstereo_tf.unmix` (mixstereo_tf/__init__.py)."""

import dataclasses
import inspect
import json
import os
import subprocess
import sys

import cv2
import numpy as np
import PIL.Image
import pytest
import skimage.data

import mixstereo_tf
from mixstereo_tf.cli import media
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.unmixing import predictors
from tests.unmixing import predictors_test


@pytest.fixture(scope='module')
def anaglyph():
  """A published-style gray anaglyph of Middlebury's Motorcycle at half size (370 x 250)
  and the median of its true disparity at that size."""
  left, right, truth = skimage.data.stereo_motorcycle()
  left, right = (cv2.resize(v, (370, 250), interpolation=cv2.INTER_AREA) for v in (left, right))
  mixed = mixtures.mix('gray', image_range.u8_to_signed(left), image_range.u8_to_signed(right))
  return image_range.signed_to_u8(mixed.numpy()), np.median(truth[np.isfinite(truth)]) / 2


def _check_known_answer(result, truth_median, method):
  assert result.left.shape == result.right.shape == (250, 370, 3)
  assert result.left.dtype == result.right.dtype == np.uint8
  assert result.disparity.shape == result.disparity_right.shape == (250, 370)
  assert result.disparity.dtype == np.float32
  assert result.info['mixture'] == result.info['detected'] == 'gray'
  assert result.info['method'] == method and len(result.info['disparity_range']) == 2
  assert np.median(result.disparity) == pytest.approx(truth_median, abs=1.5)
  with pytest.raises(dataclasses.FrozenInstanceError):
    result.left = None


def test_classical_method_detects_the_encoding(anaglyph):
  image, truth_median = anaglyph
  result = mixstereo_tf.unmix(image, method='classical')
  _check_known_answer(result, truth_median, 'classical')


def test_default_shipped_model(anaglyph):
  image, truth_median = anaglyph
  result = mixstereo_tf.unmix(image)
  _check_known_answer(result, truth_median, 'model')
  assert result.info['pretrained'] == 'anaglyph_matching'  # The default (info.json).


def test_path_and_gray_inputs(anaglyph, tmp_path):
  image = anaglyph[0][:64, 150:230]
  media.write_image(str(tmp_path / 'photo.png'), image)
  direct = mixstereo_tf.unmix(image, method='classical')
  for path in (str(tmp_path / 'photo.png'), tmp_path / 'photo.png',
               str(tmp_path / 'photo.png').encode()):
    read = mixstereo_tf.unmix(path, method='classical')
    np.testing.assert_array_equal(read.disparity, direct.disparity)
    np.testing.assert_array_equal(read.left, direct.left)
  gray = image[:, :, 1]  # [H, W]: the same as its RGB replica.
  options = dict(mixture='gray', method='classical', disparity_range='0,8')
  from_gray = mixstereo_tf.unmix(gray, **options)
  from_rgb = mixstereo_tf.unmix(np.repeat(gray[:, :, None], 3, axis=2), **options)
  assert from_gray.left.shape == (64, 80, 3) and from_gray.disparity.shape == (64, 80)
  np.testing.assert_array_equal(from_gray.disparity, from_rgb.disparity)
  assert from_gray.info['disparity_range'] == [0, 8]
  # A PIL image: a palette image as its colours, turned upright like a file (EXIF 6).
  palette = PIL.Image.fromarray(image).convert('P', palette=PIL.Image.ADAPTIVE, colors=256)
  stored = np.asarray(palette.convert('RGB'))
  exif = palette.getexif()
  exif[0x0112] = 6
  palette.save(tmp_path / 'turned.png', exif=exif)
  turned = mixstereo_tf.unmix(PIL.Image.open(tmp_path / 'turned.png'), **options)
  np.testing.assert_array_equal(turned.left, mixstereo_tf.unmix(np.rot90(stored, -1),
                                                                **options).left)


def test_a_photo_that_is_no_anaglyph_names_the_keyword():
  photo = cv2.resize(skimage.data.coffee(), (75, 50), interpolation=cv2.INTER_AREA)
  with pytest.raises(ValueError, match=r'mixture=diplopia') as raised:
    mixstereo_tf.unmix(photo)
  assert 'mixture=' in str(raised.value) and 'PredictorConfig' not in str(raised.value)


@pytest.mark.parametrize('keywords, message', [
    (dict(method='classical', mixture=None), "method='classical' needs mixture= "),
    (dict(model='anaglyph', checkpoint='run'), 'model= excludes checkpoint= and saved_model='),
    (dict(method='oracle'), "method='oracle' needs the clean stereo pair"),
    (dict(disparity_range='5,5'), "disparity_range='5,5': disparity range needs MIN < MAX"),
    (dict(method='classical', disparity_range=(5, 5)),
     'disparity_range=(5, 5): disparity range needs MIN < MAX'),
    (dict(disparity_range=(1, 2, 3)), 'disparity_range=(1, 2, 3): disparity range must be'),
    (dict(disparity_range=5), 'disparity_range=5: '),
    (dict(disparity_range=('a', 'b')), "disparity_range=('a', 'b'): disparity range must be"),
    (dict(max_network_pixels='big'), 'max_network_pixels= must be a whole number'),
    (dict(restore_colour='no'), 'restore_colour= must be None, True or False'),
    (dict(method='classical', mixture='diplopia', mixing_weight=1.0),
     "mixing_weight= must be None, 'auto' or a number in (0, 1)"),
    (dict(mixture='bogus'), "mixture='bogus': Unknown mixture"),
    (dict(model='nonexistent'), "model='nonexistent': No pretrained model"),
    (dict(checkpoint='/nonexistent'), "checkpoint='/nonexistent': /nonexistent is neither"),
    (dict(saved_model='/nonexistent'), "saved_model='/nonexistent': No SavedModel"),
])
def test_bad_keywords_are_named(keywords, message):
  with pytest.raises(ValueError) as raised:
    mixstereo_tf.unmix(np.zeros((8, 8, 3), np.uint8), **keywords)
  assert message in str(raised.value) and 'Config' not in str(raised.value)


def test_a_pair_of_fractional_bounds_widens_as_on_the_command_line(anaglyph):
  out = mixstereo_tf.unmix(anaglyph[0], method='classical', disparity_range=(1.7, 8.2))
  assert out.info['disparity_range'] == [1, 9]


def test_a_heic_path_is_read_as_the_cli_reads_it(anaglyph, tmp_path):
  """A phone's HEIC (pillow-heif): read, detected and matched at colour resolution."""
  image = anaglyph[0][:64, 150:230]
  PIL.Image.fromarray(image).save(tmp_path / 'phone.heic', quality=100)
  read = mixstereo_tf.unmix(str(tmp_path / 'phone.heic'), method='classical')
  assert read.left.shape == image.shape and read.info['mixture'] == 'gray'  # As drawn.
  assert read.info['matched_at_colour_resolution']


def test_a_folder_is_no_image_file(tmp_path):
  with pytest.raises(ValueError, match='is a folder, not an image file'):
    mixstereo_tf.unmix(str(tmp_path))


def test_a_video_or_an_array_that_is_not_uint8_is_named(tmp_path):
  with pytest.raises(ValueError, match=r'image=.*clip.MP4 is a video; .*mixstereo-unmix'):
    mixstereo_tf.unmix(str(tmp_path / 'clip.MP4'), method='classical', mixture='gray')
  for dtype in (np.float32, np.int32, bool):
    with pytest.raises(ValueError, match=f'image= must be a uint8 array .*got {np.dtype(dtype)}'):
      mixstereo_tf.unmix(np.zeros((20, 20, 3), dtype), method='classical', mixture='gray')
  for shape in ((0, 20, 3), (20, 0), (20, 20, 2), (5, 20, 20, 3)):  # Was ZeroDivisionError.
    with pytest.raises(ValueError, match=r'image= must be a \[H, W, 3\] RGB .*got shape'):
      mixstereo_tf.unmix(np.zeros(shape, np.uint8), method='classical', mixture='gray')
  contents = b'\x89PNG\r\n\x1a\n\0' + bytes(50)  # A file's contents, not its path.
  with pytest.raises(ValueError, match="image= is 59 bytes that name no file .*contents"):
    mixstereo_tf.unmix(contents, method='classical', mixture='gray')


def test_defaults_are_the_predictor_configs():
  parameters = inspect.signature(mixstereo_tf.unmix).parameters
  defaults = predictors.PredictorConfig()
  for field in dataclasses.fields(predictors.PredictorConfig):
    default = parameters['model' if field.name == 'pretrained' else field.name].default
    if field.name not in ('mixture', 'descreen', 'rectify') and default is not ...:
      assert default == getattr(defaults, field.name), field.name
  assert parameters['mixture'].default == 'auto'
  for name in ('descreen', 'rectify'):  # As the tools', not the paper's 'off'.
    assert parameters[name].default == 'auto' and getattr(defaults, name) == 'off', name


def test_importing_the_package_loads_no_tensorflow():
  code = 'import sys, mixstereo_tf; print(sorted(m for m in sys.modules if "tensorflow" in m))'
  result = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          timeout=60, check=True)
  assert result.stdout.strip() == '[]'


def test_the_first_call_prints_no_tensorflow_start_up_lines():
  code = ('import numpy as np, mixstereo_tf\n'
          'image = np.random.default_rng(0).integers(0, 256, (40, 64, 3), dtype=np.uint8)\n'
          'mixstereo_tf.unmix(image, mixture="anaglyph", method="classical")\n'
          'import tensorflow as tf; tf.constant(1.0) + 1.0\n')  # An op: no cuInit error.
  env = {k: v for k, v in os.environ.items() if k != 'TF_CPP_MIN_LOG_LEVEL'}
  result = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          timeout=300, check=True, env=env)
  assert result.stderr == ''  # Was: oneDNN and CUDA-driver notes, a cuInit error.


def test_image_kinds_read_as_files_are_and_wrong_kinds_are_refused(tmp_path):
  gray16 = np.arange(0, 65536, 257, dtype=np.uint16).reshape(16, 16)
  PIL.Image.fromarray(gray16).save(tmp_path / 'g16.png')
  from_file = mixstereo_tf._image(str(tmp_path / 'g16.png'))  # pylint: disable=protected-access
  with PIL.Image.open(tmp_path / 'g16.png') as opened:
    assert opened.mode in ('I;16', 'I')
    from_pil = mixstereo_tf._image(opened)  # pylint: disable=protected-access
  np.testing.assert_array_equal(from_pil, from_file)  # 16 bits kept, as RGB.
  assert from_pil.dtype == np.uint16 and from_pil.shape == (16, 16, 3)
  assert from_pil[0, 1].tolist() == [257] * 3 and from_pil[-1, -1].tolist() == [65535] * 3
  with pytest.raises(ValueError, match=r"floating-point PIL image \(mode 'F'\)"):
    mixstereo_tf._image(PIL.Image.fromarray(np.zeros((4, 4), np.float32)))  # pylint: disable=protected-access
  rgba = np.random.default_rng(0).integers(0, 256, (6, 8, 4), dtype=np.uint8)
  np.testing.assert_array_equal(mixstereo_tf._image(rgba), rgba[..., :3])  # pylint: disable=protected-access
  with pytest.raises(ValueError, match=r'OpenCV decodes to BGR'):
    mixstereo_tf.unmix(b'\x89PNG\r\n\x1a\n\0' * 10)
  with pytest.raises(ValueError, match=r"disparity_range=5: give \(MIN, MAX\)"):
    mixstereo_tf.unmix(rgba, disparity_range=5)
  with pytest.raises(ValueError, match=r'mixing_weight= applies to the classical method and '
                                       'the shipped models'):
    mixstereo_tf.unmix(rgba, mixture='diplopia', checkpoint=tmp_path, mixing_weight=0.3)


def test_a_path_object_of_a_checkpoint_reads_back_as_text_in_the_info(tmp_path):
  path = tmp_path / 'run'
  predictors_test.make_run_dir(str(path))
  image = np.random.default_rng(1).integers(0, 256, (32, 64, 3), dtype=np.uint8)
  result = mixstereo_tf.unmix(image, mixture='anaglyph', checkpoint=path,
                              disparity_range=(0, 7))
  assert json.loads(json.dumps(result.info))['checkpoint'] == str(path)


def test_max_network_pixels_for_a_method_without_a_network_is_refused():
  with pytest.raises(ValueError, match=r"max_network_pixels= applies to method='model'"):
    mixstereo_tf.unmix(np.zeros((8, 8, 3), np.uint8), method='classical', mixture='anaglyph',
                       max_network_pixels=1000)


def test_a_16_bit_anaglyph_gives_16_bit_views_holding_its_samples(tmp_path):
  """An array or a 16-bit PNG: the views' copied channels are the input's own samples."""
  rng = np.random.default_rng(1)
  left = rng.integers(0, 65536, (40, 64, 3)).astype(np.uint16)
  image = np.concatenate([left[..., :1], np.roll(left, -3, axis=1)[..., 1:]], -1)
  cv2.imwrite(str(tmp_path / 'scan.png'), image[..., ::-1])
  for given in (image, str(tmp_path / 'scan.png')):
    result = mixstereo_tf.unmix(given, method='classical', mixture='anaglyph')
    assert result.left.dtype == result.right.dtype == np.uint16
    np.testing.assert_array_equal(result.left[..., 0], image[..., 0])
    np.testing.assert_array_equal(result.right[..., 1:], image[..., 1:])
