"""Tests for mixstereo_tf.core.image_range: the value-range conversions, NumPy and TF alike."""

import numpy as np
import pytest
import tensorflow as tf

from mixstereo_tf.core import image_range

_U8 = np.array([0, 1, 127, 128, 254, 255], np.uint8)


def test_uint8_to_float_ranges():
  np.testing.assert_allclose(image_range.u8_to_unit(_U8), _U8 / 255.0, rtol=1e-6)
  np.testing.assert_allclose(image_range.u8_to_signed(_U8), _U8 / 127.5 - 1.0, atol=1e-6)
  assert image_range.u8_to_signed(_U8).dtype == np.float32
  np.testing.assert_array_equal(image_range.u8_to_signed(tf.constant(_U8)).numpy(),
                                image_range.u8_to_signed(_U8))
  np.testing.assert_array_equal(image_range.u8_to_unit(tf.constant(_U8)).numpy(),
                                image_range.u8_to_unit(_U8))


def test_round_trips_are_exact_for_uint8():
  for convert in (tf.constant, np.asarray):
    signed = image_range.u8_to_signed(convert(_U8))
    np.testing.assert_array_equal(np.asarray(image_range.signed_to_u8(signed)), _U8)
    unit = image_range.u8_to_unit(convert(_U8))
    np.testing.assert_array_equal(np.asarray(image_range.unit_to_u8(unit)), _U8)
    np.testing.assert_allclose(np.asarray(image_range.signed_to_unit(signed)),
                               np.asarray(unit), atol=1e-6)


def test_to_uint8_rounds_and_clips():
  values = np.array([-1.5, -1.0, 0.0, 1.0 / 255, 1.0, 2.0])
  # (x + 1) * 127.5: -63.75, 0, 127.5 (half to even: 128), ~128.0, 255, 382.5.
  np.testing.assert_array_equal(image_range.signed_to_u8(values), [0, 0, 128, 128, 255, 255])
  np.testing.assert_array_equal(image_range.signed_to_u8(tf.constant(values)).numpy(),
                                [0, 0, 128, 128, 255, 255])
  np.testing.assert_array_equal(image_range.unit_to_u8(np.array([-0.1, 0.5, 1.2])),
                                [0, 128, 255])
  np.testing.assert_allclose(image_range.unit_to_signed(np.array([0.0, 0.5, 1.0])),
                             [-1.0, 0.0, 1.0])


def test_as_unit_float_checks_the_image():
  np.testing.assert_allclose(image_range.as_unit_float(np.full((2, 2, 3), 255, np.uint8)), 1.0)
  with pytest.raises(ValueError, match='mixture must be an RGB image'):
    image_range.as_unit_float(np.zeros((2, 2)), 'mixture')
  with pytest.raises(ValueError, match='in \\[0, 1\\]'):
    image_range.as_unit_float(np.full((2, 2, 3), 2.0))
  np.testing.assert_allclose(
      image_range.as_unit_float(np.full((2, 2, 3), 65535, np.uint16)), 1.0)
  with pytest.raises(ValueError, match='uint8, uint16 or float'):
    image_range.as_unit_float(np.zeros((2, 2, 3), np.int32))


def test_16_bit_samples_convert_to_unit_to_8_bits_and_back():
  values = np.array([0, 1, 128, 129, 257, 32896, 65278, 65535], np.uint16)
  np.testing.assert_array_equal(image_range.eight_bits(values), [0, 0, 0, 1, 1, 128, 254, 255])
  np.testing.assert_allclose(image_range.to_unit(values), values / 65535.0, rtol=1e-6)
  np.testing.assert_array_equal(image_range.unit_to(image_range.to_unit(values), np.uint16),
                                values)
  np.testing.assert_array_equal(image_range.unit_to(np.array([-0.1, 0.5, 1.2]), np.uint16),
                                [0, 32768, 65535])
  eight = np.array([0, 7, 255], np.uint8)
  assert image_range.eight_bits(eight).dtype == np.uint8
  np.testing.assert_array_equal(image_range.unit_to(image_range.to_unit(eight), np.uint8), eight)
