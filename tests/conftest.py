"""Shared pytest set-up: quiet TensorFlow, two logical CPU devices for distribution tests."""

import os

os.environ.setdefault('TF_CPP_MIN_LOG_LEVEL', '2')

import tensorflow as tf  # pylint: disable=g-import-not-at-top

# Two logical CPUs let MirroredStrategy tests run on one physical CPU; this must happen
# before TensorFlow initialises its devices, so it lives here rather than in a test.
_cpus = tf.config.list_physical_devices('CPU')
tf.config.set_logical_device_configuration(
    _cpus[0], [tf.config.LogicalDeviceConfiguration()] * 2)
