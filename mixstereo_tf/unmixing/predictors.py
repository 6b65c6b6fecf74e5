"""The predictor registry: `build_unmixer` makes the `Unmixer` (`unmixer.py`) that every
tool uses (unmix, evaluate, benchmarks) from a `PredictorConfig`, by method:
  * 'model': a trained network, from a run directory / checkpoint prefix (`runs`), a
    SavedModel (`serving`) or, with neither, a model shipped with the package
    (`pretrained`, `shipped`), run around each image's disparity range (`steps`);
  * 'classical': the training-free method of each mixture family (`families`);
  * 'sgbm': a peer baseline for anaglyphs, OpenCV's untuned StereoSGBM on the eye channels
    (`classical/sgbm.py`), views restored like the classical method's;
  * 'oracle': the stereo module of a trained run on the clean pair (the paper's diplopia
    reference); it takes (left, right) instead of a mixture.
"""

import contextlib
import dataclasses
import hashlib
import os
from typing import Callable, Dict, Optional

import tensorflow as tf

from mixstereo_tf.artifacts import graphs
from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.artifacts import runs
from mixstereo_tf.artifacts import serving
from mixstereo_tf.core import mixtures
from mixstereo_tf.unmixing import disparity_range
from mixstereo_tf.unmixing import eye_order
from mixstereo_tf.unmixing import families
from mixstereo_tf.unmixing import mixture_choice
from mixstereo_tf.unmixing import shipped
from mixstereo_tf.unmixing import steps
from mixstereo_tf.unmixing import unmixer

PredictorConfig = unmixer.PredictorConfig
Unmixer = unmixer.Unmixer

_BUILDERS: Dict[str, Callable[[PredictorConfig], Unmixer]] = {}


def _register(method: str):
  def add(builder):
    _BUILDERS[method] = builder
    return builder
  return add


@contextlib.contextmanager
def _naming(config: PredictorConfig, field: str):
  """Re-raises a ValueError of loading `config.<field>` naming the field (the tools' flag,
  `unmix`'s keyword), unless it already names one."""
  try:
    yield
  except ValueError as e:
    if 'PredictorConfig.' in str(e):
      raise
    raise ValueError(f'PredictorConfig.{field}={getattr(config, field)!r}: {e}') from None


def _load_graph(config: PredictorConfig):
  """(uint8 graph, RunInfo) of a checkpoint or a SavedModel."""
  if bool(config.saved_model) == bool(config.checkpoint):
    raise ValueError('Give exactly one of PredictorConfig.saved_model and '
                     'PredictorConfig.checkpoint.')
  if config.saved_model:
    with _naming(config, 'saved_model'):
      loaded, run_info = serving.load_saved_model(config.saved_model)
    signature = loaded.signatures['serving_default']
    graph = lambda image: signature(image=image)
    graph.loaded = loaded  # Keeps the variables alive while the signature is used.
    return graph, run_info
  with _naming(config, 'checkpoint'):
    model, run_info = runs.load_run(config.checkpoint)
  return tf.function(graphs.serving_function(model),
                     input_signature=[tf.TensorSpec([None, None, 3], tf.uint8)]), run_info


def weights_identity(config: PredictorConfig) -> Optional[str]:
  """'<file> sha256:<16 hex digits>' of the file that holds the weights `config` loads (a
  checkpoint's `.index`, whose per-tensor checksums change with every retraining; a
  SavedModel's `variables/variables.index`; a shipped or folder model's weights), or None
  where no weights are named (the classical methods, the shipped default per mixture).
  Recorded in a run's settings so that results of other weights at the same path are
  told apart (`info_file`, the video jobs' manifests).

  Raises:
    ValueError: a path that holds no such file, naming the field (as loading would).
  """
  field = next((name for name in ('checkpoint', 'saved_model', 'pretrained')
                if getattr(config, name)), None)
  if field is None or (field == 'pretrained' and config.method != 'model'):
    return None
  with _naming(config, field):
    if field == 'checkpoint':
      path = runs.resolve_checkpoint(config.checkpoint)[1] + '.index'
    elif field == 'saved_model':
      path = os.path.join(config.saved_model, 'variables', 'variables.index')
    else:
      path = os.path.join(pretrained.get(config.pretrained).folder, pretrained.WEIGHTS_FILE)
    try:
      with open(path, 'rb') as f:
        digest = hashlib.sha256(f.read()).hexdigest()[:16]
    except OSError as e:
      raise ValueError(f'cannot read {path}: {e.strerror or e}') from None
  return f'{os.path.basename(path)} sha256:{digest}'


def with_weights_named(config: PredictorConfig) -> PredictorConfig:
  """`config` with the shipped model it loads named in `pretrained` where it names no
  weights (method 'model' without checkpoint, SavedModel or name): the settings a run
  records, so that a rerun spelling out the default asks the same (`info_file`, video
  manifests); `config` itself where no shipped model fits (building the predictor says
  why)."""
  if config.method != 'model' or config.pretrained or config.checkpoint or config.saved_model:
    return config
  try:
    return dataclasses.replace(config, pretrained=pretrained.choose(None, config.mixture).name)
  except ValueError:
    return config


@_register('model')
def _model(config: PredictorConfig) -> Unmixer:
  if config.pretrained and (config.checkpoint or config.saved_model):
    raise ValueError('PredictorConfig.pretrained excludes PredictorConfig.checkpoint and '
                     'PredictorConfig.saved_model.')
  if not config.checkpoint and not config.saved_model:
    if config.restore_colour is not None:  # The shipped stages always restore both views.
      raise ValueError('PredictorConfig.restore_colour applies to a trained network '
                       '(PredictorConfig.checkpoint or PredictorConfig.saved_model), not to '
                       'the shipped models, which always restore the views.')
    with _naming(config, 'pretrained' if config.pretrained else 'mixture'):
      entry = pretrained.choose(config.pretrained, config.mixture)
    return shipped.pretrained_unmixer(entry, config)
  if config.checkpoint and not config.saved_model:  # Checked before the model is built.
    with _naming(config, 'checkpoint'):
      trained = runs.read_run_info(runs.resolve_checkpoint(config.checkpoint)[0]).mixtures
    unmixer.check_mixture(config, trained)
  graph, run_info = _load_graph(config)
  return unmixer.model_unmixer(graph, run_info, config)


@_register('classical')
def _classical(config: PredictorConfig) -> Unmixer:
  if config.saved_model or config.checkpoint:
    raise ValueError("PredictorConfig.method='classical' takes neither "
                     'PredictorConfig.saved_model nor PredictorConfig.checkpoint.')
  if config.mixture is None:
    raise ValueError("PredictorConfig.method='classical' needs PredictorConfig.mixture (a "
                     "name or 'auto').")
  supported = families.classical_names()
  if config.mixture not in supported + (mixture_choice.AUTO,):
    raise ValueError(f"PredictorConfig.method='classical' does not support "
                     f'PredictorConfig.mixture={config.mixture}; supported: '
                     f'{", ".join(supported)}.')
  return unmixer.image_unmixer(
      'classical', config.mixture, supported, config, unmixer.classical_range,
      steps.classical_unmix, unmixer.family_of(config.mixture).display_range(),
      unmixer.family_of(config.mixture).restores_views)


@_register('sgbm')
def _sgbm(config: PredictorConfig) -> Unmixer:
  if config.saved_model or config.checkpoint:
    raise ValueError("PredictorConfig.method='sgbm' takes neither "
                     'PredictorConfig.saved_model nor PredictorConfig.checkpoint.')
  supported = families.detected().names
  if config.mixture is None:
    raise ValueError("PredictorConfig.method='sgbm' needs PredictorConfig.mixture (an "
                     "anaglyph encoding or 'auto').")
  if config.mixture not in supported + (mixture_choice.AUTO,):
    raise ValueError(f"PredictorConfig.method='sgbm' needs PredictorConfig.mixture, an "
                     f"anaglyph encoding or 'auto' (got {config.mixture}); supported: "
                     f'{", ".join(supported)}.')
  return unmixer.image_unmixer('sgbm', config.mixture, supported, config, unmixer.classical_range,
                        steps.sgbm_unmix, families.detected().display_range(), True)


@_register('oracle')
def _oracle(config: PredictorConfig) -> Unmixer:
  if not config.checkpoint or config.saved_model:
    raise ValueError("PredictorConfig.method='oracle' needs PredictorConfig.checkpoint (a "
                     'stereo_only or joint training run) and takes no '
                     'PredictorConfig.saved_model.')
  if config.swap_eyes is not False:
    raise ValueError("PredictorConfig.swap_eyes does not apply to method 'oracle' (its "
                     'inputs are the clean pair).')
  with _naming(config, 'checkpoint'):
    model, run_info = runs.load_run(config.checkpoint)
  if run_info.mode == 'separation_only':
    raise ValueError(f"PredictorConfig.method='oracle' runs a checkpoint's stereo network, "
                     f'which the separation_only run {config.checkpoint} never trained.')
  return Unmixer(graphs.pair_function(model), 'oracle', config.mixture or run_info.mixtures[0],
                 run_info.model_config.max_disparity, takes_pair=True)


METHODS = tuple(_BUILDERS)


def build_unmixer(config: PredictorConfig) -> Unmixer:
  """The Unmixer `config` asks for.

  Raises:
    ValueError: unknown method or mixture, or arguments the method does not take; the
      message names the PredictorConfig fields.
  """
  if config.method not in _BUILDERS:
    raise ValueError(f'Unknown PredictorConfig.method={config.method!r}; valid: '
                     f'{", ".join(METHODS)}.')
  if config.mixture not in (None, mixture_choice.AUTO):
    with _naming(config, 'mixture'):
      mixtures.get_mixture(config.mixture)  # ValueError listing the valid names.
  if config.method != 'model' and config.pretrained:
    raise ValueError("PredictorConfig.pretrained applies to method 'model' only.")
  if config.method != 'model' and config.restore_colour is not None:
    raise ValueError("PredictorConfig.restore_colour applies to method 'model' only.")
  if (config.mixing_weight is not None and config.mixture not in (None, mixture_choice.AUTO)
      and not families.of(config.mixture).weighted):
    raise ValueError(f'PredictorConfig.mixing_weight applies to double images; mixture '
                     f'{config.mixture!r} has no mixing weight.')
  if config.mixing_weight is not None and (config.checkpoint or config.saved_model):
    raise ValueError('PredictorConfig.mixing_weight applies to the classical method and the '
                     'shipped models; a network of PredictorConfig.checkpoint or '
                     'PredictorConfig.saved_model was trained on 1/2 and takes none.')
  if config.swap_eyes not in eye_order.SWAP_EYES:
    raise ValueError(f'PredictorConfig.swap_eyes={config.swap_eyes!r}; give False, True or '
                     f'{eye_order.AUTO!r}.')
  if isinstance(config.disparity_range, str):
    if config.disparity_range != disparity_range.NETWORK:
      raise ValueError(f'PredictorConfig.disparity_range={config.disparity_range!r}; give '
                       f'(MIN, MAX), None or {disparity_range.NETWORK!r}.')
  elif config.disparity_range is not None and not (
      config.disparity_range[0] < config.disparity_range[1]):
    raise ValueError(f'PredictorConfig.disparity_range needs MIN < MAX, got '
                     f'{config.disparity_range}.')
  return _BUILDERS[config.method](config)
