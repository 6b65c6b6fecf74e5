"""The Unmixers of the models shipped with the package (`artifacts/pretrained`), by kind:
  * 'joint': the paper's network, run like a trained run (`unmixer.model_unmixer`);
  * 'refiner': the classical method, then the refiner on its result (`refiner_stage.refiner_unmix`);
  * 'features': the learned matching stage of anaglyphs (`learned_matching`): learned
    descriptors of both eyes, cosine costs, SGM, views restored from the encoding; it
    plans its disparity range with the same costs (`Stage.plan`);
  * 'echo_features': the learned echo stage of double images (`learned_diplopia`): learned
    self-similarity costs, SGM, mixing weight, layer separation.
A model that knows several encodings detects each image's when no mixture is given.
"""

import dataclasses
from typing import Callable, Dict, Optional, Tuple

import tensorflow as tf

from mixstereo_tf.artifacts import graphs
from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.artifacts import runs
from mixstereo_tf.core import precision
from mixstereo_tf.models import layers_util
from mixstereo_tf.models import refiner
from mixstereo_tf.unmixing import families
from mixstereo_tf.unmixing import learned_diplopia
from mixstereo_tf.unmixing import learned_matching
from mixstereo_tf.unmixing import mixture_choice
from mixstereo_tf.unmixing import refiner_stage
from mixstereo_tf.unmixing import steps
from mixstereo_tf.unmixing import unmixer

Solve = Callable[..., Dict[str, object]]


@dataclasses.dataclass(frozen=True)
class Stage:
  """A shipped stage as serving and the refiner's training examples run it.

  Attributes:
    solve: the `steps.run` solver, `solve(image, name, search, hint)` -> outputs.
    plan: its range planning (`steps.estimate_range`'s `plan`); None: the family's.
  """
  solve: Solve
  plan: Optional[steps.Planner] = None


def _refiner_stage(model: tf.keras.Model, base: Optional[Stage] = None) -> Stage:
  """`refiner_stage.refiner_unmix` with the model traced once per set of outputs it may
  leave out ((): none), planning as its base. TensorFlow prunes what left-out outputs
  alone need: without a video frame's right disparity the network took 0.45 s instead of
  0.68 s at 1280x720; without both, only the views' network runs."""
  signature = [tf.TensorSpec([1, None, None, refiner.INPUT_CHANNELS], tf.float32)]
  functions = {}

  def network(skipped: Tuple[str, ...]):
    if skipped not in functions:
      functions[skipped] = tf.function(
          lambda x: {k: v for k, v in model(x, training=False).items() if k not in skipped},
          input_signature=signature)
    return functions[skipped]

  base_solve = base.solve if base else None
  return Stage(lambda image, name, search, hint: refiner_stage.refiner_unmix(
      network, model.size_multiple, image, name, search, hint, base_solve),
               base.plan if base else None)


def _learned_range(descriptors: learned_matching.Descriptors) -> steps.Planner:
  """The learned matching stage's own range planning (`learned_matching.estimate_range`)."""
  return lambda image, name, hint: learned_matching.estimate_range(
      descriptors, image, name, families.of(name).matching(hint))


def _replacing_stage(function_of: Callable, unmix: Callable, stage_name: str,
                     plan_of: Optional[Callable[[Callable], steps.Planner]] = None):
  """The builder of a stage that replaces the classical matching: `function_of` traces the
  model once, `unmix(function, image, name, search, hint)` runs the stage and
  `plan_of(function)`, when given, is its own range planning (else the family's)."""

  def build(model: tf.keras.Model, base: Optional[Stage] = None) -> Stage:
    if base is not None:
      raise ValueError(f'The {stage_name} replaces the classical matching; it cannot run on '
                       'top of another stage.')
    function = function_of(model)
    return Stage(lambda image, name, search, hint: unmix(function, image, name, search, hint),
                 plan_of(function) if plan_of else None)

  return build


# kind -> the builder of its Stage from the loaded model; the optional second argument:
# the stage it runs on instead of the classical method (a refiner plans as its base).
_STAGES: Dict[str, Callable[[tf.keras.Model, Optional[Stage]], Stage]] = {
    'refiner': _refiner_stage,
    'features': _replacing_stage(learned_matching.descriptor_function,
                                 learned_matching.learned_unmix, 'learned matching stage',
                                 _learned_range),
    'echo_features': _replacing_stage(learned_diplopia.echo_function,
                                      learned_diplopia.learned_unmix, 'learned echo stage')}


def stage(entry: pretrained.Pretrained, base: Optional[Stage] = None) -> Stage:
  """A shipped stage (kind 'refiner', 'features' or 'echo_features'), on `base` instead of
  the classical method when given, its convolutions in bfloat16 where the CPU has native
  bfloat16 (`core/precision.py`). Serving and the refiner's training examples
  (`training/refiner_data.py`) both run stages through it.

  Raises:
    ValueError: a kind without such a stage ('joint').
  """
  if entry.kind not in _STAGES:
    raise ValueError(f'{entry.name}: a {entry.kind} model is no stage of the classical '
                     f'route; stages: {", ".join(_STAGES)}.')
  model = pretrained.load_model(entry)
  if precision.inference_bfloat16():
    layers_util.compute_in_bfloat16(model)
  return _STAGES[entry.kind](model, base)


def pretrained_unmixer(entry: pretrained.Pretrained,
                       config: unmixer.PredictorConfig = unmixer.PredictorConfig(),
                       base: Optional[pretrained.Pretrained] = None) -> unmixer.Unmixer:
  """The 'model' Unmixer of a shipped model (module docstring); with `base` (default: the
  model's own `Pretrained.base`), a shipped stage that `entry` (a refiner) runs on instead
  of the classical method.

  Raises:
    ValueError: a mixture the model does not unmix, or one without the model's stage.
  """
  if base is None and entry.base:
    base = pretrained.get(entry.base)
  if entry.kind == 'joint':
    model = pretrained.load_model(entry)
    run_info = runs.RunInfo(entry.mixture, entry.crop[0], entry.crop[1], model.model_config)
    graph = tf.function(graphs.serving_function(model),
                        input_signature=[tf.TensorSpec([None, None, 3], tf.uint8)])
    return unmixer.model_unmixer(graph, run_info, config)
  trained = entry.mixtures
  lacking = [m for m in trained if entry.kind not in families.of(m).learned_stages]
  if lacking:
    raise ValueError(f'{entry.name}: mixtures {", ".join(lacking)} have no {entry.kind} stage.')
  if config.mixture is None and len(trained) > 1:  # Several encodings: detect each image's.
    config = dataclasses.replace(config, mixture=mixture_choice.AUTO)
  requested = unmixer.check_mixture(config, trained)
  built = stage(entry, base and stage(base))

  def solve(image, name, search, hint):
    outputs = built.solve(image, name, search, hint)
    outputs['info'] = dict(outputs.get('info', {}),
                           pretrained=entry.name + (f' on {base.name}' if base else ''))
    return outputs

  return unmixer.image_unmixer('model', requested, trained, config, unmixer.classical_range,
                               solve, unmixer.family_of(trained[0]).display_range(),
                               any(families.of(m).restores_views for m in trained), built.plan)
