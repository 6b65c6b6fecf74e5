"""Evaluation protocols as registered entries, and the table pieces they share.

A `Protocol` says everything that differs between benchmarks: which dataset (and split
list) it lists through `data.sources`, how one image's disparity is scored, which tables
it prints (with the paper's numbers) and how many images make a full run. The runner and
the report are generic; adding a benchmark is one new `register(Protocol(...))` in a module
of `evaluation/protocols/`.
"""

import dataclasses
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

from mixstereo_tf.data import records
from mixstereo_tf.evaluation import results

# (title, columns, rows, percent columns, decimals); rows are dicts keyed by column.
Table = Tuple[str, Sequence[str], List[Dict[str, Any]], Sequence[str], int]
# score(config, record, loaded ground truth, predicted left disparity [H, W])
#   -> {metric: value}.
Scorer = Callable[[results.EvalConfig, records.StereoSample, Dict[str, np.ndarray],
                   np.ndarray], Dict[str, float]]

PAPER_LABELS = {
    'ours': 'paper: Zhong et al.', 'joulin': 'paper: Joulin & Kang',
    'williem': 'paper: Williem et al.', 'li': 'paper: Li & Brown (layer sep.)',
    'oracle': 'paper: oracle (clean pair)', 'godard': 'paper: Godard et al.',
    'garg': 'paper: Garg et al.', 'zhou': 'paper: Zhou et al.',
    'separation_only': 'paper: separation only', 'joint': 'paper: joint',
}
TRIVIAL_LABEL = 'mixture as each view'
PERCENT_COLUMNS = ('bad-1', 'bad-1 nonocc', 'bad-3', 'D1-all', 'D1-noc')


@dataclasses.dataclass(frozen=True)
class Protocol:
  """One benchmark.

  Attributes:
    name: the `--protocol` value.
    dataset: the `data.sources` dataset its pairs are listed from.
    description: one line for help texts.
    score: the per-image disparity metrics (fractions for rates).
    tables: EvalResult -> the tables to print.
    full_count: images a full run covers (None: whatever is listed); a run over fewer
      needs `EvalConfig.allow_partial`.
    needs_data_dir: False for the embedded data ('sample').
    default_split_list: the package's split list of list-based protocols, relative to
      `data_lists/` (see `data.split_lists`).
    check_record: raises ValueError when a listed pair lacks what `score` reads (run on
      every pair before any is evaluated); None: nothing beyond the images.
  """
  name: str
  dataset: str
  description: str
  score: Scorer
  tables: Callable[[results.EvalResult], List[Table]]
  full_count: Optional[int] = None
  needs_data_dir: bool = True
  default_split_list: Optional[str] = None
  check_record: Optional[Callable[[records.StereoSample], None]] = None


_REGISTRY: Dict[str, Protocol] = {}


def register(protocol: Protocol) -> Protocol:
  """Adds a protocol; its name must be new."""
  if protocol.name in _REGISTRY:
    raise ValueError(f'Protocol {protocol.name!r} is registered twice.')
  _REGISTRY[protocol.name] = protocol
  return protocol


def get(name: str) -> Protocol:
  """The protocol called `name`; ValueError listing the registered ones."""
  if name not in _REGISTRY:
    raise ValueError(f'Unknown EvalConfig.protocol={name!r}; valid: {", ".join(names())}.')
  return _REGISTRY[name]


def names() -> Tuple[str, ...]:
  return tuple(_REGISTRY)


def percent(value: Optional[float]) -> Optional[float]:
  """A fraction as percent (None stays None)."""
  return None if value is None else 100.0 * value


def ours_label(result: results.EvalResult) -> str:
  return f'this run ({result.method})'


def trivial(row: Dict[str, Any]) -> Dict[str, Any]:
  """The trivial baseline's PSNR columns (the mixture itself as each view)."""
  return {'PSNR L': row.get('mixture_psnr_left'), 'PSNR R': row.get('mixture_psnr_right')}


def paper_row(label: str, numbers: Dict[str, float]) -> Dict[str, Any]:
  """A paper entry in table columns (paper percentages are printed as percent already)."""
  names_ = {'psnr_left': 'PSNR L', 'psnr_right': 'PSNR R', 'psnr': 'PSNR', 'bad1': 'bad-1',
            'd1_all': 'D1-all'}
  row = {'Method': label}
  for key, value in numbers.items():
    row[names_.get(key, key)] = value
  return row


def check_coverage(config: results.EvalConfig, count: int) -> None:
  """A protocol with a full count (KITTI 2015: 200) averages fewer images only with
  `allow_partial`; ValueError otherwise."""
  full = get(config.protocol).full_count
  if full is not None and count != full and not config.allow_partial:
    raise ValueError(f'{config.protocol} covers {count} of {full} images: its average would '
                     f"not be comparable with the paper's. Evaluate all {full} images, or set "
                     'EvalConfig.allow_partial to print a table marked '
                     f'"partial: {count} of {full} images".')
