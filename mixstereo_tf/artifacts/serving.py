"""SavedModel export and loading: a self-contained unmixing graph for images of any size.

The exported SavedModel loads with plain `tf.saved_model.load` (no mixstereo_tf import):
  * signature `serving_default`: `image` uint8 [H, W, 3] (any H, W) ->
    `left`, `right` uint8 [H, W, 3] (the separation network's views),
    `disparity` float32 [H, W] (left-referenced, pixels, positive: left pixel x matches
    right pixel x - d), `disparity_right` float32 [H, W] (right pixel x matches left x + d).
    Padding to the network's multiple (edge replication, bottom / right) and cropping back
    happen inside the graph (`graphs.serving_function` builds it).
  * signature `metadata`: no inputs -> `mixture` (string), `crop_height`, `crop_width`,
    `max_disparity`, `size_multiple` (int32) and `model_config` (JSON string).
  * the same values as attributes of the loaded object (`loaded.mixture` etc., variables)
    and as `assets.extra/run_info.json` beside the graph.
"""

import json
import os
from typing import Callable, Dict, Sequence, Tuple

import tensorflow as tf

from mixstereo_tf import models
from mixstereo_tf.artifacts import runs

RUN_INFO_FILE = 'run_info.json'
UnmixGraph = Callable[[tf.Tensor], Dict[str, tf.Tensor]]


class _Exported(tf.Module):
  """The SavedModel root: the weights, the unmix function and the run's metadata."""

  def __init__(self, unmix: UnmixGraph, variables: Sequence[tf.Variable],
               run_info: runs.RunInfo):
    super().__init__(name='mixstereo_export')
    # Track the weights, not the Keras model: Keras 3 layers would add their own serving
    # functions to the export, which fail for the two-input stereo network.
    self.model_variables = list(variables)
    config = run_info.model_config
    constant = lambda value, dtype: tf.Variable(value, dtype=dtype, trainable=False)
    self.mixture = constant(run_info.mixture, tf.string)
    self.crop_height = constant(run_info.crop_height, tf.int32)
    self.crop_width = constant(run_info.crop_width, tf.int32)
    self.max_disparity = constant(config.max_disparity, tf.int32)
    self.size_multiple = constant(config.size_multiple, tf.int32)
    self.model_config = constant(json.dumps(config.to_dict(), sort_keys=True), tf.string)
    self._unmix = unmix

  @tf.function(input_signature=[tf.TensorSpec([None, None, 3], tf.uint8, name='image')])
  def unmix(self, image):
    return self._unmix(image)

  @tf.function(input_signature=[])
  def metadata(self):
    return {'mixture': self.mixture.read_value(),
            'crop_height': self.crop_height.read_value(),
            'crop_width': self.crop_width.read_value(),
            'max_disparity': self.max_disparity.read_value(),
            'size_multiple': self.size_multiple.read_value(),
            'model_config': self.model_config.read_value()}


def export_saved_model(unmix: UnmixGraph, variables: Sequence[tf.Variable],
                       run_info: runs.RunInfo, export_dir: str) -> str:
  """Writes the SavedModel described in the module docstring to `export_dir`.

  Args:
    unmix: the uint8 graph function (`graphs.serving_function(model)`).
    variables: the model's variables `unmix` reads (saved with the graph).
    run_info: the run's mixture, training crop and architecture.
    export_dir: output directory (created; if it exists, an empty folder).

  Returns:
    export_dir.

  Raises:
    ValueError: `export_dir` already holds a SavedModel, or other files, or is a file.
  """
  if tf.io.gfile.exists(os.path.join(export_dir, 'saved_model.pb')):
    raise ValueError(f'{export_dir} already holds a SavedModel; choose a new export_dir.')
  if tf.io.gfile.exists(export_dir):
    if not tf.io.gfile.isdir(export_dir):
      raise ValueError(f'{export_dir} is a file; choose a new export_dir.')
    if tf.io.gfile.listdir(export_dir):
      raise ValueError(f'{export_dir} is not empty (its files would be mixed with the '
                       'SavedModel\'s); choose a new export_dir.')
  root = _Exported(unmix, variables, run_info)
  tf.saved_model.save(root, export_dir, signatures={
      'serving_default': root.unmix.get_concrete_function(),
      'metadata': root.metadata.get_concrete_function()})
  extra = os.path.join(export_dir, 'assets.extra')
  tf.io.gfile.makedirs(extra)
  with tf.io.gfile.GFile(os.path.join(extra, RUN_INFO_FILE), 'w') as f:
    f.write(json.dumps(run_info.to_dict(), indent=2, sort_keys=True))
  return export_dir


def load_saved_model(export_dir: str) -> Tuple[tf.Module, runs.RunInfo]:
  """Loads an export and its RunInfo (from the `metadata` signature).

  Returns:
    (the loaded object; keep it alive while its signatures are used, run_info).

  Raises:
    ValueError: `export_dir` holds no SavedModel or one without the `metadata` signature.
  """
  if not tf.io.gfile.exists(os.path.join(export_dir, 'saved_model.pb')):
    raise ValueError(f'No SavedModel at {export_dir} (no saved_model.pb).')
  loaded = tf.saved_model.load(export_dir)
  if 'metadata' not in loaded.signatures:
    raise ValueError(f'The SavedModel at {export_dir} has no "metadata" signature; it was '
                     'not written by mixstereo_tf.export.')
  meta = loaded.signatures['metadata']()
  run_info = runs.RunInfo(
      mixture=meta['mixture'].numpy().decode('utf-8'),
      crop_height=int(meta['crop_height']), crop_width=int(meta['crop_width']),
      model_config=models.ModelConfig.from_dict(
          json.loads(meta['model_config'].numpy().decode('utf-8'))),
      mode=_exported_mode(export_dir))
  return loaded, run_info


def _exported_mode(export_dir: str) -> str:
  """What the exported run trained (`RunInfo.mode`), from `assets.extra/run_info.json`;
  'joint' where it is not recorded (exports before it was)."""
  path = os.path.join(export_dir, 'assets.extra', RUN_INFO_FILE)
  try:
    with tf.io.gfile.GFile(path) as f:
      return str(json.load(f).get('mode', 'joint'))
  except (tf.errors.OpError, ValueError, AttributeError):
    return 'joint'
