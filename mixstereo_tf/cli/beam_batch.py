"""Unmixing an archive on Apache Beam: every input through `unmix_files.unmix_item`.

The one module that imports Beam (the `.[beam]` extra), so the base install stays light.
Each input gets exactly the outputs and `<name>_info.json` that `mixstereo-unmix` writes
(`unmix_files`), names from `input_listing.output_names` over the whole input list (an
input an earlier run into the folder named keeps its name, so a grown archive renames
nothing). The unmixer is built once per worker (`_UnmixFn.setup`). Runs are resumable: an
input whose outputs are complete (`completed_info`) is skipped. An input that fails with one of
`input_failures.INPUT_ERRORS` goes to the dead-letter list and the job goes on; any other
error is a bug and fails the job, as in `mixstereo-unmix`. The output folder also gets
`batch_summary.csv` (one row per input, `SUMMARY_FIELDS`) and `batch_dead_letters.csv`
(input, error). Inputs and the output folder must be paths every worker opens as local
files (a local disk, or a shared or mounted one on a cluster); `--input_list` itself may
live on any file system Beam reads (`gs://`, `s3://`, `hdfs://`, ...).
"""

# Worker processes import this module first (to unpickle the DoFn): quiet TF there too.
from mixstereo_tf.cli import startup  # pylint: disable=unused-import

import csv  # pylint: disable=g-bad-import-order
import logging as std_logging
import os
import time
from typing import Dict, Iterator, List, Optional, Sequence, Tuple

from absl import logging
import apache_beam as beam
from apache_beam.io.filesystems import FileSystems
from apache_beam.metrics.metric import MetricsFilter
from apache_beam.options.pipeline_options import PipelineOptions
from apache_beam.options.pipeline_options import StandardOptions

from mixstereo_tf.cli import info_file
from mixstereo_tf.cli import input_failures
from mixstereo_tf.cli import input_listing
from mixstereo_tf.cli import media
from mixstereo_tf.cli import unmix_files
from mixstereo_tf.core import printable
from mixstereo_tf.unmixing import predictors

SUMMARY = 'batch_summary.csv'
DEAD_LETTERS = 'batch_dead_letters.csv'
# Summary columns: status is done, skipped (complete before this run) or failed; mixture
# is the encoding used (the one detected under --mixture=auto), detected the detector's
# verdict and confidence (empty when not run), disparity_range the signed pixels searched
# and seconds this run's wall time on the input (reading, unmixing, writing).
SUMMARY_FIELDS = ('input', 'name', 'status', 'mixture', 'detected', 'confidence',
                  'disparity_range', 'seconds', 'error')
STATUSES = ('done', 'skipped', 'failed')
_DEAD = 'dead_letters'  # The DoFn's tagged output of failed inputs.
DEFAULT_RUNNER = 'FnApiRunner'


def read_input_list(path: str, earlier: Optional[Dict[str, str]] = None
                    ) -> List[input_listing.MediaItem]:
  """The items of a text file holding one input path per line (blank lines and lines
  starting with '#' ignored, a file listed twice in any spelling taken once), on any file
  system Beam reads (`.gz` and other compressed lists are decompressed), named by
  `input_listing.output_names` (with `earlier`, the names an earlier run gave).

  Raises:
    ValueError: the list cannot be read, is empty, or names a non-local path (workers
      read inputs as local files: mount the bucket and list the mounted paths).
  """
  try:
    with FileSystems.open(path) as f:
      lines = f.read().decode('utf-8-sig').splitlines()  # A BOM (Windows editors) dropped.
  except (OSError, UnicodeDecodeError) as e:
    raise ValueError(f'--input_list: cannot read {path}: {e}') from None
  entries = [line.strip() for line in lines
             if line.strip() and not line.lstrip().startswith('#')]
  # A file listed twice, however spelt (a/x.png, ./a/x.png, /abs/a/x.png), runs once.
  first = {}
  for entry in entries:
    first.setdefault(os.path.realpath(entry), entry)
  paths = list(first.values())
  if not paths:
    raise ValueError(f'--input_list: no paths in {path}')
  for number, entry in enumerate(paths, 1):
    if FileSystems.get_scheme(entry):
      raise ValueError(f'--input_list: entry {number} of {path}, {entry}, is not a local '
                       'path; workers read inputs as local files (mount the file system '
                       'and list the mounted paths).')
  videos = input_listing.VIDEO_EXTENSIONS
  return [input_listing.MediaItem(entry, os.path.splitext(entry)[1].lower() in videos, name)
          for entry, name in zip(paths, input_listing.output_names(paths, earlier))]


def list_inputs(input_spec: Optional[str], input_list: Optional[str],
                output_dir: str = '') -> List[input_listing.MediaItem]:
  """The items of `--input` (as `mixstereo-unmix` expands it: `input_listing.iter_inputs`)
  or of `--input_list` (`read_input_list`); exactly one must be given. Inputs an earlier run into
  `output_dir` named keep their names, and what they wrote is no input
  (`info_file.read_earlier`).

  Raises:
    ValueError: both or neither given, or the given one names nothing usable.
  """
  if (input_spec is None) == (input_list is None):
    raise ValueError('Give exactly one of --input and --input_list.')
  earlier = info_file.read_earlier(output_dir) if output_dir else info_file.Earlier()
  if input_list is not None:
    return read_input_list(input_list, earlier.names)
  return list(input_listing.iter_inputs(input_spec, earlier.names, earlier.outputs))


def completed_info(output_dir: str, name: str) -> Optional[Dict[str, object]]:
  """The `<name>_info.json` of an input whose outputs are complete, else None.

  Complete: the info file (which `unmix_item` writes last) parses and every file it lists
  exists. A half-written info file or a missing output means the input is done again.
  """
  info = info_file.read_json(os.path.join(output_dir, name + info_file.INFO_SUFFIX))
  files = info.get('files') if info else None
  if not isinstance(files, list) or not all(
      os.path.isfile(os.path.join(output_dir, file)) for file in files):
    return None
  return info


def foreign_results(info: Dict[str, object], item: input_listing.MediaItem, method: str,
                    request: Optional[Dict[str, object]] = None) -> Optional[str]:
  """Why complete results under `item.name` are not `item`'s by `method` asked for as
  `request` (`info_file.describe`; another input, another method or other options: a
  re-run with other flags), or None: they are, and are skipped."""
  written_for = info.get('input')
  if isinstance(written_for, str) and os.path.realpath(written_for) != os.path.realpath(
      item.path):  # The real files: a folder reached by another path (a link) is the same.
    return (f'the output folder holds results named {item.name} of another input, '
            f'{written_for}; use another --output_dir')
  if info.get('method') not in (None, method):
    return (f'the output folder holds results of {item.path} by method '
            f'{info["method"]!r}, not {method!r}; use another --output_dir')
  changed = info_file.differences(info.get('request'), request) if request else []
  if changed:
    return (f'the output folder holds results of {item.path} asked for with other flags '
            f'({"; ".join(changed)}); use another --output_dir, or remove '
            f'{item.name}_info.json to redo it')
  return None


def summary_row(item: input_listing.MediaItem, status: str, info: Dict[str, object],
                seconds: float, error: str = '') -> Dict[str, object]:
  """One `SUMMARY_FIELDS` row from an input's info (`{}` when it failed)."""
  search = info.get('disparity_range')
  # Names that are no UTF-8 as \xNN (`core.printable`): Beam's coder and the CSV refuse them.
  text = printable.printable
  return {'input': text(item.path), 'name': text(item.name), 'status': status,
          'mixture': info.get('mixture') or '', 'detected': info.get('detected') or '',
          'confidence': info.get('confidence', ''),
          'disparity_range': ','.join(str(v) for v in search) if search else '',
          'seconds': round(seconds, 3), 'error': text(error)}


class _UnmixFn(beam.DoFn):
  """(index, path, is_video, name) -> (index, summary row); failures also to the `_DEAD`
  output as (index, {'input': path, 'error': reason}). The unmixer is built once per DoFn
  instance (per worker). Elements are plain tuples: decoding them imports nothing."""

  def __init__(self, config: predictors.PredictorConfig, output_dir: str,
               options: media.OutputOptions):
    super().__init__()
    self._config, self._output_dir, self._options = config, output_dir, options
    self._request = info_file.describe(options)  # What every input is asked for.
    self._unmixer = None

  def setup(self):
    self._unmixer = predictors.build_unmixer(self._config)
    os.makedirs(self._output_dir, exist_ok=True)

  def process(self, element: Tuple[int, bytes, bool, bytes]) -> Iterator[object]:
    index, item = element[0], input_listing.MediaItem(
        os.fsdecode(element[1]), element[2], os.fsdecode(element[3]))
    info = completed_info(self._output_dir, item.name)
    other = info and foreign_results(info, item, self._unmixer.method, self._request)
    if other:  # Before the change test: a changed input is not redone with other flags.
      yield from _failed(index, item, other, 0.0)
      return
    earlier = ''
    if info and info_file.changed(info, item.path):
      logging.info('%s changed since its results were written: done again.', item.path)
      info, earlier = None, (f'; the results of its earlier version remain '
                             f'({item.name}_info.json and the files it lists)')
    if info is not None:
      beam.metrics.Metrics.counter('mixstereo', 'skipped').inc()
      yield index, summary_row(item, 'skipped', info, 0.0)
      return
    start = time.perf_counter()
    try:
      with unmix_files.naming_input(item.path):  # Per thread (Beam's threads run several).
        unmix_files.unmix_item(self._unmixer, item, self._output_dir, self._options,
                               unmix_files.UnmixReport())
    except input_failures.INPUT_ERRORS as e:
      input_failures.check_output_room(self._output_dir, e)  # OutputFull ends the job.
      yield from _failed(index, item, input_failures.reason(e) + earlier,
                         time.perf_counter() - start)
      return
    beam.metrics.Metrics.counter('mixstereo', 'done').inc()
    yield index, summary_row(item, 'done', completed_info(self._output_dir, item.name) or {},
                             time.perf_counter() - start)


def _failed(index: int, item: input_listing.MediaItem, why: str,
            seconds: float) -> Iterator[object]:
  """`_UnmixFn`'s outputs for an input that failed: logged, counted, a dead letter and its
  summary row."""
  logging.error('failed %s: %s (to the dead-letter list)', item.path, why,
                extra={unmix_files.NAMES_ITS_INPUT: True})  # Not another thread's input.
  beam.metrics.Metrics.counter('mixstereo', 'failed').inc()
  yield beam.pvalue.TaggedOutput(_DEAD, (index, {'input': printable.printable(item.path),
                                                 'error': printable.printable(why)}))
  yield index, summary_row(item, 'failed', {}, seconds, why)


def _write_csv(path: str, fields: Sequence[str],
               rows: List[Tuple[int, Dict[str, object]]]) -> None:
  """Writes (input index, {field: value}) rows in input order, replacing `path` at once."""
  with open(path + '.tmp', 'w', encoding='utf-8', newline='') as f:
    writer = csv.DictWriter(f, fields)
    writer.writeheader()
    writer.writerows(row for _, row in sorted(rows, key=lambda row: row[0]))
  os.replace(path + '.tmp', path)


def build(pipeline: beam.Pipeline, items: Sequence[input_listing.MediaItem],
          config: predictors.PredictorConfig, output_dir: str,
          options: media.OutputOptions) -> None:
  """Adds the unmixing of `items` into `output_dir` and the two CSV files to `pipeline`."""
  results = (pipeline
             # Paths as bytes: Beam's text coder refuses names that are no UTF-8.
             | 'Inputs' >> beam.Create([(index, os.fsencode(item.path), item.is_video,
                                         os.fsencode(item.name))
                                        for index, item in enumerate(items)])
             | 'Spread' >> beam.Reshuffle()
             | 'Unmix' >> beam.ParDo(_UnmixFn(config, output_dir, options)).with_outputs(
                 _DEAD, main='rows'))
  summary, dead = os.path.join(output_dir, SUMMARY), os.path.join(output_dir, DEAD_LETTERS)
  _ = (results.rows | 'AllRows' >> beam.combiners.ToList()
       | 'WriteSummary' >> beam.Map(lambda rows: _write_csv(summary, SUMMARY_FIELDS, rows)))
  _ = (results[_DEAD] | 'AllFailures' >> beam.combiners.ToList()
       | 'WriteDeadLetters' >> beam.Map(lambda rows: _write_csv(dead, ('input', 'error'), rows)))


class DropInterrupts(std_logging.Filter):
  """Drops the log record (with its traceback) Beam writes when Ctrl-C stops a transform:
  the tool then says in one line that it was interrupted and how to continue."""

  def filter(self, record: std_logging.LogRecord) -> bool:
    return 'KeyboardInterrupt' not in record.getMessage()


def pipeline_options(args: Sequence[str]) -> PipelineOptions:
  """Beam's options from the arguments the tool's flags left (`--runner=...`).

  Without `--runner`: `DEFAULT_RUNNER`, Beam's local Python runner (its workers set by
  `--direct_num_workers`, `--direct_running_mode`). Beam's own default, DirectRunner,
  first tries to download the Prism runner from the internet.

  Raises:
    ValueError: an argument is no Beam option (a mistyped flag), naming it.
  """
  options = PipelineOptions(list(args))
  unknown = set(options.get_all_options(retain_unknown_options=True)) - set(
      options.get_all_options())
  if unknown:
    raise ValueError('Unknown flag(s), neither the tool\'s nor Apache Beam pipeline options: '
                     + ', '.join(f'--{name}' for name in sorted(unknown)))
  standard = options.view_as(StandardOptions)
  standard.runner = standard.runner or DEFAULT_RUNNER
  return options


def run(items: Sequence[input_listing.MediaItem], config: predictors.PredictorConfig,
        output_dir: str, options: media.OutputOptions,
        beam_options: Optional[PipelineOptions] = None) -> Dict[str, int]:
  """Unmixes `items` into `output_dir` on the runner of `beam_options` (default:
  `DEFAULT_RUNNER`, one worker in this process) and waits for the job.

  Returns:
    {status: inputs} for `STATUSES`, from the job's metrics.
  """
  input_listing.prepare_output_dir(items, output_dir)
  pipeline = beam.Pipeline(options=beam_options or pipeline_options([]))
  build(pipeline, items, config, output_dir, options)
  result = pipeline.run()
  result.wait_until_finish()
  counters = result.metrics().query(MetricsFilter().with_namespace('mixstereo'))['counters']
  counts = dict.fromkeys(STATUSES, 0)
  for counter in counters:
    counts[counter.key.metric.name] += counter.result
  return counts
