"""Tests for consecutive frames unmixed side by side (video.frame_pipeline)."""

import dataclasses
import threading

import numpy as np
import pytest

from mixstereo_tf.classical import anaglyph
from mixstereo_tf.classical import diplopia
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.video import frame_pipeline
from mixstereo_tf.video import motion
from mixstereo_tf.video import temporal
from tests.unmixing import eye_order_test
from tests.video import temporal_test

H, W = 6, 8


class _Recorder:
  """A fake unmixer: frame k's disparity is k everywhere (consistent but for column 0);
  it reports it through on_disparity, then waits for `release[k]` before it returns."""

  def __init__(self, frames):
    self.hints, self.release = [], [threading.Event() for _ in range(frames)]
    self.started = [threading.Event() for _ in range(frames)]

  def __call__(self, image, hint):
    k = int(image[0, 0, 0])
    self.hints.append(hint)
    self.started[k].set()
    found = {'disparity_left': np.full((H, W), float(k), np.float32),
             'disparity_right': np.full((H, W), float(k), np.float32),
             'consistent_left': np.arange(W)[None].repeat(H, 0) > 0}
    if hint.on_disparity is not None:
      hint.on_disparity(found)  # Never for frames alone (temporal consistency off).
    assert self.release[k].wait(10)
    return dict(found, info={'mixture': 'anaglyph', 'disparity_range': [0, 9]})


def _frame(k):
  return np.full((H, W, 3), k, np.uint8)


def test_the_next_frame_is_matched_while_this_one_is_restored():
  unmixer = _Recorder(3)
  unmixer.release[0].set()  # A shot's first frame is waited for whole.
  with frame_pipeline.FramePipeline(unmixer, temporal.VideoState()) as pipeline:
    first = pipeline.submit(_frame(0))
    assert first.done() and unmixer.hints[0].on_disparity is None
    second = pipeline.submit(_frame(1))  # Returns once frame 1 reported its disparities,
    third = pipeline.submit(_frame(2))  # so frame 2 starts while frame 1 still runs.
    assert unmixer.started[2].wait(10) and not second.done() and not third.done()
    unmixer.release[1].set()
    unmixer.release[2].set()
    assert second.result()['disparity_left'][0, 0] == 1 and third.result()
  # Frame 2's prior: frame 1's reported disparity, NaN where its check failed.
  prior = unmixer.hints[2].prior
  assert np.isnan(prior[:, 0]).all() and (prior[:, 1:] == 1).all()
  assert unmixer.hints[1].mixture == 'anaglyph'


def test_frames_of_a_shot_whose_encoding_may_change_are_waited_for_whole():
  class Unsettled(_Recorder):
    def __call__(self, image, hint):
      return dict(super().__call__(image, hint), info={
          'mixture': 'half_color', 'also_fits': 'anaglyph', 'disparity_range': [0, 9]})

  unmixer = Unsettled(3)
  for release in unmixer.release:
    release.set()
  state = temporal.VideoState(temporal.TemporalConfig(settle_every=1))
  with frame_pipeline.FramePipeline(unmixer, state) as pipeline:
    assert all(pipeline.submit(_frame(k)).done() for k in range(3))
  assert [hint.on_disparity for hint in unmixer.hints] == [None] * 3
  assert [hint.may_be for hint in unmixer.hints] == [None, 'anaglyph', 'anaglyph']


def test_frames_alone_run_two_at_a_time_without_waiting_for_each_other():
  unmixer = _Recorder(3)
  state = temporal.VideoState(temporal.TemporalConfig(enabled=False))
  with frame_pipeline.FramePipeline(unmixer, state) as pipeline:
    first, second = pipeline.submit(_frame(0)), pipeline.submit(_frame(1))
    assert unmixer.started[1].wait(10) and not first.done()
    third = []
    submitting = threading.Thread(target=lambda: third.append(pipeline.submit(_frame(2))))
    submitting.start()
    assert not unmixer.started[2].wait(0.3)  # No third frame in flight,
    unmixer.release[1].set()  # until one of the two is done.
    assert unmixer.started[2].wait(10)
    unmixer.release[0].set()
    unmixer.release[2].set()
    submitting.join()
    assert [p.result()['disparity_left'][0, 0] for p in (first, second, third[0])] == [0, 1, 2]
  assert all(hint.on_disparity is None and hint.prior is None for hint in unmixer.hints)


def test_a_frame_failing_before_its_disparities_raises_from_submit():
  def failing(image, hint):
    raise ValueError(f'frame {int(image[0, 0, 0])} is broken')
  with frame_pipeline.FramePipeline(failing, temporal.VideoState()) as pipeline:
    with pytest.raises(ValueError, match='frame 3 is broken'):
      pipeline.submit(_frame(3))


def test_a_frame_already_unmixed_with_its_hint_is_not_unmixed_again():
  """A video's opening frame (`cli.video_files.opening`): its outputs are the frame's and
  the next frame's prior, without a second call; a different image or hint is unmixed."""
  unmixer = _Recorder(3)
  for release in unmixer.release:
    release.set()
  state = temporal.VideoState()
  hint = dataclasses.replace(temporal.VideoState().begin(_frame(0), cut=True),
                             unread='disparity_right')
  known = {'disparity_left': np.full((H, W), 7.0, np.float32), 'info': {
      'mixture': 'anaglyph', 'disparity_range': [0, 9]}}
  unmixed = frame_pipeline.Unmixed(_frame(0), hint, known)
  with frame_pipeline.FramePipeline(unmixer, state) as pipeline:
    first = pipeline.submit(_frame(0), cut=True, unmixed=unmixed, unread='disparity_right',
                            fallback_mixture='anaglyph')  # Read by no frame with one.
    second = pipeline.submit(_frame(1), unmixed=unmixed, unread='disparity_right')
    assert first.result() is known and second.result()['disparity_left'][0, 0] == 1
  assert len(unmixer.hints) == 1 and (unmixer.hints[0].prior == 7).all()
  assert unmixer.hints[0].mixture == 'anaglyph'
  assert unmixed.serves(_frame(0), dataclasses.replace(hint, fallback_mixture='gray'))
  assert not unmixed.serves(_frame(1), hint)
  assert not unmixed.serves(_frame(0), dataclasses.replace(hint, unread=None))
  assert not unmixed.serves(_frame(0), dataclasses.replace(hint, prior=np.zeros((H, W))))


def _one_at_a_time(unmixer, frames, config):
  """Each frame whole before the next starts; the next frame's prior is what this frame
  reported through on_disparity (its outputs where it reported nothing: a shot's first)."""
  state, outputs = temporal.VideoState(config), []
  for frame in frames:
    hint, told = state.begin(frame), []
    if hint.mixture is not None:
      hint = dataclasses.replace(hint, on_disparity=told.append)
    outputs.append(unmixer(frame, hint=hint))
    state.end(told[0] if told else outputs[-1])
  return outputs


@pytest.mark.parametrize('method,mixture,swapped,pretrained,alone', [
    ('classical', 'anaglyph', False, None, False),
    ('classical', 'anaglyph', True, None, False),
    ('model', 'anaglyph', False, None, False),  # The learned stage,
    ('model', 'anaglyph', False, 'anaglyph', False),  # the refiner on its base's report,
    ('model', 'anaglyph', False, None, True),  # the learned stage on every frame alone,
    ('classical', 'diplopia', False, None, False),  # double images, told before the layers,
    ('model', 'diplopia', False, 'diplopia_weighted_penalised', False)])  # and refined.
def test_side_by_side_frames_give_the_outputs_of_one_at_a_time(method, mixture, swapped,
                                                               pretrained, alone,
                                                               monkeypatch):
  if swapped:  # Cyan-red frames: the matcher runs on the mirrored image.
    left, right, _ = eye_order_test._pair()  # pylint: disable=protected-access
    frames = [temporal_test._anaglyph(right, left)] * 3  # pylint: disable=protected-access
  else:
    frames = temporal_test._shot(3, 5, name=mixture)  # pylint: disable=protected-access
  unmixer = predictors.build_unmixer(predictors.PredictorConfig(
      method, mixture=mixture, swap_eyes='auto' if swapped else False,
      pretrained=pretrained))
  shots, priors = [], []  # Each frame's shot decisions and prior, as its hint gives them.

  def recording(image, hint):
    shots.append((hint.mixture, hint.disparity_range, hint.swap_eyes))
    priors.append(hint.prior)
    return unmixer(image, hint=hint)

  # The prior as reported, not moved with the camera (`video.motion`: its own tests).
  config = temporal.TemporalConfig(enabled=not alone,
                                  motion=motion.MotionConfig(enabled=False))
  single = _one_at_a_time(recording, frames, config)
  module, name = (diplopia, 'unmix_diplopia') if mixture == 'diplopia' else (
      anaglyph, 'unmix_anaglyph')
  told, first, unmix = [], {}, getattr(module, name)

  def counting(*args, **kwargs):  # Frames start in order; they may end in any.
    index = len(told)
    told.append(kwargs.get('on_disparity'))
    first[index] = unmix(*args, **kwargs)
    return first[index]

  monkeypatch.setattr(module, name, counting)
  with frame_pipeline.FramePipeline(recording, temporal.VideoState(config)) as pipeline:
    pending = [pipeline.submit(frame) for frame in frames]
    together = [p.result() for p in pending]
  # Every frame after the shot's first one was told early, the refiners' bases too; the
  # shot was decided once, by its first frame, as one frame at a time.
  assert sum(t is not None for t in told) == (0 if alone else len(frames) - 1)
  assert shots[len(frames):] == shots[:len(frames)]
  assert shots[1][0] == (None if alone else mixture)
  if mixture == 'anaglyph':
    assert {o['info']['eye_order'] for o in together} == {
        'swapped' if swapped else 'as_given'}
  for one, other in zip(single, together):
    for key in ('left', 'right', 'disparity_left', 'consistent_left'):
      if key in one:
        np.testing.assert_array_equal(one[key], other[key])
  if pretrained == 'diplopia_weighted_penalised':  # Frame 2 searched around frame 1's
    prior = priors[len(frames) + 2]  # first stage, not around the refined disparity.
    np.testing.assert_array_equal(prior, first[1]['disparity_left'])
    assert np.abs(prior - together[1]['disparity_left']).max() > 0.1
