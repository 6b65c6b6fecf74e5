"""Tests for the Apache Beam batch pipeline (mixstereo_tf.cli.beam_batch) and its binary."""

import csv
import dataclasses
import errno
import gzip
import json
import logging as std_logging
import os
import subprocess
import sys

import numpy as np
import pytest

from mixstereo_tf.cli import beam_batch
from mixstereo_tf.cli import input_images
from mixstereo_tf.cli import media
from mixstereo_tf.cli import info_file
from mixstereo_tf.cli import input_failures
from mixstereo_tf.cli import input_listing
from mixstereo_tf.cli import unmix_files
from mixstereo_tf.unmixing import predictors

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CONFIG = predictors.PredictorConfig('classical', mixture='anaglyph', disparity_range=(0, 8))
OPTIONS = media.OutputOptions('sbs')
OWN_FILES = (beam_batch.SUMMARY, beam_batch.DEAD_LETTERS)


def _folder(path):
  """a.png, a.jpg (a shared stem), b.png and a corrupt broken.png; returns the folder."""
  path.mkdir()
  for seed, name in enumerate(('a.png', 'a.jpg', 'b.png')):
    image = np.random.RandomState(seed).randint(0, 256, (36, 52, 3)).astype(np.uint8)
    media.write_image(str(path / name), image)
  (path / 'broken.png').write_bytes(b'\x89PNG\r\n\x1a\n truncated')
  return path


def _csv(path):
  with open(path, encoding='utf-8', newline='') as f:
    return list(csv.DictReader(f))


def _without_seconds(path):
  info = json.loads(path.read_text())
  assert info.pop('seconds') > 0
  return info


def test_outputs_equal_the_cli_failures_dead_letter_and_a_rerun_skips(tmp_path, monkeypatch):
  folder = _folder(tmp_path / 'in')
  cli = unmix_files.unmix_inputs(predictors.build_unmixer(CONFIG), str(folder),
                                 str(tmp_path / 'cli'), OPTIONS)
  assert (cli.processed, len(cli.failures)) == (3, 1)
  builds = []
  build = predictors.build_unmixer
  monkeypatch.setattr(predictors, 'build_unmixer',
                      lambda config: builds.append(config) or build(config))
  items = beam_batch.list_inputs(str(folder), None)
  out = tmp_path / 'batch'
  counts = beam_batch.run(items, CONFIG, str(out), OPTIONS)
  assert counts == {'done': 3, 'skipped': 0, 'failed': 1} and builds == [CONFIG]
  # The CLI's files, byte for byte (info.json: all but the seconds).
  names = sorted(os.listdir(tmp_path / 'cli'))
  assert sorted(set(os.listdir(out)) - set(OWN_FILES)) == names
  assert 'a_png_sbs.png' in names and 'a_jpg_info.json' in names
  for name in names:
    if name.endswith('_info.json'):
      assert _without_seconds(out / name) == _without_seconds(tmp_path / 'cli' / name), name
    else:
      assert (out / name).read_bytes() == (tmp_path / 'cli' / name).read_bytes(), name
  for name in names:  # unmix_item writes each input's info.json last.
    if name.endswith('_info.json'):
      listed = json.loads((out / name).read_text())['files']
      assert os.stat(out / name).st_mtime_ns >= max(os.stat(out / f).st_mtime_ns for f in listed)
  dead = _csv(out / beam_batch.DEAD_LETTERS)
  assert [row['input'] for row in dead] == [str(folder / 'broken.png')]
  assert dead[0]['error'] == cli.failures[0][1]  # 'ValueError: Cannot decode image file: ...'
  rows = _csv(out / beam_batch.SUMMARY)
  assert [(row['name'], row['status']) for row in rows] == [
      ('a_jpg', 'done'), ('a_png', 'done'), ('b', 'done'), ('broken', 'failed')]
  assert rows[0]['mixture'] == 'anaglyph' and rows[0]['disparity_range'] == '0,8'
  assert float(rows[0]['seconds']) > 0 and 'Cannot decode' in rows[3]['error']
  # A re-run skips the complete inputs; b lost a file, so it is unmixed again.
  os.remove(out / 'b_disparity.npy')
  stamps = {name: os.stat(out / name).st_mtime_ns for name in names if name.startswith('a_')}
  counts = beam_batch.run(items, CONFIG, str(out), OPTIONS)
  assert counts == {'done': 1, 'skipped': 2, 'failed': 1}
  assert stamps == {name: os.stat(out / name).st_mtime_ns for name in stamps}
  assert (out / 'b_disparity.npy').read_bytes() == (
      tmp_path / 'cli' / 'b_disparity.npy').read_bytes()
  assert [row['status'] for row in _csv(out / beam_batch.SUMMARY)] == [
      'skipped', 'skipped', 'done', 'failed']
  assert len(_csv(out / beam_batch.DEAD_LETTERS)) == 1
  # An input replaced at the same path (size, modification time) is done again.
  b_info = json.loads((out / 'b_info.json').read_text())
  assert b_info['input_size'] == os.stat(folder / 'b.png').st_size
  os.utime(folder / 'b.png', ns=(b_info['input_mtime_ns'] + 10**9,) * 2)
  counts = beam_batch.run(items, CONFIG, str(out), OPTIONS)
  assert counts == {'done': 1, 'skipped': 2, 'failed': 1}
  # Other flags on the same folder: refused per input, nothing overwritten or kept silently.
  other = dataclasses.replace(OPTIONS, layout='tb')
  counts = beam_batch.run(items, CONFIG, str(out), other)
  assert counts == {'done': 0, 'skipped': 0, 'failed': 4}
  assert stamps == {name: os.stat(out / name).st_mtime_ns for name in stamps}
  assert "layout: 'sbs' -> 'tb'" in _csv(out / beam_batch.DEAD_LETTERS)[0]['error']


def test_input_list_names_like_the_cli(tmp_path):
  for folder in ('x', 'y'):
    (tmp_path / folder).mkdir()
  paths = [str(tmp_path / 'x' / 'p.png'), str(tmp_path / 'y' / 'p.png'),
           str(tmp_path / 'clip.MP4')]
  with gzip.open(tmp_path / 'list.txt.gz', 'wt') as f:  # Beam decompresses by extension.
    f.write('\n'.join(paths[:2]) + '\n\n  ' + paths[2] + '\n')
  items = beam_batch.list_inputs(None, str(tmp_path / 'list.txt.gz'))
  assert [item.path for item in items] == paths
  assert [item.name for item in items] == input_listing.output_names(paths) == [
      'p_png', 'p_png_2', 'clip']
  assert [item.is_video for item in items] == [False, False, True]
  (tmp_path / 'remote.txt').write_text(f'{paths[0]}\ngs://bucket/scan.jpg\n')
  with pytest.raises(ValueError, match=r'entry 2 of .*remote.txt, gs://bucket/scan.jpg, is '
                                       'not a local path'):
    beam_batch.list_inputs(None, str(tmp_path / 'remote.txt'))
  (tmp_path / 'notes.txt').write_text(f'# scans of 1998\n{paths[0]}\n  # {paths[1]}\n'
                                      f'{paths[2]}\n{paths[0]}\n')
  items = beam_batch.list_inputs(None, str(tmp_path / 'notes.txt'))
  assert [item.path for item in items] == [paths[0], paths[2]]  # Comments out, repeat once.
  assert [item.name for item in items] == ['p', 'clip']
  # A BOM (lists saved on Windows) and one file in three spellings.
  relative = os.path.relpath(paths[0])
  (tmp_path / 'spelt.txt').write_text(f'\ufeff{paths[0]}\n./{relative}\n{relative}\n'
                                      f'{paths[2]}\n', encoding='utf-8')
  items = beam_batch.list_inputs(None, str(tmp_path / 'spelt.txt'))
  assert [item.path for item in items] == [paths[0], paths[2]]
  (tmp_path / 'empty.txt').write_text('\n \n# only a comment\n')
  with pytest.raises(ValueError, match='--input_list: no paths in .*empty.txt'):
    beam_batch.list_inputs(None, str(tmp_path / 'empty.txt'))
  with pytest.raises(ValueError, match='--input_list: cannot read .*missing.txt'):
    beam_batch.list_inputs(None, str(tmp_path / 'missing.txt'))
  with pytest.raises(ValueError, match='exactly one of --input and --input_list'):
    beam_batch.list_inputs(str(tmp_path), str(tmp_path / 'list.txt.gz'))


def test_results_of_another_input_or_method_are_not_skipped_as_done(tmp_path):
  item = input_listing.MediaItem(str(tmp_path / 'in' / 'p.png'), False, 'p')
  mine = {'input': item.path, 'method': 'classical'}
  assert beam_batch.foreign_results(mine, item, 'classical') is None
  assert beam_batch.foreign_results({'files': []}, item, 'model') is None  # Older infos.
  assert 'by method \'classical\', not \'model\'' in beam_batch.foreign_results(
      mine, item, 'model')
  other = dict(mine, input=str(tmp_path / 'elsewhere' / 'p.png'))
  assert 'another input' in beam_batch.foreign_results(other, item, 'classical')
  # Asked for with other flags (the mixture detected before, now named; a new format).
  asked = info_file.describe(media.OutputOptions(settings={'mixture': 'auto'}))
  recorded = dict(mine, request=asked)
  assert beam_batch.foreign_results(recorded, item, 'classical', asked) is None
  now = info_file.describe(media.OutputOptions(settings={'mixture': 'anaglyph'},
                                                 formats=('mpo',)))
  why = beam_batch.foreign_results(recorded, item, 'classical', now)
  assert "mixture: 'auto' -> 'anaglyph'" in why and "output_formats: [] -> ['mpo']" in why
  assert 'remove p_info.json to redo it' in why
  assert beam_batch.foreign_results(mine, item, 'classical', now) is None  # Older infos.
  # Other weights at the same checkpoint path; a field the old request lacks is not asked.
  trained = info_file.describe(media.OutputOptions(settings={
      'mixture': 'auto', 'checkpoint': 'runs/a', 'weights': 'ckpt-1.index sha256:1'}))
  retrained = info_file.describe(media.OutputOptions(settings={
      'mixture': 'auto', 'checkpoint': 'runs/a', 'weights': 'ckpt-1.index sha256:2'}))
  why = beam_batch.foreign_results(dict(mine, request=trained), item, 'classical', retrained)
  assert "weights: 'ckpt-1.index sha256:1' -> 'ckpt-1.index sha256:2'" in why
  assert beam_batch.foreign_results(recorded, item, 'classical', dict(
      asked, settings=dict(asked['settings'], weights=None))) is None
  # The shipped default recorded unnamed (before runs named it) is the default named now,
  # not another model.
  def shipped(pretrained, weights):
    return info_file.describe(media.OutputOptions(settings={
        'method': 'model', 'mixture': 'auto', 'pretrained': pretrained, 'checkpoint': None,
        'saved_model': None, 'weights': weights}))
  unnamed = dict(mine, request=shipped(None, None))
  default = shipped('anaglyph_matching', 'weights.npz sha256:1')
  assert beam_batch.foreign_results(unnamed, item, 'classical', default) is None
  why = beam_batch.foreign_results(unnamed, item, 'classical',
                                   shipped('anaglyph', 'weights.npz sha256:2'))
  assert "pretrained: None -> 'anaglyph'" in why
  # The stereo formats in another order write the same files.
  two = info_file.describe(media.OutputOptions(formats=('mpo', 'jps')))
  assert beam_batch.foreign_results(dict(mine, request=two), item, 'classical', dict(
      two, output_formats=['jps', 'mpo'])) is None


def test_complete_means_the_info_and_every_file_it_lists(tmp_path):
  assert beam_batch.completed_info(str(tmp_path), 'a') is None
  (tmp_path / 'a_info.json').write_text('{"files": ["a_left.png", "a_disparity.npy"]')
  assert beam_batch.completed_info(str(tmp_path), 'a') is None  # Cut short.
  (tmp_path / 'a_info.json').write_text('{"files": ["a_left.png", "a_disparity.npy"]}')
  (tmp_path / 'a_left.png').write_bytes(b'')
  assert beam_batch.completed_info(str(tmp_path), 'a') is None
  (tmp_path / 'a_disparity.npy').write_bytes(b'')
  assert beam_batch.completed_info(str(tmp_path), 'a') == {
      'files': ['a_left.png', 'a_disparity.npy']}


def test_pipeline_options_pass_beams_and_name_unknown_flags():
  options = beam_batch.pipeline_options(['--direct_num_workers=2', '--job_name=scans'])
  assert options.get_all_options()['runner'] == beam_batch.DEFAULT_RUNNER
  assert options.get_all_options()['direct_num_workers'] == 2
  options = beam_batch.pipeline_options(['--runner=DataflowRunner', '--project=p'])
  assert options.get_all_options()['runner'] == 'DataflowRunner'
  with pytest.raises(ValueError, match="neither the tool's nor Apache Beam pipeline "
                                       'options: --layot$'):
    beam_batch.pipeline_options(['--runner=FnApiRunner', '--layot=sbs'])


def test_binary_on_an_input_list(tmp_path):
  folder = _folder(tmp_path / 'in')
  (tmp_path / 'list.txt').write_text(f'{folder / "b.png"}\n{folder / "broken.png"}\n')
  env = dict(os.environ, TF_CPP_MIN_LOG_LEVEL='2')
  result = subprocess.run(
      [sys.executable, '-m', 'mixstereo_tf.batch', '--method=classical', '--mixture=anaglyph',
       '--disparity_range=0,8', f'--input_list={tmp_path / "list.txt"}',
       f'--output_dir={tmp_path / "out"}', '--layout=tb', '--direct_num_workers=2',
       '--direct_running_mode=multi_processing'],
      capture_output=True, text=True, env=env, cwd=REPO, timeout=300, check=False)
  assert result.returncode == 1, result.stderr[-3000:]
  # Logged once: by the worker process, not relayed again by the runner's job service.
  assert result.stderr.count(f'failed {folder / "broken.png"}') == 1, result.stderr[-3000:]
  assert (f'error: 1 of 2 input(s) failed: see {tmp_path / "out" / beam_batch.DEAD_LETTERS}'
          in result.stderr)
  assert '1 input(s) done, 0 skipped' in result.stderr
  assert sorted(os.listdir(tmp_path / 'out')) == sorted(
      ['b_tb.png', 'b_disparity.png', 'b_disparity16.png', 'b_disparity.npy', 'b_info.json',
       *OWN_FILES])
  assert input_images.read_image(str(tmp_path / 'out' / 'b_tb.png')).shape == (72, 52, 3)


def test_an_interrupted_binary_exits_130_saying_how_to_continue(tmp_path):
  """Beam re-raises Ctrl-C inside a bundle as RuntimeError('KeyboardInterrupt ...')."""
  folder = _folder(tmp_path / 'in')
  script = ('import sys\n'
            'from mixstereo_tf import batch\n'
            'from mixstereo_tf.cli import beam_batch\n'
            'def interrupted(*args):\n'
            '  raise RuntimeError("KeyboardInterrupt [while running \'Unmix\']")\n'
            'beam_batch.run = interrupted\n'
            'sys.argv[1:] = sys.argv[2:]\n'
            'batch.run()\n')
  result = subprocess.run(
      [sys.executable, '-c', script, 'mixstereo-batch', '--method=classical',
       '--mixture=anaglyph', f'--input={folder}', f'--output_dir={tmp_path / "out"}'],
      capture_output=True, text=True, cwd=REPO, timeout=300, check=False,
      env=dict(os.environ, TF_CPP_MIN_LOG_LEVEL='2'))
  assert result.returncode == 130, result.stderr[-3000:]
  assert 'Interrupted: the inputs finished so far are kept' in result.stderr
  assert 'Traceback' not in result.stderr



def test_beams_record_of_a_ctrl_c_is_dropped_and_others_kept():
  keep = beam_batch.DropInterrupts().filter
  record = lambda message: std_logging.LogRecord('beam', std_logging.ERROR, 'f.py', 1,
                                                 message, (), None)
  assert not keep(record("KeyboardInterrupt [while running 'Unmix/ParDo(_UnmixFn)']"))
  assert keep(record("ValueError [while running 'Unmix/ParDo(_UnmixFn)']"))


def test_a_name_that_is_no_utf8_is_unmixed_and_listed_and_a_changed_input_keeps_its_flags(
    tmp_path, caplog):
  """A Latin-1 file name (an old share): Beam's text coder refused it and no input was
  done. An input changed since its results, asked for with other flags, was redone with
  those flags beside the others' results; it is refused like them."""
  # The log names the file as \\xNN (core/printable): pytest-xdist's reports, UTF-8,
  # crashed on its surrogates.
  caplog.set_level(std_logging.INFO, logger='absl')
  folder = _folder(tmp_path / 'in')
  os.remove(folder / 'broken.png')
  latin = os.path.join(str(folder), os.fsdecode(b'caf\xe9.png'))
  os.rename(folder / 'b.png', latin)
  items = beam_batch.list_inputs(str(folder), None)
  out = tmp_path / 'out'
  assert beam_batch.run(items, CONFIG, str(out), OPTIONS) == {
      'done': 3, 'skipped': 0, 'failed': 0}
  rows = _csv(out / beam_batch.SUMMARY)
  assert sorted(row['name'] for row in rows) == ['a_jpg', 'a_png', 'caf\\xe9']
  assert os.path.exists(os.path.join(str(out), os.fsdecode(b'caf\xe9_info.json')))
  os.utime(latin, ns=(1, 1))  # Changed since: redone with the same flags only.
  sbs = media.OutputOptions('separate')
  counts = beam_batch.run(beam_batch.list_inputs(str(folder), None), CONFIG, str(out), sbs)
  assert counts == {'done': 0, 'skipped': 0, 'failed': 3}
  assert not any(name.endswith('_left.png') for name in os.listdir(out))
  assert beam_batch.run(beam_batch.list_inputs(str(folder), None), CONFIG, str(out),
                        OPTIONS) == {'done': 1, 'skipped': 2, 'failed': 0}
  assert any('caf\\xe9.png' in record.getMessage() for record in caplog.records)


def test_results_reached_through_a_linked_folder_are_the_same_inputs(tmp_path):
  folder = _folder(tmp_path / 'real')
  os.remove(folder / 'broken.png')
  os.symlink(folder, tmp_path / 'alias')
  out = str(tmp_path / 'out')
  assert beam_batch.run(beam_batch.list_inputs(str(tmp_path / 'alias'), None), CONFIG, out,
                        OPTIONS)['done'] == 3
  assert beam_batch.run(beam_batch.list_inputs(str(folder), None), CONFIG, out,
                        OPTIONS) == {'done': 0, 'skipped': 3, 'failed': 0}


def test_an_input_replaced_by_a_failing_file_says_its_earlier_results_remain(tmp_path):
  folder = _folder(tmp_path / 'in')
  os.remove(folder / 'broken.png')
  out = tmp_path / 'out'
  beam_batch.run(beam_batch.list_inputs(str(folder), None), CONFIG, str(out), OPTIONS)
  (folder / 'b.png').write_bytes(b'\x89PNG\r\n\x1a\n replaced by a broken file')
  counts = beam_batch.run(beam_batch.list_inputs(str(folder), None), CONFIG, str(out), OPTIONS)
  assert counts == {'done': 0, 'skipped': 2, 'failed': 1}
  dead = _csv(out / beam_batch.DEAD_LETTERS)
  assert 'the results of its earlier version remain (b_info.json' in dead[0]['error']


@pytest.mark.parametrize('error, free, message', [
    (OSError('4800 requested and 3040 written'), 0, 'on a full disk'),  # NumPy's tofile.
    (OSError(errno.EROFS, os.strerror(errno.EROFS)), None, 'Read-only file system'),
])
def test_a_full_or_read_only_output_ends_the_job(tmp_path, monkeypatch, error, free, message):
  """A read-only disk ends it with room left (its inputs failed one by one)."""
  folder = _folder(tmp_path / 'in')
  os.remove(folder / 'broken.png')
  usage = input_failures.shutil.disk_usage(tmp_path)

  def failing(*args, **kwargs):
    raise error
  monkeypatch.setattr(media, 'write_image_outputs', failing)
  if free is not None:
    monkeypatch.setattr(input_failures.shutil, 'disk_usage', lambda path: usage._replace(free=free))
  with pytest.raises((input_failures.OutputFull, RuntimeError), match=message):
    beam_batch.run(beam_batch.list_inputs(str(folder), None), CONFIG, str(tmp_path / 'out'),
                   OPTIONS)


def test_the_librarys_warnings_name_their_input(tmp_path, caplog):
  """The batch's warnings did not say which file they were about."""
  folder = _folder(tmp_path / 'in')
  os.remove(folder / 'broken.png')
  caplog.set_level(std_logging.WARNING, logger='absl')
  wide = dataclasses.replace(CONFIG, disparity_range=(0, 60))  # Beyond the 52-px images.
  beam_batch.run(beam_batch.list_inputs(str(folder), None), wide, str(tmp_path / 'out'),
                 OPTIONS)
  beyond = sorted(r.getMessage().split(': The disparity range')[0] for r in caplog.records
                  if 'reaches beyond the image' in r.getMessage())
  assert beyond == sorted(str(folder / name) for name in ('a.jpg', 'a.png', 'b.png'))
