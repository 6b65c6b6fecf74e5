"""Inference on images of any size: loading a trained run and the `Unmixer`.

The networks need inputs whose height and width are multiples of `ModelConfig.size_multiple`
(32 for the paper's model). An image of any size is padded at the bottom and the right by
edge replication, run, and the outputs are cropped back. Padding does not move the image
content, so disparities keep their units (pixels of the input image); in the joint model
they are computed from the separated views, so padding affects them only through the
separation network's border context.
"""

import dataclasses
import json
import os
from typing import Callable, Dict, Optional, Tuple

import numpy as np
import tensorflow as tf
from tensorflow.core.protobuf import trackable_object_graph_pb2

from mixstereo_tf import mixtures
from mixstereo_tf import models
from mixstereo_tf.ops import colour_restore

CONFIG_FILE = 'config.json'


@dataclasses.dataclass(frozen=True)
class RunInfo:
  """What a trained model expects: its mixture operator, training crop and architecture."""
  mixture: str
  crop_height: int
  crop_width: int
  model_config: models.ModelConfig

  def to_dict(self) -> Dict[str, object]:
    return {'mixture': self.mixture, 'crop_height': self.crop_height,
            'crop_width': self.crop_width, 'model': self.model_config.to_dict()}

  @classmethod
  def from_dict(cls, values: Dict[str, object]) -> 'RunInfo':
    return cls(str(values['mixture']), int(values['crop_height']), int(values['crop_width']),
               models.ModelConfig.from_dict(values['model']))


def read_run_info(config_path: str) -> RunInfo:
  """Reads a training run's `config.json` (sections 'model' and 'pipeline').

  Raises:
    ValueError: the file is missing, not JSON, or lacks an entry; the message names it.
  """
  if not tf.io.gfile.exists(config_path):
    raise ValueError(f'No {CONFIG_FILE} at {config_path}: not a training run directory.')
  with tf.io.gfile.GFile(config_path) as f:
    try:
      config = json.load(f)
    except json.JSONDecodeError as e:
      raise ValueError(f'{config_path} is not valid JSON: {e}') from None
  try:
    pipeline = config['pipeline']
    return RunInfo(mixture=str(pipeline['mixture']), crop_height=int(pipeline['crop_height']),
                   crop_width=int(pipeline['crop_width']),
                   model_config=models.ModelConfig.from_dict(config['model']))
  except (KeyError, TypeError) as e:
    raise ValueError(f'{config_path} lacks the entry {e} (expected sections "model" and '
                     '"pipeline" with mixture, crop_height, crop_width).') from None


def resolve_checkpoint(model_dir_or_checkpoint: str,
                       checkpoint: Optional[str] = None) -> Tuple[str, str]:
  """(run directory, checkpoint prefix) for a run directory or a checkpoint prefix.

  `checkpoint`, when given, overrides the directory's latest checkpoint.

  Raises:
    ValueError: no checkpoint in the directory, or the named checkpoint does not exist.
  """
  if tf.io.gfile.isdir(model_dir_or_checkpoint):
    model_dir = model_dir_or_checkpoint
    checkpoint = checkpoint or tf.train.latest_checkpoint(model_dir)
    if checkpoint is None:
      raise ValueError(f'No checkpoint in {model_dir} (no "checkpoint" index file).')
  else:
    if checkpoint is not None:
      raise ValueError(f'{model_dir_or_checkpoint} is not a directory; pass a run directory '
                       'together with a checkpoint.')
    checkpoint = model_dir_or_checkpoint
    model_dir = os.path.dirname(checkpoint) or '.'
  if not tf.io.gfile.exists(checkpoint + '.index'):
    raise ValueError(f'Checkpoint not found: {checkpoint} (no {checkpoint}.index).')
  return model_dir, checkpoint


def _stored_variable_count(checkpoint: str, root_child: str) -> int:
  """Variables the checkpoint's object graph reaches from the root's `root_child` node.

  Counted on the graph, not on key names: a variable shared with the optimizer may be
  stored under the optimizer's path.
  """
  graph = trackable_object_graph_pb2.TrackableObjectGraph()
  graph.ParseFromString(tf.train.load_checkpoint(checkpoint).get_tensor(
      '_CHECKPOINTABLE_OBJECT_GRAPH'))
  start = [c.node_id for c in graph.nodes[0].children if c.local_name == root_child]
  seen, stack = set(), list(start)
  while stack:
    node = stack.pop()
    if node not in seen:
      seen.add(node)
      stack.extend(c.node_id for c in graph.nodes[node].children)
  return sum(1 for n in seen
             if any(a.name == 'VARIABLE_VALUE' for a in graph.nodes[n].attributes))


def load_run(model_dir_or_checkpoint: str,
             checkpoint: Optional[str] = None) -> Tuple[models.MixStereoNet, RunInfo]:
  """Builds the model of a training run and restores its weights.

  Args:
    model_dir_or_checkpoint: a run directory (its latest checkpoint is used) or a checkpoint
      prefix such as `runs/demo/ckpt-1000`; `config.json` is read from its folder.
    checkpoint: optional checkpoint prefix overriding the directory's latest.

  Returns:
    (model, run_info).

  Raises:
    ValueError: missing config.json / checkpoint, or weights that do not fit the model.
  """
  model_dir, checkpoint = resolve_checkpoint(model_dir_or_checkpoint, checkpoint)
  run_info = read_run_info(os.path.join(model_dir, CONFIG_FILE))
  model = models.build_model(run_info.model_config)  # Creates the variables.
  status = tf.train.Checkpoint(model=model).read(checkpoint)
  try:
    status.assert_existing_objects_matched()
  except AssertionError as e:
    raise ValueError(f'Checkpoint {checkpoint} does not hold this model\'s weights: '
                     f'{str(e)[:300]}') from None
  status.expect_partial()  # The optimizer's slots are not needed.
  # The check above only covers objects the checkpoint graph reaches from the model; a
  # checkpoint written while layers were untracked (Keras 3 list attributes) lacks some.
  stored = _stored_variable_count(checkpoint, 'model')
  if stored < len(model.variables):
    raise ValueError(f'Checkpoint {checkpoint} holds {stored} of the model\'s '
                     f'{len(model.variables)} weights; it cannot restore this model.')
  return model, run_info


def pad_to_multiple(image: tf.Tensor, multiple: int) -> tf.Tensor:
  """Pads height and width at the bottom / right to multiples of `multiple`.

  Edge replication: padded rows and columns copy the last row / column. Works on dynamic
  shapes (for serving graphs).

  Args:
    image: [B, H, W, C] or [H, W, C], any dtype.
    multiple: positive int.

  Returns:
    The padded image, [.., ceil(H / m) m, ceil(W / m) m, C]; `image[..., :H, :W, :]` of it
    is the input.
  """
  if multiple <= 0:
    raise ValueError(f'multiple must be positive, got {multiple}.')
  image = tf.convert_to_tensor(image)
  shape = tf.shape(image)
  for axis in (-3, -2):
    size = shape[axis]
    padded = (size + multiple - 1) // multiple * multiple
    image = tf.gather(image, tf.minimum(tf.range(padded), size - 1), axis=image.shape.rank + axis)
  return image


def crop_to(image: tf.Tensor, height, width) -> tf.Tensor:
  """Inverse of `pad_to_multiple`: the top-left [.., height, width, C] of `image`."""
  return image[..., :height, :width, :]


def make_unmix_fn(model: tf.keras.Model,
                  multiple: int) -> Callable[[tf.Tensor], Dict[str, tf.Tensor]]:
  """The uint8-in, uint8/pixels-out function shared by `Unmixer` and the SavedModel.

  Returns:
    fn(image uint8 [H, W, 3]) -> {'left', 'right': uint8 [H, W, 3], 'disparity',
    'disparity_right': float32 [H, W] pixels (left- and right-referenced)}.
  """

  def unmix(image: tf.Tensor) -> Dict[str, tf.Tensor]:
    height, width = tf.shape(image)[0], tf.shape(image)[1]
    mixture = tf.cast(pad_to_multiple(image, multiple), tf.float32) / 127.5 - 1.0
    outputs = model(mixture[tf.newaxis], training=False)
    result = {}
    for key in ('left', 'right'):
      view = crop_to(outputs[key][0], height, width)
      result[key] = tf.cast(tf.round(tf.clip_by_value((view + 1.0) * 127.5, 0.0, 255.0)),
                            tf.uint8)
    for key, name in (('disparity_left', 'disparity'), ('disparity_right', 'disparity_right')):
      result[name] = tf.cast(crop_to(outputs[key][0], height, width)[..., 0], tf.float32)
    return result

  return unmix


def _restore_colour(image: np.ndarray, outputs: Dict[str, np.ndarray],
                    spec: mixtures.MixtureSpec) -> Dict[str, np.ndarray]:
  """Paper section 4.2: channels the mixture kept, warped by the estimated disparities."""
  as_float = lambda u8: tf.cast(u8, tf.float32) / 127.5 - 1.0
  restored = colour_restore.restore_views(
      as_float(image), outputs['disparity_left'][..., None],
      outputs['disparity_right'][..., None], spec, fallback_left=as_float(outputs['left']),
      fallback_right=as_float(outputs['right']))
  return {key: tf.cast(tf.round(tf.clip_by_value((restored[key] + 1.0) * 127.5, 0.0, 255.0)),
                       tf.uint8).numpy() for key in ('left', 'right')}


class Unmixer:
  """Separates a mixture image of any size into two views and their disparities.

  Backed by a Keras model (`from_model`) or an exported SavedModel (`from_saved_model`);
  both run the same padded uint8 graph (`make_unmix_fn`).
  """

  def __init__(self, unmix_fn: Callable[[tf.Tensor], Dict[str, tf.Tensor]], run_info: RunInfo,
               restore_colour: Optional[bool] = None):
    """Args: unmix_fn as made by `make_unmix_fn`; run_info of the model; restore_colour:
    rebuild the views' exact channels from the mixture (default: for channel anaglyphs)."""
    self._unmix_fn = unmix_fn
    self.run_info = run_info
    self.spec = mixtures.get_mixture(run_info.mixture)
    self.restore_colour = (self.spec.is_channel_anaglyph if restore_colour is None
                           else bool(restore_colour))

  @classmethod
  def from_model(cls, model: models.MixStereoNet, run_info: RunInfo,
                 restore_colour: Optional[bool] = None) -> 'Unmixer':
    fn = tf.function(make_unmix_fn(model, run_info.model_config.size_multiple),
                     input_signature=[tf.TensorSpec([None, None, 3], tf.uint8)])
    return cls(fn, run_info, restore_colour)

  @classmethod
  def from_saved_model(cls, export_dir: str, restore_colour: Optional[bool] = None
                       ) -> 'Unmixer':
    """Loads a SavedModel written by `serving.export_saved_model`."""
    from mixstereo_tf import serving  # pylint: disable=g-import-not-at-top (cycle)
    loaded, run_info = serving.load_saved_model(export_dir)
    signature = loaded.signatures['serving_default']
    unmixer = cls(lambda image: signature(image=image), run_info, restore_colour)
    unmixer._loaded = loaded  # Keeps the variables alive while the signature is used.
    return unmixer

  def __call__(self, image: np.ndarray) -> Dict[str, np.ndarray]:
    """Unmixes one mixture image.

    Args:
      image: uint8 [H, W, 3] RGB (or [H, W] / [H, W, 1] gray, replicated to RGB), any size.

    Returns:
      'left', 'right': uint8 [H, W, 3]; 'disparity_left', 'disparity_right': float32 [H, W]
      pixels, positive (left pixel x matches right x - d_L; right x matches left x + d_R).
    """
    image = np.asarray(image)
    if image.dtype != np.uint8:
      raise ValueError(f'Unmixer expects a uint8 image, got {image.dtype}.')
    if image.ndim == 2:
      image = image[:, :, None]
    if image.ndim != 3 or image.shape[2] not in (1, 3):
      raise ValueError(f'Unmixer expects [H, W, 3] or gray [H, W], got {image.shape}.')
    if image.shape[2] == 1:
      image = np.repeat(image, 3, axis=2)
    raw = self._unmix_fn(tf.constant(image))
    outputs = {'left': raw['left'].numpy(), 'right': raw['right'].numpy(),
               'disparity_left': raw['disparity'].numpy(),
               'disparity_right': raw['disparity_right'].numpy()}
    if self.restore_colour:
      outputs.update(_restore_colour(image, outputs, self.spec))
    return outputs
