"""Tests for mixstereo_tf.video.streams: decoding, encoding, remuxing with the audio copied."""

import fractions
import subprocess

import av
import cv2
import imageio_ffmpeg
import numpy as np
import pytest

from mixstereo_tf.video import assembly
from mixstereo_tf.video import encoders
from mixstereo_tf.video import streams

Fraction = fractions.Fraction
# Lossless audio where the container takes it, AAC in MP4 (its decoded samples compare
# exactly too when the packets are copied).
AUDIO = {'.mp4': 'aac', '.mov': 'pcm_s16le', '.mkv': 'flac', '.avi': 'pcm_s16le',
         '.webm': 'libopus', '.ts': 'mp2'}


def pattern(index, height=64, width=96):
  """A moving colour pattern: frame `index` of a test clip, uint8 RGB."""
  y, x = np.mgrid[:height, :width]
  return np.stack([(x * 8 + index * 5) % 256, (y * 6 + index * 3) % 256,
                   ((x + y) * 4) % 256], -1).astype(np.uint8)


def make_video(path, frames, rate=Fraction(12), audio_rate=48000, rotation=0, tags=None,
               aspect=None):
  """Writes frames (uint8 RGB) with a 440 Hz sine as mono audio (codec from AUDIO) using
  PyAV directly, independently of the writer under test; `tags`: container tags, and the
  audio's language 'fra'; `aspect`: the sample aspect ratio. Returns the path."""
  extension = str(path)[str(path).rfind('.'):]
  with av.open(str(path), 'w') as out:
    codec = {'.avi': 'mjpeg', '.webm': 'libvpx-vp9'}.get(extension, 'libx264')
    options = {'qmin': '1', 'qmax': '2'} if codec == 'mjpeg' else {'crf': '12'}
    video = out.add_stream(codec, rate=rate, options=options)
    video.height, video.width = frames[0].shape[:2]
    video.pix_fmt = 'yuvj420p' if codec == 'mjpeg' else 'yuv420p'
    if rotation:
      video.set_display_rotation(rotation)
    audio = out.add_stream(AUDIO[extension], rate=audio_rate, layout='mono')
    if tags:
      out.metadata.update(tags)
      audio.metadata['language'] = 'fra'
    if aspect:
      video.codec_context.sample_aspect_ratio = aspect
    for index, image in enumerate(frames):
      frame = av.VideoFrame.from_ndarray(image, format='rgb24')
      frame.pts = index
      out.mux(video.encode(frame))
    samples = int(audio_rate * len(frames) / rate)
    sine = 0.3 * np.sin(2 * np.pi * 440 * np.arange(samples) / audio_rate)
    planar = audio.codec_context.format.name == 'fltp'
    block = audio.codec_context.frame_size or 1024
    for start in range(0, samples, block):
      chunk = sine[start:start + block]
      chunk = chunk.astype(np.float32) if planar else (chunk * 32767).astype(np.int16)
      frame = av.AudioFrame.from_ndarray(chunk[None], format='fltp' if planar else 's16',
                                         layout='mono')
      frame.sample_rate, frame.pts = audio_rate, start
      out.mux(audio.encode(frame))
    out.mux(video.encode(None))
    out.mux(audio.encode(None))
  return str(path)


def audio_samples(path):
  """All decoded samples of a file's first audio stream, [channels, samples]."""
  with av.open(str(path)) as container:
    return np.concatenate([f.to_ndarray() for f in container.decode(audio=0)], axis=1)


def read_all(path, upright=True):
  """(VideoInfo, [Frame]) of a whole video."""
  info, frames = streams.open_video(str(path), upright=upright)
  return info, list(frames)


@pytest.mark.parametrize('extension', ['.mp4', '.mkv', '.avi'])
def test_parts_assembled_keep_rate_timestamps_and_audio(tmp_path, extension):
  source = make_video(tmp_path / f'in{extension}', [pattern(i) for i in range(20)])
  info, frames = read_all(source)
  assert (info.width, info.height, info.frame_rate, info.audio_streams) == (96, 64, 12, 1)
  assert info.frame_count in (20, None) and info.rotation == 0 and len(frames) == 20
  # Decoded close to what was encoded (crf 12, or MJPEG), RGB order kept.
  assert float(np.abs(frames[7].image.astype(int) - pattern(7)).mean()) < 6
  # Two parts, each timed from 0 and shifted by its first frame's time.
  parts = []
  for first in (0, 8):
    part = str(tmp_path / f'part{first}.mov')
    with streams.VideoWriter(part, info.frame_rate, info.time_base,
                              encoders.encoder_for(source)) as writer:
      for frame in frames[first:first + (8 if first == 0 else 12)]:
        writer.write(frame.image, frame.time - frames[first].time)
    parts.append(assembly.Part(part, frames[first].time))
  output = str(tmp_path / f'out{extension}')
  assembly.assemble(parts, output, info.frame_rate, info.time_base, audio_source=source)
  out_info, out_frames = read_all(output)
  assert out_info.frame_rate == info.frame_rate and len(out_frames) == 20
  assert [f.time for f in out_frames] == [f.time for f in frames]
  assert [f.time for f in frames[:3]] == [0, Fraction(1, 12), Fraction(1, 6)] or (
      extension == '.mkv')  # Matroska counts milliseconds: 0, 83/1000, 167/1000.
  # Re-encoded once more (4:2:0 blurs the pattern's colour stripes a little).
  errors = [np.abs(a.image.astype(int) - b.image).mean() for a, b in zip(frames, out_frames)]
  assert max(errors) < 5, errors
  np.testing.assert_array_equal(audio_samples(output), audio_samples(source))
  assert audio_samples(source).shape[1] >= 20 * 4000  # 48 kHz for 20 frames at 12 fps.


def test_a_short_last_part_with_wider_spaced_frames_assembles(tmp_path):
  """Its encoder's decode times reach back over the previous part's (a cut or
  variable-rate video's last segment): the muxer refused them ('returned 22')."""
  source = make_video(tmp_path / 'in.mp4', [pattern(i) for i in range(20)])
  info, frames = read_all(source)
  parts = []
  for first, times in ((0, [Fraction(i, 12) for i in range(10)]),
                       (10, [Fraction(2 * i, 12) for i in range(3)])):
    part = str(tmp_path / f'part{first}.mov')
    with streams.VideoWriter(part, info.frame_rate, info.time_base,
                              encoders.encoder_for(source)) as writer:
      for index, time in enumerate(times):
        writer.write(frames[first + index].image, time)
    parts.append(assembly.Part(part, frames[first].time))
  output = str(tmp_path / 'out.mp4')
  assembly.assemble(parts, output, info.frame_rate, info.time_base, audio_source=source)
  _, out_frames = read_all(output)
  assert [f.time for f in out_frames] == [Fraction(i, 12) for i in range(10)] + [
      Fraction(10 + 2 * i, 12) for i in range(3)]


def _with_subtitles(path, output, tags):
  """`path` remuxed into `output` with a subtitle stream (language 'deu', cues 'Hallo' at
  0-0.2 s and 'Welt' at 0.2-0.3 s; MP4: mov_text, Matroska: SubRip) by FFmpeg, and the
  container `tags` set again (FFmpeg's remux drops an MP4's creation_time)."""
  srt = str(output) + '.srt'
  with open(srt, 'w', encoding='utf-8') as f:
    f.write('1\n00:00:00,000 --> 00:00:00,200\nHallo\n\n'
            '2\n00:00:00,200 --> 00:00:00,300\nWelt\n')
  codec = 'mov_text' if str(output).endswith('.mp4') else 'srt'
  subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), '-loglevel', 'error', '-i', str(path),
                  '-i', srt, '-map', '0', '-map', '1', '-c', 'copy', '-c:s', codec,
                  '-metadata:s:s:0', 'language=deu'] +
                 [arg for k, v in tags.items() for arg in ('-metadata', f'{k}={v}')] +
                 [str(output)], check=True)
  return str(output)


def _subtitle_texts(path):
  """{'language', 'texts'} of a file's first subtitle stream, texts in order."""
  with av.open(str(path)) as container:
    stream = container.streams.subtitles[0]
    texts = [bytes(packet).decode('utf-8', 'replace')
             for packet in container.demux(stream) if packet.size]
  return stream.metadata.get('language'), texts


@pytest.mark.parametrize('extension', ['.mp4', '.mkv'])
def test_assembly_keeps_the_sources_tags_audio_language_aspect_and_subtitles(tmp_path,
                                                                              extension):
  tags = {'title': 'Holiday', 'creation_time': '2020-05-01T10:00:00.000000Z'}
  source = _with_subtitles(make_video(tmp_path / f'plain{extension}',
                                      [pattern(i) for i in range(4)], tags=tags,
                                      aspect=Fraction(4, 3)), tmp_path / f'in{extension}',
                           tags)
  info, frames = read_all(source)
  assert info.aspect == Fraction(4, 3)
  part = str(tmp_path / 'part.mov')
  with streams.VideoWriter(part, info.frame_rate, info.time_base,
                            encoders.encoder_for(source), info.aspect) as writer:
    for frame in frames:
      writer.write(frame.image, frame.time)
  output = str(tmp_path / f'out{extension}')
  assembly.assemble([assembly.Part(part, frames[0].time)], output, info.frame_rate,
                    info.time_base, audio_source=source)
  with av.open(output) as out:
    assert out.metadata.get('title') == 'Holiday'
    assert out.metadata.get('creation_time', '').startswith('2020-05-01')
    assert out.streams.audio[0].metadata.get('language') == 'fra'
    assert out.streams.video[0].sample_aspect_ratio == Fraction(4, 3)
  language, texts = _subtitle_texts(output)
  assert language == 'deu' and len(texts) == 2  # (MP4's cues carry a length prefix.)
  assert texts[0].endswith('Hallo') and texts[1].endswith('Welt')
  assert (language, texts) == _subtitle_texts(source)  # Packets copied unchanged.


@pytest.mark.parametrize('extension', ['.mp4', '.avi'])
def test_writer_tags_the_matrix_it_uses_and_passes_primaries_on(tmp_path, extension):
  """Untagged 4:2:0 is read as BT.709 by players at HD sizes, where FFmpeg's default RGB
  conversion wrote BT.601 (green 255 showed as 215): the pixels must match their tags."""
  bars = np.zeros((32, 128, 3), np.uint8)
  for i, colour in enumerate([(255, 0, 0), (0, 255, 0), (0, 0, 255), (255, 255, 0),
                              (0, 255, 255), (255, 0, 255), (128, 64, 32), (200, 200, 200)]):
    bars[:, 16 * i:16 * (i + 1)] = colour
  path = str(tmp_path / f'bars{extension}')
  settings = encoders.encoder_for(path)
  with streams.VideoWriter(path, Fraction(10), colour=(1, 1)) as writer:
    for index in range(2):
      writer.write(bars, Fraction(index, 10))
  with av.open(path) as container:
    context = container.streams.video[0].codec_context
    assert (context.colorspace, context.color_range) == (settings.matrix,
                                                         settings.color_range)
    frame = next(container.decode(video=0))
    as_tagged = frame.to_ndarray(format='rgb24')
    assumed = frame.reformat(format='rgb24', src_colorspace='ITU709' if extension == '.mp4'
                             else 'ITU601').to_ndarray()  # What players assume untagged.
  for decoded in (as_tagged, assumed):
    assert np.abs(decoded[:, 2:-2].astype(int) - bars[:, 2:-2]).max() <= 4
  info, _ = read_all(path)
  assert info.colour == ((1, 1) if extension == '.mp4' else (2, 2))  # AVI holds no tags.


def test_exact_ntsc_rate_odd_size_and_rotation(tmp_path):
  rate = Fraction(30000, 1001)
  source = make_video(tmp_path / 'in.mp4', [pattern(i, 34, 48) for i in range(6)], rate,
                      rotation=90)
  info, frames = read_all(source, upright=False)
  assert info.frame_rate == rate and info.rotation == 90 and info.turned == 0
  part = str(tmp_path / 'part.mp4')
  with streams.VideoWriter(part, rate, info.time_base) as writer:
    for frame in frames:
      odd = frame.image[:33, :47].copy()  # Odd size: padded by edge replication.
      odd[32] = odd[:, 46] = 255
      writer.write(odd, frame.time)
  assembly.assemble([assembly.Part(part)], str(tmp_path / 'out.mp4'), rate, info.time_base,
                    rotation=info.rotation)
  out_info, out_frames = read_all(tmp_path / 'out.mp4', upright=False)
  assert out_info.frame_rate == rate and out_info.rotation == 90
  assert (out_info.height, out_info.width, out_info.audio_streams) == (34, 48, 0)
  assert [f.time for f in out_frames] == [Fraction(i * 1001, 30000) for i in range(6)]
  assert out_frames[2].image[33].min() > 220 and out_frames[2].image[:, 47].min() > 220


def test_a_rotation_of_no_quarter_turn_is_read_and_kept_to_the_degree(tmp_path):
  """A 30-degree display matrix (29.9996 in 16.16 fixed point) read 29 through PyAV's
  truncating `rotation`, and each pass through the tool lost a degree."""
  source = make_video(tmp_path / 'in.mp4', [pattern(i) for i in range(2)], rotation=30)
  info, frames = read_all(source)
  assert info.rotation == 30 and info.turned == 0  # Not a quarter turn: passed on.
  part = str(tmp_path / 'part.mp4')
  with streams.VideoWriter(part, info.frame_rate, info.time_base) as writer:
    for frame in frames:
      writer.write(frame.image, frame.time)
  assembly.assemble([assembly.Part(part)], str(tmp_path / 'out.mp4'), info.frame_rate,
                    info.time_base, rotation=info.rotation)
  assert read_all(tmp_path / 'out.mp4')[0].rotation == 30


@pytest.mark.parametrize('degrees', [90, -90, 180])
def test_frames_come_upright_as_ffmpeg_shows_them(tmp_path, degrees):
  """A display matrix of quarter turns (a phone filming in portrait): the frames arrive as
  FFmpeg's own command line shows them (its autorotation, an independent reference)."""
  frames = [pattern(i, 34, 48) for i in range(3)]
  for image in frames:
    image[:6, :6] = 255  # A corner mark: any wrong turn or mirror moves it.
  source = make_video(tmp_path / 'in.mp4', frames, rotation=degrees)
  info, got = read_all(source)
  shown = str(tmp_path / 'shown.png')
  subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), '-loglevel', 'error', '-i', source,
                  '-frames:v', '1', shown], check=True)
  reference = cv2.imread(shown)[..., ::-1]
  assert (info.height, info.width) == reference.shape[:2] == got[0].image.shape[:2]
  assert info.turned == degrees and info.rotation == 0
  assert np.abs(got[0].image.astype(int) - reference).mean() < 4
  assert (info.width, info.height) == ((34, 48) if degrees % 180 else (48, 34))


def test_writer_keeps_timestamps_increasing_and_one_size(tmp_path):
  path = str(tmp_path / 'v.mkv')
  with streams.VideoWriter(path, Fraction(10)) as writer:
    writer.write(pattern(0), Fraction(0))
    writer.write(pattern(1), Fraction(0))  # Same time: moved one tick on.
    with pytest.raises(ValueError, match='differs'):
      writer.write(pattern(2, 32, 32), Fraction(1, 5))
  _, frames = read_all(path)
  assert [f.time for f in frames] == [0, Fraction(1, 10)]


def test_bad_files_are_named(tmp_path):
  with pytest.raises(ValueError, match='missing.mp4'):
    streams.open_video(str(tmp_path / 'missing.mp4'))
  (tmp_path / 'garbage.mp4').write_bytes(b'not a video at all' * 50)
  with pytest.raises(ValueError, match='garbage.mp4'):
    streams.open_video(str(tmp_path / 'garbage.mp4'))
  with av.open(str(tmp_path / 'sound.mkv'), 'w') as out:  # Audio only.
    stream = out.add_stream('flac', rate=8000, layout='mono')
    frame = av.AudioFrame.from_ndarray(np.zeros((1, 800), np.int16), format='s16',
                                       layout='mono')
    frame.sample_rate, frame.pts = 8000, 0
    out.mux(stream.encode(frame))
    out.mux(stream.encode(None))
  with pytest.raises(ValueError, match='sound.mkv: no video stream'):
    streams.open_video(str(tmp_path / 'sound.mkv'))
  with pytest.raises(ValueError, match=r'clip\.flv'):
    streams.VideoWriter(str(tmp_path / 'clip.flv'), Fraction(25))
  with pytest.raises(ValueError, match='No video'):
    assembly.assemble([], str(tmp_path / 'out.mp4'), Fraction(25))


def test_video_info_says_whether_colour_is_stored_at_half_resolution(tmp_path):
  source = make_video(tmp_path / 'in.mp4', [pattern(i) for i in range(2)])  # yuv420p.
  assert read_all(source)[0].chroma_halved
  full = str(tmp_path / 'rgb.mov')
  with av.open(full, 'w') as out:
    stream = out.add_stream('png', rate=12)
    stream.width, stream.height, stream.pix_fmt = 96, 64, 'rgb24'
    for index in range(2):
      out.mux(stream.encode(av.VideoFrame.from_ndarray(pattern(index), format='rgb24')))
    out.mux(stream.encode(None))
  assert not read_all(full)[0].chroma_halved


def test_video_info_gives_the_bits_per_sample(tmp_path):
  assert read_all(make_video(tmp_path / 'in.mp4', [pattern(0)]))[0].bits == 8
  deep = str(tmp_path / 'ten.mkv')
  with av.open(deep, 'w') as out:
    stream = out.add_stream('libx264', rate=12)
    stream.width, stream.height, stream.pix_fmt = 96, 64, 'yuv420p10le'
    for index in range(2):
      frame = av.VideoFrame.from_ndarray(pattern(index), format='rgb24')
      frame.pts = index
      out.mux(stream.encode(frame))
    out.mux(stream.encode(None))
  info, frames = read_all(deep)
  assert info.bits == 10 and frames[0].image.dtype == np.uint8
  _, wide = streams.open_video(deep, deep=True)
  wide = [frame.image for frame in wide]
  assert wide[0].dtype == np.uint16 and len(wide) == 2
  difference = np.abs(wide[0] / 257.0 - frames[0].image)  # Up to 3.5: swscale's rgb24
  assert difference.mean() < 1 and difference.max() < 4  # path upsamples colour otherwise.
  _, eight = streams.open_video(make_video(tmp_path / 'in8.mp4', [pattern(0)]), deep=True)
  assert next(eight).image.dtype == np.uint8  # An 8-bit stream stays uint8.


def test_uint16_frames_keep_10_bits_in_high_10_and_8_in_h264(tmp_path):
  """The writer takes uint16 frames: a DEEP encoder keeps a ramp's 10-bit levels; an 8-bit
  one gets them rounded to 8 bits (`image_range.eight_bits`; read back as uint8)."""
  ramp = np.rint(np.linspace(0.2, 0.8, 64 * 96) * 65535).astype(np.uint16).reshape(64, 96)
  image = np.dstack([ramp] * 3)
  levels = {}
  for name, settings in (('deep.mp4', encoders.DEEP), ('plain.mp4', None)):
    with streams.VideoWriter(str(tmp_path / name), Fraction(10), encoder=settings) as writer:
      writer.write(image, Fraction(0))
    _, frames = streams.open_video(str(tmp_path / name), deep=True)
    decoded = next(frames).image.astype(np.uint16)
    decoded = decoded if settings else decoded * 257
    assert np.abs(decoded.astype(float) - image).max() < 4 * 257, name  # Limited range.
    levels[name] = len(np.unique(decoded[..., 1] >> 6))
  assert levels['deep.mp4'] > 400 and levels['plain.mp4'] <= 160, levels


def _transport_stream(path, frames, first_index):
  """MPEG-TS bytes of `frames` (uint8 RGB, one size), their pts from `first_index`."""
  with av.open(str(path), 'w', format='mpegts') as out:
    video = out.add_stream('libx264', rate=12, options={'crf': '12'})
    video.height, video.width = frames[0].shape[:2]
    video.pix_fmt = 'yuv420p'
    for index, image in enumerate(frames, first_index):
      frame = av.VideoFrame.from_ndarray(image, format='rgb24')
      frame.pts = index
      out.mux(video.encode(frame))
    out.mux(video.encode(None))
  return path.read_bytes()


def test_a_stream_whose_size_changes_is_read_at_the_first_frames_size(tmp_path, caplog):
  """Joined broadcast clips: frames 4-7 are half the size of frames 0-3; they arrive
  scaled to the first size (an encoder takes one size), with one warning naming frame 4."""
  caplog.set_level('WARNING', logger='absl')
  big = [pattern(i) for i in range(4)]
  small = [np.full((32, 48, 3), (30 * i, 200, 90), np.uint8) for i in range(4, 8)]
  joined = tmp_path / 'joined.ts'
  joined.write_bytes(_transport_stream(tmp_path / 'a.ts', big, 0) +
                     _transport_stream(tmp_path / 'b.ts', small, 4))
  info, frames = read_all(joined)
  assert (info.width, info.height) == (96, 64) and len(frames) == 8
  assert all(f.image.shape == (64, 96, 3) for f in frames)
  assert all(b.time > a.time for a, b in zip(frames, frames[1:]))
  for frame, image in zip(frames[4:], small):  # Each one's own colour, at the first size.
    np.testing.assert_allclose(frame.image.mean(axis=(0, 1)), image[0, 0], atol=4)
  warnings = [r.getMessage() for r in caplog.records if 'scaled to' in r.getMessage()]
  assert len(warnings) == 1 and 'frames from 4 on are 48x32, not 96x64' in warnings[0]
