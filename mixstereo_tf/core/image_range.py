"""Image value ranges in one place: uint8 <-> [0, 1] <-> [-1, 1], for NumPy and TensorFlow.

Three ranges are in use (docs/DESIGN.md):
  * uint8 0..255: image files, readers, predictor inputs and outputs (16-bit files: uint16
    0..65535, their views restored at that depth: `to_unit`, `unit_to`, `eight_bits`);
  * 'unit' [0, 1]: photometric augmentation, the classical baselines, the losses' SSIM/L1
    terms (monodepth's constants are for this range);
  * 'signed' [-1, 1]: network inputs and outputs (the paper normalises to [-1, 1]).

Every function takes a NumPy array (or anything `np.asarray` accepts) or a `tf.Tensor`
and returns the same kind. Float results are float32 for uint8 inputs and keep the input's
float dtype otherwise. Conversions to uint8 round half to even and clip to 0..255.
TensorFlow is not imported here: a tensor exists only once its caller has imported it, so
the image readers (`data.image_io`) stay light.
"""

import sys

import numpy as np


def _is_tensor(value) -> bool:
  tf = sys.modules.get('tensorflow')
  return tf is not None and tf.is_tensor(value)


def _tf():
  """TensorFlow, already imported (`_is_tensor` was true)."""
  return sys.modules['tensorflow']


def u8_to_unit(image):
  """uint8 0..255 -> float32 [0, 1] (value / 255)."""
  if _is_tensor(image):
    tf = _tf()
    return tf.cast(image, tf.float32) / 255.0
  return np.asarray(image).astype(np.float32) / np.float32(255.0)


def to_unit(image) -> np.ndarray:
  """A uint8 (value / 255) or uint16 (value / 65535) NumPy image as float32 [0, 1]."""
  image = np.asarray(image)
  if image.dtype == np.uint16:
    return image.astype(np.float32) / np.float32(65535.0)
  return u8_to_unit(image)


def eight_bits(image) -> np.ndarray:
  """A uint16 NumPy image as uint8, round(v / 257) (65535 -> 255, 257 k -> k); others as
  they are."""
  image = np.asarray(image)
  if image.dtype != np.uint16:
    return image
  return ((image.astype(np.uint32) + 128) // 257).astype(np.uint8)


def unit_to(image, dtype) -> np.ndarray:
  """[0, 1] NumPy image -> `dtype`: uint8 as `unit_to_u8`; uint16 round(x * 65535), clipped."""
  if np.dtype(dtype) != np.uint16:
    return unit_to_u8(image)
  scaled = np.rint(np.asarray(image, np.float32) * np.float32(65535.0))
  return np.clip(scaled, 0.0, 65535.0, out=scaled).astype(np.uint16)


def u8_to_signed(image):
  """uint8 0..255 -> float32 [-1, 1] (value / 127.5 - 1)."""
  if _is_tensor(image):
    tf = _tf()
    return tf.cast(image, tf.float32) / 127.5 - 1.0
  return np.asarray(image).astype(np.float32) / np.float32(127.5) - np.float32(1.0)


def unit_to_signed(image):
  """[0, 1] -> [-1, 1] (2 x - 1)."""
  return image * 2.0 - 1.0


def signed_to_unit(image):
  """[-1, 1] -> [0, 1] ((x + 1) / 2)."""
  return (image + 1.0) * 0.5


def unit_to_u8(image):
  """[0, 1] -> uint8: round(x * 255), clipped to 0..255."""
  if _is_tensor(image):
    tf = _tf()
    return tf.cast(tf.round(tf.clip_by_value(image * 255.0, 0.0, 255.0)), tf.uint8)
  scaled = np.asarray(np.rint(np.asarray(image) * 255.0))
  # Bounds of the array's own type: NumPy's clip is several times slower with int bounds.
  return np.clip(scaled, scaled.dtype.type(0), scaled.dtype.type(255), out=scaled).astype(
      np.uint8)


def signed_to_u8(image):
  """[-1, 1] -> uint8: round((x + 1) * 127.5), clipped to 0..255.

  NumPy inputs are computed in float64, so the rounding is that of the exact value.
  """
  if _is_tensor(image):
    tf = _tf()
    return tf.cast(tf.round(tf.clip_by_value((image + 1.0) * 127.5, 0.0, 255.0)), tf.uint8)
  scaled = np.add(image, 1.0, dtype=np.float64)  # One new array, then in place.
  scaled *= 127.5
  np.round(scaled, out=scaled)
  return np.clip(scaled, 0.0, 255.0, out=scaled).astype(np.uint8)


def as_unit_float(image, name: str = 'image') -> np.ndarray:
  """A NumPy RGB image as float32 [0, 1]: uint8 / uint16 as `to_unit`, float is checked.

  Args:
    image: uint8 [H, W, 3] (0..255), uint16 (0..65535) or float [H, W, 3] in [0, 1].
    name: what the image is, for error messages.

  Raises:
    ValueError: not [H, W, 3], another dtype, or floats outside [0, 1] / non-finite.
  """
  image = np.asarray(image)
  if image.ndim != 3 or image.shape[-1] != 3:
    raise ValueError(f'{name} must be an RGB image [H, W, 3], got shape {image.shape}.')
  if image.dtype in (np.uint8, np.uint16):
    return to_unit(image)
  if not np.issubdtype(image.dtype, np.floating):
    raise ValueError(f'{name} must be uint8, uint16 or float in [0, 1], got dtype '
                     f'{image.dtype}.')
  if not np.all(np.isfinite(image)) or image.min() < -1e-3 or image.max() > 1 + 1e-3:
    raise ValueError(f'float {name} must be finite and in [0, 1], got range '
                     f'[{np.nanmin(image)}, {np.nanmax(image)}].')
  return np.clip(image, 0.0, 1.0).astype(np.float32)
