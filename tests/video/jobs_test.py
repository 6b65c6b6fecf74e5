"""Tests for mixstereo_tf.video.jobs: interruption leaves no final file, re-runs resume."""

import json
import os

import numpy as np
import pytest

from mixstereo_tf.video import jobs
from tests.video import streams_test


class Interrupted(Exception):
  """Stands in for Ctrl-C / a crash inside the renderer."""


def _renderer(calls, fail_at=None):
  """A renderer recording the frames it sees: 'sbs' = frame | inverted frame, 'gray'."""
  def render(image):
    if fail_at is not None and len(calls) == fail_at:
      raise Interrupted()
    calls.append(int(image[0, 0, 0]))
    gray = np.repeat(image.mean(axis=2, keepdims=True).astype(np.uint8), 3, axis=2)
    return {'sbs': np.concatenate([image, 255 - image], axis=1), 'gray': gray}
  return render


def _job(tmp_path, source, name, settings=None):
  return jobs.VideoJob(
      source, {key: str(tmp_path / f'{name}_{key}.mp4') for key in ('sbs', 'gray')},
      settings or {'renderer': 'test'}, jobs.VideoConfig(segment_frames=8))


def test_interrupted_then_resumed_equals_one_run(tmp_path):
  source = streams_test.make_video(tmp_path / 'in.mp4',
                                    [streams_test.pattern(i) for i in range(27)])
  calls = []
  once = jobs.run(_job(tmp_path, source, 'once'), _renderer(calls))
  assert (once['frames'], once['resumed_frames'], len(calls)) == (27, 0, 27)
  assert sorted(os.listdir(tmp_path)) == ['in.mp4', 'once_gray.mp4', 'once_sbs.mp4']
  # Interrupted in the third segment (frames 16..23): no final or partial output exists,
  # two segments are finished and listed.
  job = _job(tmp_path, source, 'again')
  calls = []
  with pytest.raises(Interrupted):
    jobs.run(job, _renderer(calls, fail_at=19))
  assert not any(os.path.exists(p) or os.path.exists(jobs.partial_path(p))
                 for p in job.outputs.values())
  with open(os.path.join(job.folder, jobs.MANIFEST), encoding='utf-8') as f:
    manifest = json.load(f)
  assert [s['frames'] for s in manifest['segments']] == [8, 8] and not manifest['complete']
  assert sorted(os.listdir(job.folder)) == [
      'gray_00000.mov', 'gray_00001.mov', 'manifest.json', 'sbs_00000.mov', 'sbs_00001.mov']
  # The re-run renders only from frame 16 and gives the same frames, times and audio.
  resumed_calls = []
  resumed = jobs.run(job, _renderer(resumed_calls))
  assert (resumed['frames'], resumed['resumed_frames'], len(resumed_calls)) == (27, 16, 11)
  assert resumed_calls[:3] == calls[16:]  # Frames 16-18 again: their segment was lost.
  assert not os.path.exists(job.folder)
  for key in ('sbs', 'gray'):
    info_a, frames_a = streams_test.read_all(tmp_path / f'once_{key}.mp4')
    info_b, frames_b = streams_test.read_all(tmp_path / f'again_{key}.mp4')
    assert len(frames_a) == len(frames_b) == 27 and info_a == info_b
    assert info_a.frame_rate == 12 and info_a.audio_streams == 1
    assert [f.time for f in frames_a] == [f.time for f in frames_b]
    for a, b in zip(frames_a, frames_b):
      np.testing.assert_array_equal(a.image, b.image)
    np.testing.assert_array_equal(streams_test.audio_samples(tmp_path / f'again_{key}.mp4'),
                                  streams_test.audio_samples(source))
  assert frames_a[0].image.shape == (64, 96, 3)


def test_changed_settings_or_input_start_afresh(tmp_path):
  source = streams_test.make_video(tmp_path / 'in.mkv',
                                    [streams_test.pattern(i) for i in range(12)])
  job = _job(tmp_path, source, 'out')
  with pytest.raises(Interrupted):
    jobs.run(job, _renderer([], fail_at=9))
  calls = []
  # Other settings: the finished segment is not reused.
  with pytest.raises(Interrupted):
    jobs.run(_job(tmp_path, source, 'out', {'renderer': 'other'}), _renderer(calls, 9))
  assert len(calls) == 9
  # A touched input: not reused either.
  os.utime(source, ns=(1, 1))
  calls = []
  result = jobs.run(job, _renderer(calls))
  assert (result['frames'], result['resumed_frames'], len(calls)) == (12, 0, 12)
  assert streams_test.read_all(job.outputs['sbs'])[0].width == 192


def test_a_finished_run_removes_the_folders_of_its_inputs_stopped_runs(tmp_path):
  """Stopped with other outputs (another layout), then run to the end: the stopped run's
  segments stayed for good. Another input's stopped run is kept."""
  source = streams_test.make_video(tmp_path / 'in.mp4',
                                    [streams_test.pattern(i) for i in range(12)])
  other = streams_test.make_video(tmp_path / 'other.mp4',
                                   [streams_test.pattern(i) for i in range(12)])
  stopped, kept = _job(tmp_path, source, 'left'), _job(tmp_path, other, 'its')
  for job in (stopped, kept):
    with pytest.raises(Interrupted):
      jobs.run(job, _renderer([], fail_at=9))
  assert os.path.isdir(stopped.folder) and os.path.isdir(kept.folder)
  jobs.run(_job(tmp_path, source, 'tb'), _renderer([]))
  assert not os.path.exists(stopped.folder) and os.path.isdir(kept.folder)


def test_an_unreadable_input_leaves_no_job_folder(tmp_path):
  source = tmp_path / 'broken.mp4'
  source.write_bytes(b'\x00\x00\x00\x18ftypmp42 truncated')
  job = _job(tmp_path, str(source), 'out')
  with pytest.raises(ValueError, match='broken.mp4'):
    jobs.run(job, _renderer([]))
  assert sorted(os.listdir(tmp_path)) == ['broken.mp4']


def test_segment_length_must_be_positive():
  with pytest.raises(ValueError, match='segment_frames'):
    jobs.VideoConfig(segment_frames=0)
