"""Consistency checks of the transcribed paper numbers against the paper's own claims."""

import numpy as np
import pytest

from mixstereo_tf.core import mixtures
from mixstereo_tf.evaluation import metrics
from mixstereo_tf.evaluation import paper_numbers as pn


@pytest.mark.parametrize('method', ['ours', 'joulin', 'williem'])
def test_middlebury_bad1_mean_is_the_mean_of_the_scenes(method):
  scenes = [pn.lookup('middlebury', 'anaglyph', method, s)['bad1']
            for s in pn.MIDDLEBURY_SCENES]
  mean = pn.lookup('middlebury', 'anaglyph', method, 'mean')['bad1']
  # The paper rounds to 2 decimals (Joulin's 26.815 printed as 26.82).
  assert abs(np.mean(scenes) - mean) <= 0.005 + 1e-9


def test_middlebury_improvement_claims():
  # Text: "32.55% performance leap than Williem" and "352.28% ... than Joulin".
  ours = pn.lookup('middlebury', 'anaglyph', 'ours', 'mean')['bad1']
  williem = pn.lookup('middlebury', 'anaglyph', 'williem', 'mean')['bad1']
  joulin = pn.lookup('middlebury', 'anaglyph', 'joulin', 'mean')['bad1']
  assert 100 * (williem / ours - 1) == pytest.approx(32.55, abs=0.01)
  assert 100 * (joulin / ours - 1) == pytest.approx(352.28, abs=0.01)


def test_ours_beats_the_baselines_as_claimed():
  for scene in pn.MIDDLEBURY_SCENES:
    ours = pn.lookup('middlebury', 'anaglyph', 'ours', scene)
    for method in ('joulin', 'williem'):
      other = pn.lookup('middlebury', 'anaglyph', method, scene)
      assert ours['psnr_left'] > other['psnr_left'] and ours['bad1'] < other['bad1']
  kitti = {m: pn.lookup('kitti2015', 'anaglyph', m) for m in ('ours', 'joulin', 'williem')}
  assert min(kitti, key=lambda m: kitti[m]['d1_all']) == 'ours'
  assert pn.lookup('kitti2015', 'diplopia', 'oracle')['d1_all'] == 5.28
  assert (pn.lookup('kitti2015_ablation', None, 'joint')['psnr'] >
          pn.lookup('kitti2015_ablation', None, 'separation_only')['psnr'])


def test_keys_use_project_names():
  for protocol, mixture, _, scene in pn.PAPER_NUMBERS:
    assert mixture is None or mixture in mixtures.MIXTURE_NAMES
    assert scene is None or scene in pn.MIDDLEBURY_SCENES + ('mean',)
  for (protocol, _, _, _), values in pn.PAPER_NUMBERS.items():
    if protocol == 'eigen':
      assert tuple(values) == metrics.DEPTH_METRIC_NAMES


def test_lookup_and_methods():
  assert pn.lookup('eigen', 'monocular', 'godard')['rmse'] == 4.471
  assert pn.lookup('kitti2015', 'diplopia', 'joulin') == {}
  assert pn.methods('kitti2015', 'anaglyph') == ('ours', 'joulin', 'williem')
  assert pn.methods('eigen', 'monocular') == ('ours', 'godard', 'garg', 'zhou')
  with pytest.raises(ValueError, match='kitti2015'):
    pn.lookup('kitti2012', 'anaglyph', 'ours')
