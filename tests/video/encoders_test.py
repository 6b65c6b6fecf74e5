"""Tests for mixstereo_tf.video.encoders: the encoder of each container and its stereo tag."""

import pytest

from mixstereo_tf.video import encoders


def test_each_extension_has_its_encoder_and_others_are_refused_by_name():
  assert encoders.encoder_for('a.MP4').codec == 'libx264'
  assert encoders.encoder_for('a.avi').codec == 'mjpeg'
  with pytest.raises(ValueError, match=r'Cannot write video clip\.webm: extension must be'):
    encoders.encoder_for('clip.webm')


def test_stereo_modes_add_x264_frame_packing_only():
  plain = encoders.encoder_for('a.mp4')
  tagged = encoders.encoder_for('a.mp4', 'top_bottom')
  assert dict(tagged.options)['x264-params'] == dict(plain.options)['x264-params'] + (
      ':frame-packing=4')
  assert dict(encoders.encoder_for('a.mkv', 'left_right').options)['x264-params'].endswith(
      'frame-packing=3')
  assert encoders.encoder_for('a.avi', 'left_right') == encoders.encoder_for('a.avi')


def test_frames_of_more_than_8_bits_get_h264_high_10_with_its_stereo_tag():
  for path in ('a.mp4', 'a.MOV', 'a.mkv'):
    deep = encoders.encoder_for(path, 'left_right', bits=10)
    assert (deep.codec, deep.pix_fmt, deep.bits) == ('libx264', 'yuv420p10le', 10)
    assert dict(deep.options)['x264-params'].endswith('frame-packing=3')
  assert encoders.encoder_for('a.mp4').bits == 8
  assert encoders.encoder_for('a.avi', bits=10) == encoders.encoder_for('a.avi')
