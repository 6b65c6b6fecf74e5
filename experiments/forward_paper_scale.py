r"""Times one forward pass of the paper-scale model (256x512, 96 levels, batch 1).

  python experiments/forward_paper_scale.py [--height=256 --width=512 --repeats=3]

Prints the first call (tracing included), the median of the next calls, and the peak
resident memory of the process (VmHWM). Not a test: this machine is shared and noisy.
"""

import statistics
import time

from absl import app
from absl import flags
import tensorflow as tf

from mixstereo_tf import models

flags.DEFINE_integer('height', 256, 'Input height (multiple of 32).')
flags.DEFINE_integer('width', 512, 'Input width (multiple of 32).')
flags.DEFINE_integer('repeats', 3, 'Timed calls after the first.')
flags.DEFINE_boolean('training', False, 'Batch-norm mode of the pass.')
FLAGS = flags.FLAGS


def peak_memory_gib() -> float:
  """The process' peak resident set (VmHWM) in GiB."""
  with open('/proc/self/status') as f:
    for line in f:
      if line.startswith('VmHWM:'):
        return int(line.split()[1]) / 2**20
  return float('nan')


def main(argv):
  del argv
  model = models.build_model(models.ModelConfig())
  forward = tf.function(lambda x: model(x, training=FLAGS.training))
  mixture = tf.random.uniform([1, FLAGS.height, FLAGS.width, 3], -1.0, 1.0, seed=0)
  start = time.perf_counter()
  outputs = forward(mixture)
  first = time.perf_counter() - start
  times = []
  for _ in range(FLAGS.repeats):
    start = time.perf_counter()
    outputs = forward(mixture)
    float(tf.reduce_sum(outputs['disparity_left']))  # Wait for the result.
    times.append(time.perf_counter() - start)
  print(f'forward {FLAGS.height}x{FLAGS.width}, {model.model_config.max_disparity} levels, '
        f'{sum(int(tf.size(v)) for v in model.trainable_variables):,} parameters')
  print(f'first call (with tracing): {first:.2f} s')
  print(f'median of {FLAGS.repeats}: {statistics.median(times):.2f} s '
        f'(min {min(times):.2f}, max {max(times):.2f})')
  print(f'peak resident memory: {peak_memory_gib():.2f} GiB')
  print('output shapes: ' + ', '.join(f'{k} {tuple(v.shape)}' for k, v in outputs.items()))


if __name__ == '__main__':
  app.run(main)
