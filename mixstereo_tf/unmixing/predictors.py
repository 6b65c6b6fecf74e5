"""Inference on images of any size: padding, the model's graphs and the `Unmixer`.

The networks need inputs whose height and width are multiples of `ModelConfig.size_multiple`
(32 for the paper's model). An image of any size is padded at the bottom and the right by
edge replication, run, and the outputs are cropped back. Padding does not move the image
content, so disparities keep their units (pixels of the input image).

The `Unmixer` is the one predictor object every tool uses (unmix, evaluate, benchmarks);
`build_unmixer` makes one from a `PredictorConfig` through a registry of methods:
  * 'model': a trained network, from a run directory / checkpoint prefix (`runs`), a
    SavedModel (`serving`) or, with neither, a model shipped with the package
    (`pretrained`), run around each image's disparity range (`steps`);
  * 'classical': the training-free method of each mixture family (`families`);
  * 'sgbm': a peer baseline for anaglyphs, OpenCV's untuned StereoSGBM on the eye channels
    (`classical/sgbm.py`), views restored like the classical method's;
  * 'oracle': the stereo module of a trained run on the clean pair (the paper's diplopia
    reference); it takes (left, right) instead of a mixture.
"""

import dataclasses
from typing import Callable, Dict, Optional, Sequence, Tuple, Union

import numpy as np
import tensorflow as tf

from mixstereo_tf.artifacts import graphs
from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.artifacts import runs
from mixstereo_tf.artifacts import serving
from mixstereo_tf.core import mixtures
from mixstereo_tf.models import refiner
from mixstereo_tf.unmixing import disparity_range
from mixstereo_tf.unmixing import families
from mixstereo_tf.unmixing import steps

Outputs = Dict[str, np.ndarray]


def as_rgb(image) -> np.ndarray:
  """A uint8 mixture as [H, W, 3]; gray [H, W] / [H, W, 1] is replicated to RGB."""
  image = np.asarray(image)
  if image.dtype != np.uint8:
    raise ValueError(f'Unmixer expects a uint8 image, got {image.dtype}.')
  if image.ndim == 2:
    image = image[:, :, None]
  if image.ndim != 3 or image.shape[2] not in (1, 3):
    raise ValueError(f'Unmixer expects [H, W, 3] or gray [H, W], got {image.shape}.')
  return np.repeat(image, 3, axis=2) if image.shape[2] == 1 else image


@dataclasses.dataclass(frozen=True)
class PredictorConfig:
  """Which unmixer to build (the tools' predictor flags).

  Attributes:
    method: a name of METHODS.
    checkpoint: run directory or checkpoint prefix ('model', 'oracle').
    saved_model: SavedModel directory ('model'); exclusive with checkpoint.
    mixture: the inputs' mixture operator; 'auto': detected per image (anaglyphs); None:
      the model's own (required for 'classical'). A model refuses encodings it was not
      trained on.
    restore_colour: restore both views from the encoding and the disparities with the
      network's views as the prior (paper 4.2; None: on for anaglyphs); 'model' only.
    disparity_range: (min, max) signed pixels of the input; None: estimated per image;
      disparity_range.NETWORK: the method's own (a network's [0, D - 1], input as is).
    max_network_pixels: a model's input is reduced to at most this many pixels.
    pretrained: a shipped model's name or folder ('model' without checkpoint and
      saved_model; None: the first shipped model for the mixture, `pretrained.choose`).
  """
  method: str = 'model'
  checkpoint: Optional[str] = None
  saved_model: Optional[str] = None
  mixture: Optional[str] = None
  restore_colour: Optional[bool] = None
  disparity_range: Union[None, str, Tuple[int, int]] = None
  max_network_pixels: Optional[int] = 2_000_000
  pretrained: Optional[str] = None


@dataclasses.dataclass(frozen=True)
class Unmixer:
  """A predictor: `unmixer(mixture_u8)`, or `unmixer(left_u8, right_u8)` when takes_pair.

  Called on a uint8 mixture [H, W, 3] it returns {'left', 'right': uint8 [H, W, 3],
  'disparity_left', 'disparity_right': float32 [H, W] signed pixels, 'info': what was done
  (`steps`)}; an 'oracle' returns the disparities of the clean pair. A video frame
  may be given a `hints.FrameHint` (`unmixer(frame, hint=hint)`: its shot's encoding,
  range and prior); `fn` is then called with `hint=` as well.

  Attributes:
    fn: the function behind the call.
    method: the METHODS name that built it.
    mixture: the mixture its inputs are made with ('auto': detected per image).
    max_disparity: the largest disparity of its default range, pixels (display range).
    restore_colour: whether it restores the views from the encoding (paper 4.2).
    takes_pair: True for 'oracle' (inputs are the clean views).
  """
  fn: Callable[..., Outputs]
  method: str
  mixture: str
  max_disparity: float
  restore_colour: bool = False
  takes_pair: bool = False

  def __call__(self, *images: np.ndarray, hint=None) -> Outputs:
    return self.fn(*images) if hint is None else self.fn(*images, hint=hint)


_BUILDERS: Dict[str, Callable[[PredictorConfig], Unmixer]] = {}


def _register(method: str):
  def add(builder):
    _BUILDERS[method] = builder
    return builder
  return add


def _load_graph(config: PredictorConfig):
  """(uint8 graph, RunInfo) of a checkpoint or a SavedModel."""
  if bool(config.saved_model) == bool(config.checkpoint):
    raise ValueError('Give exactly one of PredictorConfig.saved_model and '
                     'PredictorConfig.checkpoint.')
  if config.saved_model:
    loaded, run_info = serving.load_saved_model(config.saved_model)
    signature = loaded.signatures['serving_default']
    graph = lambda image: signature(image=image)
    graph.loaded = loaded  # Keeps the variables alive while the signature is used.
    return graph, run_info
  model, run_info = runs.load_run(config.checkpoint)
  return tf.function(graphs.serving_function(model),
                     input_signature=[tf.TensorSpec([None, None, 3], tf.uint8)]), run_info


def _check_mixture(config: PredictorConfig, trained: Sequence[str]) -> str:
  """The mixture asked for (default: the model's first); refuses one it was not trained on."""
  requested = config.mixture or trained[0]
  if requested != steps.AUTO and requested not in trained:
    raise ValueError(f'PredictorConfig.mixture={requested} but the model was trained on '
                     f'{", ".join(repr(m) for m in trained)} mixtures '
                     f'({config.saved_model or config.checkpoint or "this model"}).')
  return requested


@_register('model')
def _model(config: PredictorConfig) -> Unmixer:
  if config.pretrained and (config.checkpoint or config.saved_model):
    raise ValueError('PredictorConfig.pretrained excludes PredictorConfig.checkpoint and '
                     'PredictorConfig.saved_model.')
  if not config.checkpoint and not config.saved_model:
    return pretrained_unmixer(pretrained.choose(config.pretrained, config.mixture), config)
  if config.checkpoint and not config.saved_model:  # Checked before the model is built.
    _check_mixture(config, runs.read_run_info(
        runs.resolve_checkpoint(config.checkpoint)[0]).mixtures)
  graph, run_info = _load_graph(config)
  return model_unmixer(graph, run_info, config)


def model_unmixer(graph: Callable[[tf.Tensor], Dict[str, tf.Tensor]], run_info: runs.RunInfo,
                  config: PredictorConfig = PredictorConfig()) -> Unmixer:
  """The 'model' Unmixer around a uint8 serving graph (`graphs.serving_function`) of a run."""
  trained = run_info.mixtures
  requested = _check_mixture(config, trained)
  levels = run_info.model_config.max_disparity
  restore = config.restore_colour
  if restore is None:
    restore = any(families.of(m).restores_views for m in trained)

  def solve(image, name, search, hint):
    del hint  # The network takes no prior.
    return steps.model_unmix(graph, image, name, search, levels,
                                   config.max_network_pixels, bool(restore))

  return _image_unmixer('model', requested, trained, config, lambda _: (0, levels - 1),
                        solve, levels, bool(restore))


def _image_unmixer(method: str, requested: str, allowed: Sequence[str],
                   config: PredictorConfig, default_range: Callable[[str], Tuple[int, int]],
                   solve: Callable[..., Outputs], display: float, restore: bool) -> Unmixer:
  """An Unmixer of mixture images: `steps.run`'s steps around `solve`."""
  fn = lambda image, hint=None: steps.run(as_rgb(image), requested, allowed,
                                                config.disparity_range, default_range,
                                                method, solve, hint)
  return Unmixer(fn, method, requested, display, restore)


def pretrained_unmixer(entry: pretrained.Pretrained,
                       config: PredictorConfig = PredictorConfig()) -> Unmixer:
  """The 'model' Unmixer of a shipped model (`pretrained`): a joint network runs like a
  trained run; a refiner runs on the classical method's result (`steps`), on the
  encoding detected in each image when no mixture is given and it knows several."""
  model = pretrained.load_model(entry)
  if entry.kind == 'joint':
    run_info = runs.RunInfo(entry.mixture, entry.crop[0], entry.crop[1], model.model_config)
    graph = tf.function(graphs.serving_function(model),
                        input_signature=[tf.TensorSpec([None, None, 3], tf.uint8)])
    return model_unmixer(graph, run_info, config)
  trained = entry.mixtures
  lacking = [m for m in trained if entry.kind not in families.of(m).learned_stages]
  if lacking:
    raise ValueError(f'{entry.name}: mixtures {", ".join(lacking)} have no {entry.kind} stage.')
  if config.mixture is None and len(trained) > 1:  # Several encodings: detect each image's.
    config = dataclasses.replace(config, mixture=steps.AUTO)
  requested = _check_mixture(config, trained)
  signature = [tf.TensorSpec([1, None, None, refiner.INPUT_CHANNELS], tf.float32)]
  network = tf.function(lambda x: model(x, training=False), input_signature=signature)

  def solve(image, name, search, hint):
    outputs = steps.refiner_unmix(network, model.size_multiple, image, name, search,
                                        hint)
    outputs['info'] = {'pretrained': entry.name}
    return outputs

  return _image_unmixer('model', requested, trained, config, _classical_range, solve,
                        _family(trained[0]).display_range(),
                        any(families.of(m).restores_views for m in trained))


def _family(mixture: str) -> families.Family:
  """The family of a mixture name; for 'auto', the one detection finds."""
  return families.detected() if mixture == steps.AUTO else families.of(mixture)


def _classical_range(mixture: str) -> Tuple[int, int]:
  """The classical method's own range for a mixture (`Family.classical_range`)."""
  return families.of(mixture).classical_range()


@_register('classical')
def _classical(config: PredictorConfig) -> Unmixer:
  if config.saved_model or config.checkpoint:
    raise ValueError("PredictorConfig.method='classical' takes neither "
                     'PredictorConfig.saved_model nor PredictorConfig.checkpoint.')
  if config.mixture is None:
    raise ValueError("PredictorConfig.method='classical' needs PredictorConfig.mixture (a "
                     "name or 'auto').")
  supported = families.classical_names()
  if config.mixture not in supported + (steps.AUTO,):
    raise ValueError(f"PredictorConfig.method='classical' does not support "
                     f'PredictorConfig.mixture={config.mixture}; supported: '
                     f'{", ".join(supported)}.')
  return _image_unmixer(
      'classical', config.mixture, supported, config, _classical_range,
      steps.classical_unmix, _family(config.mixture).display_range(),
      _family(config.mixture).restores_views)


@_register('sgbm')
def _sgbm(config: PredictorConfig) -> Unmixer:
  if config.saved_model or config.checkpoint:
    raise ValueError("PredictorConfig.method='sgbm' takes neither "
                     'PredictorConfig.saved_model nor PredictorConfig.checkpoint.')
  supported = families.detected().names
  if config.mixture not in supported + (steps.AUTO,):
    raise ValueError(f"PredictorConfig.method='sgbm' needs PredictorConfig.mixture, an "
                     f"anaglyph encoding or 'auto' (got {config.mixture}); supported: "
                     f'{", ".join(supported)}.')
  return _image_unmixer('sgbm', config.mixture, supported, config, _classical_range,
                        steps.sgbm_unmix, families.detected().display_range(), True)


@_register('oracle')
def _oracle(config: PredictorConfig) -> Unmixer:
  if not config.checkpoint or config.saved_model:
    raise ValueError("PredictorConfig.method='oracle' needs PredictorConfig.checkpoint (a "
                     'stereo_only training run) and takes no PredictorConfig.saved_model.')
  model, run_info = runs.load_run(config.checkpoint)
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
  if config.mixture not in (None, steps.AUTO):
    mixtures.get_mixture(config.mixture)  # ValueError listing the valid names.
  if config.method != 'model' and config.pretrained:
    raise ValueError("PredictorConfig.pretrained applies to method 'model' only.")
  if config.method != 'model' and config.restore_colour is not None:
    raise ValueError("PredictorConfig.restore_colour applies to method 'model' only.")
  if isinstance(config.disparity_range, str):
    if config.disparity_range != disparity_range.NETWORK:
      raise ValueError(f'PredictorConfig.disparity_range={config.disparity_range!r}; give '
                       f'(MIN, MAX), None or {disparity_range.NETWORK!r}.')
  elif config.disparity_range is not None and not (
      config.disparity_range[0] < config.disparity_range[1]):
    raise ValueError(f'PredictorConfig.disparity_range needs MIN < MAX, got '
                     f'{config.disparity_range}.')
  return _BUILDERS[config.method](config)
