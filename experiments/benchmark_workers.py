"""The measurements of experiments/benchmark.py; each runs alone in a fresh process.

`WORKERS` maps a name to a function returning a JSON-able dict; `experiments/benchmark.py`
dispatches to it (and to `benchmark_ops.WORKERS`) and adds 'peak_gib', the process' peak
resident memory (VmHWM). Times are seconds: the first call (tracing / compilation)
apart, then the median, min and max of timed repeats after one warm-up call.
"""

import os
import statistics
import tempfile
import time

import numpy as np
import tensorflow as tf

from experiments import bench_data
from mixstereo_tf import models
from mixstereo_tf.artifacts import graphs
from mixstereo_tf.artifacts import runs
from mixstereo_tf.artifacts import serving
from mixstereo_tf.core import image_range
from mixstereo_tf.core import mixtures
from mixstereo_tf.data import kitti
from mixstereo_tf.data import pipeline
from mixstereo_tf.data import sample
from mixstereo_tf.data import sources
from mixstereo_tf.ops import conv3d
from mixstereo_tf.ops import cost_volume
from mixstereo_tf.training import objective
from mixstereo_tf.training import step as step_lib
from mixstereo_tf.unmixing import families

_DEMO_FLAGS = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'demo.flags')


def peak_gib() -> float:
  """Peak resident memory of this process (VmHWM) in GiB."""
  with open('/proc/self/status') as f:
    for line in f:
      if line.startswith('VmHWM:'):
        return int(line.split()[1]) / 2**20
  raise ValueError('/proc/self/status has no VmHWM line.')


def configuration(name: str, implementation: str = 'auto'):
  """(ModelConfig, (crop_height, crop_width)) of 'paper' or 'demo' (experiments/demo.flags)."""
  if name == 'paper':
    return models.ModelConfig(conv3d_implementation=implementation), (256, 512)
  if name != 'demo':
    raise ValueError(f"configuration must be 'paper' or 'demo', got {name!r}.")
  values = {}
  with open(_DEMO_FLAGS) as f:
    for line in f:
      if line.startswith('--') and '=' in line:
        key, value = line[2:].strip().split('=', 1)
        values[key] = value
  ints = lambda key: tuple(int(v) for v in values[key].split(','))
  config = models.ModelConfig(
      separation_widths=ints('unet_widths'), stereo_features=int(values['stereo_features']),
      stereo_residual_blocks=int(values['num_res_blocks']),
      stereo_3d_widths=ints('volume_features'), max_disparity=int(values['max_disparity']),
      conv3d_implementation=implementation)
  return config, (int(values['crop_height']), int(values['crop_width']))


def timed(fn, repeats: int, warmup: bool = True) -> dict:
  """Calls fn() once (timed as 'first'), once more if `warmup`, then `repeats` timed times.

  fn must block until its result is ready.
  """
  start = time.perf_counter()
  fn()
  first = time.perf_counter() - start
  if warmup:
    fn()
  times = []
  for _ in range(repeats):
    start = time.perf_counter()
    fn()
    times.append(time.perf_counter() - start)
  return {'first': first, 'median': statistics.median(times), 'min': min(times),
          'max': max(times), 'repeats': repeats}


def _block(structure) -> None:
  for tensor in tf.nest.flatten(structure):
    if tensor is not None:
      tensor.numpy()


def train_batch(crop, max_disparity: int):
  """One real batch of the `sample` source at the crop size (batch 1)."""
  samples = sample.sample_records('train', num_scenes=2, height=crop[0], width=crop[1],
                                  max_disparity=max_disparity)
  config = pipeline.PipelineConfig(crop_height=crop[0], crop_width=crop[1])
  # As the training loop does: the whole element, its string 'name' included.
  return next(iter(pipeline.train_dataset(samples, config)))


def train(config: str, jit: bool, steps: int, implementation: str = 'auto') -> dict:
  """Joint TrainStep (forward, paper objective, backward, RMSProp update)."""
  if implementation == 'auto':  # As the training loop resolves it.
    implementation = conv3d.auto_implementation('CPU', jit)
  model_config, crop = configuration(config, implementation)
  model = models.build_model(model_config)
  batch = train_batch(crop, model_config.max_disparity)
  optimizer = tf.keras.optimizers.RMSprop(1e-4)
  trainer = step_lib.TrainStep(model, optimizer, objective.LossConfig(), 'joint',
                               tf.distribute.get_strategy(), jit)
  optimizer.build(trainer.variables)
  # At paper scale a step takes tens of seconds: the first call is the only warm-up.
  result = timed(lambda: float(trainer(batch)[0]['loss']), steps, warmup=config == 'demo')
  result['steps_per_s'] = 1.0 / result['median']
  return result


def gradient_fn(forward, sources):
  """tf.function: forward() and the gradient of its sum w.r.t. `sources`."""

  @tf.function
  def fn():
    with tf.GradientTape() as tape:
      tape.watch([s for s in sources if isinstance(s, tf.Tensor)])
      out = forward()
      total = tf.add_n([tf.reduce_sum(tf.cast(t, tf.float32)) for t in tf.nest.flatten(out)])
    return tape.gradient(total, sources)

  return lambda: _block(fn())


def modules(config: str, repeats: int = 1) -> dict:
  """Forward+backward of each part alone, at the step's shapes (one module per timing)."""
  model_config, (height, width) = configuration(config)
  model = models.build_model(model_config)
  net = model.stereo
  rng = tf.random.Generator.from_seed(0)
  image = lambda n: rng.uniform([n, height, width, 3], -1.0, 1.0)
  mixture, pair = image(1), image(4)  # The tower sees 2 views x (direct, mirrored).
  feature_count, levels = model_config.stereo_features, model_config.max_disparity
  features = rng.normal([4, height // 2, width // 2, feature_count])
  left_features, right_features = features[:2], features[2:]
  volume = rng.normal([2, levels // 2, height // 2, width // 2, 2 * feature_count])
  cost = rng.normal([2, levels, height, width])
  batch = {k: image(1) for k in ('mixture', 'left', 'right')}
  outputs = {'left': image(1), 'right': image(1),
             'disparity_left': rng.uniform([1, height, width, 1], 0.0, levels - 1.0),
             'disparity_right': rng.uniform([1, height, width, 1], 0.0, levels - 1.0)}
  output_list = list(outputs.values())

  def loss_forward():
    named = dict(zip(outputs, output_list))
    return objective.total_loss(named, batch, objective.LossConfig(), 'joint')['loss']

  parts = {
      'separation (U-Net)': gradient_fn(
          lambda: model.separation(mixture, training=True),
          model.separation.trainable_variables),
      'feature tower (2D, 4 images)': gradient_fn(
          lambda: net.feature_tower(pair, training=True),
          [v for v in net.trainable_variables if '3d' not in v.path]),
      'cost volume (concat)': gradient_fn(
          lambda: cost_volume.concat_cost_volume(left_features, right_features, levels // 2),
          [left_features, right_features]),
      '3D encoder-decoder': gradient_fn(
          lambda: net.filter_volume(volume, training=True),
          [volume] + [v for v in net.trainable_variables if '3d' in v.path]),
      'soft-argmin': gradient_fn(lambda: cost_volume.soft_argmin(cost), [cost]),
      'losses incl. warp': gradient_fn(loss_forward, output_list),
  }
  return {name: timed(fn, repeats, warmup=False) for name, fn in parts.items()}


def _conv_flops(op) -> float:
  """Forward FLOPs (2 x multiply-adds) of one convolution op from its static shapes."""
  if op.type in ('Conv2D', 'Conv3D'):
    kernel = op.inputs[1].shape
    return 2.0 * np.prod(op.outputs[0].shape) * np.prod(kernel[:-1])
  # Conv{2,3}DBackpropInput(V2) = transposed conv: every input element of the transposed
  # conv (out_backprop, last input) is spread over k^n x C_out outputs.
  kernel = op.inputs[1].shape
  return 2.0 * np.prod(op.inputs[2].shape) * np.prod(kernel[:-2]) * kernel[-2]


def _module_of(op_name: str) -> str:
  if 'separation' in op_name:
    return 'separation'
  if '3d' in op_name:
    return '3D encoder-decoder'
  return 'feature tower'


def flops(config: str) -> dict:
  """Analytic FLOPs of one training forward pass, per conv layer (native strided ops)."""
  model_config, (height, width) = configuration(config, 'native')
  model = models.build_model(model_config)
  graph = tf.function(lambda x: model(x, training=True)).get_concrete_function(
      tf.TensorSpec([1, height, width, 3], tf.float32)).graph
  layers, per_module = [], {}
  for op in graph.get_operations():
    if op.type in ('Conv2D', 'Conv3D', 'Conv2DBackpropInput', 'Conv3DBackpropInputV2'):
      count = _conv_flops(op)
      module = _module_of(op.name)
      per_module[module] = per_module.get(module, 0.0) + count
      layers.append((op.name, op.type, list(op.outputs[0].shape), count))
  forward = sum(per_module.values())
  return {'forward_gflop': forward / 1e9, 'train_gflop': 3 * forward / 1e9,
          'per_module_gflop': {k: v / 1e9 for k, v in per_module.items()},
          'layers': [(n, t, s, c / 1e9) for n, t, s, c in layers]}


def conv3d_peak(repeats: int = 3) -> dict:
  """GFLOP/s of a large stride-1 3x3x3 conv shaped like the model's first 3D layers."""
  shape, channels = [1, 48, 128, 256, 32], 32
  x = tf.random.normal(shape)
  kernel = tf.random.normal([3, 3, 3, shape[-1], channels])
  fn = tf.function(lambda: tf.nn.conv3d(x, kernel, [1] * 5, 'SAME'))
  result = timed(lambda: fn().numpy(), repeats)
  result['gflop'] = 2 * np.prod(shape[:-1]) * channels * 27 * shape[-1] / 1e9
  result['gflop_per_s'] = result['gflop'] / result['median']
  result['shape'] = f'{shape} -> {channels}, 3x3x3'
  return result


def matmul_peak(repeats: int = 3) -> dict:
  """GFLOP/s of a 4096^3 float32 matmul."""
  n = 4096
  a, b = tf.random.normal([n, n]), tf.random.normal([n, n])
  fn = tf.function(lambda: tf.matmul(a, b))
  result = timed(lambda: fn().numpy(), repeats)
  result['gflop'] = 2 * n**3 / 1e9
  result['gflop_per_s'] = result['gflop'] / result['median']
  return result


def input_pipeline(count: int = 60) -> dict:
  """Pairs/s of train_dataset at 256x512 crops from two sources."""
  config = pipeline.PipelineConfig(crop_height=256, crop_width=512)
  samples = sample.sample_records('train', num_scenes=count + 5, height=256, width=512,
                                  max_disparity=models.ModelConfig().max_disparity)
  result = {'sample 256x512': bench_data.pairs_per_second(
      pipeline.train_dataset(samples, config), count)}
  with tempfile.TemporaryDirectory() as root:
    samples = kitti.read_split_list(bench_data.write_kitti_folder(root, 20), root).samples
    result['KITTI PNG 375x1242'] = bench_data.pairs_per_second(
        pipeline.train_dataset(samples, config), count)
  return result


def export(export_dir: str) -> dict:
  """Exports the paper-configuration model with random weights as a SavedModel."""
  model_config = models.ModelConfig()
  model = models.build_model(model_config)
  run_info = runs.RunInfo('anaglyph', 256, 512, model_config)
  start = time.perf_counter()
  serving.export_saved_model(graphs.serving_function(model), model.variables, run_info,
                             export_dir)
  return {'seconds': time.perf_counter() - start}


def saved_model_inference(export_dir: str, height: int, width: int, repeats: int = 1
                          ) -> dict:
  """Latency of the SavedModel's serving_default on one uint8 frame."""
  loaded = tf.saved_model.load(export_dir)
  unmix = loaded.signatures['serving_default']
  image = tf.constant(np.random.default_rng(0).integers(0, 256, (height, width, 3),
                                                        dtype=np.uint8))
  result = timed(lambda: _block(unmix(image=image)), repeats, warmup=False)
  result['frames_per_s'] = 1.0 / result['median']
  return result


def forward(config: str = 'paper', repeats: int = 2) -> dict:
  """One inference forward pass of the Keras model (both disparities), batch 1."""
  model_config, (height, width) = configuration(config)
  model = models.build_model(model_config)
  fn = tf.function(lambda x: model(x, training=False))
  mixture = tf.random.stateless_uniform([1, height, width, 3], [3, 0], -1.0, 1.0)
  return timed(lambda: _block(fn(mixture)), repeats)


def classical(height: int = 375, width: int = 1242) -> dict:
  """Seconds per frame of the training-free baseline (anaglyph, diplopia) on one scene."""
  scene = sample.sample_records('heldout', num_scenes=1, height=height, width=width,
                                max_disparity=models.ModelConfig().max_disparity)[0]
  views = sources.load_sample(scene)
  left, right = (image_range.u8_to_signed(tf.constant(views[k][None]))
                 for k in ('left', 'right'))
  result = {'size': f'{height}x{width}'}
  for name in ('anaglyph', 'diplopia'):
    mixture = image_range.signed_to_u8(mixtures.mix(name, left, right)[0].numpy())
    result[name] = timed(lambda m=mixture, n=name: families.of(n).classical(m, n), 1,
                         warmup=False)
  return result


WORKERS = {'train': train, 'modules': modules, 'flops': flops, 'conv3d_peak': conv3d_peak,
           'matmul_peak': matmul_peak, 'pipeline': input_pipeline, 'export': export,
           'inference': saved_model_inference, 'forward': forward, 'classical': classical}

