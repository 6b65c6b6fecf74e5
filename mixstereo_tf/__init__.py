"""mixstereo_tf: stereo computation for a single mixture image (Zhong, Dai, Li, ECCV 2018).

The public face is one function:

  import mixstereo_tf
  result = mixstereo_tf.unmix('photo.jpg')  # Or a uint8 [H, W, 3] / gray [H, W] array.
  result.left, result.right    # uint8 [H, W, 3] views (uint16 for a 16-bit anaglyph).
  result.disparity             # float32 [H, W], signed pixels of the left view.
  result.info['mixture']       # The encoding unmixed ('auto': the one detected).

Importing the package is cheap: TensorFlow and the models load on the first `unmix` call.
"""

import dataclasses
import functools
import os
import re
from typing import Any, Dict, Optional, Tuple, Union

import numpy as np

__version__ = '0.1.0'

# TensorFlow >= 2.17 leaves its oneDNN kernels off on CPUs without AVX-512 (e.g. AVX2-only
# AMD EPYC); its own kernels for stride-2 Conv3D gradients and Conv3DTranspose are then
# 10-200x slower: the demo trained at 0.23 steps/s instead of ~6 on one core. Read when
# TensorFlow is first imported, so it applies to every tool and to `unmix` unless the
# caller imported TensorFlow first or set the variable (an explicit setting wins).
os.environ.setdefault('TF_ENABLE_ONEDNN_OPTS', '1')

# Log lines naming a file whose name is not UTF-8 are written with \xNN escapes, so that a
# strict UTF-8 sink (an absl log file, pytest-xdist) takes them (`core/printable.py`).
from mixstereo_tf.core import printable as _printable  # pylint: disable=g-import-not-at-top
_printable.install()

# PredictorConfig fields whose `unmix` keyword has another name.
_KEYWORDS = {'pretrained': 'model'}


@dataclasses.dataclass(frozen=True)
class Unmixed:
  """What `unmix` returns.

  Disparities are signed pixels of the input (negative = behind the screen): the left
  pixel x matches the right pixel x - disparity[y, x]; the right pixel x matches the left
  pixel x + disparity_right[y, x].

  Attributes:
    left: uint8 [H, W, 3] left view; uint16 for a 16-bit anaglyph or double image (a
      uint16 array or a 16-bit file: matched at 8 bits, its views made at 16).
    right: the right view, as left.
    disparity: float32 [H, W] disparity of the left view.
    disparity_right: float32 [H, W] disparity of the right view.
    info: what the CLI's side-car `<name>_info.json` holds about the unmixing (JSON-able):
      'mixture' (the encoding unmixed), 'detected' and 'confidence' (the detector's
      encoding), 'disparity_range' ([min, max] pixels searched), 'method', 'pretrained'
      (the shipped model's name, when one ran), 'eye_order' ('as_given' or 'swapped'),
      'seconds', and the method's own details.
  """
  left: np.ndarray
  right: np.ndarray
  disparity: np.ndarray
  disparity_right: np.ndarray
  info: Dict[str, Any]


def _keywords(message: str) -> str:
  """`message` naming `unmix` keywords (`mixture=`) instead of PredictorConfig fields."""

  def keyword(match: re.Match) -> str:
    return f'{_KEYWORDS.get(match.group(1), match.group(1))}='

  return re.sub(r'\bPredictorConfig\.(\w+)=?', keyword, message)


def _image(image) -> np.ndarray:
  """`unmix`'s image argument as an array: a path (str, bytes, PathLike) read like the CLI
  reads it (16-bit files as uint16), a PIL image as RGB turned upright by its EXIF
  orientation (as a file would be); ValueError naming `image=` for videos, bytes that are
  no path, and arrays that are not uint8 or uint16 images."""
  from mixstereo_tf.cli import input_images  # pylint: disable=g-import-not-at-top
  from mixstereo_tf.cli import input_listing  # pylint: disable=g-import-not-at-top
  if isinstance(image, bytes) and (b'\0' in image or len(image) > 4096):
    raise ValueError(f'image= is {len(image)} bytes that name no file (a file\'s contents?); '
                     'give its path, or an RGB array (e.g. np.asarray(PIL.Image.open('
                     "io.BytesIO(data)).convert('RGB')); OpenCV decodes to BGR: reverse it "
                     'with [..., ::-1]).')
  if isinstance(image, (str, bytes, os.PathLike)):
    path = os.fsdecode(image)
    if os.path.splitext(path)[1].lower() in input_listing.VIDEO_EXTENSIONS:
      raise ValueError(f'image={path} is a video; unmix() takes one image (videos: '
                       f'mixstereo-unmix --input={path}).')
    return input_images.read_image(path, deep=True)
  if hasattr(image, 'getexif') and hasattr(image, 'convert'):  # A PIL image: as a file.
    image = _pil_rgb(image)
  array = np.asarray(image)
  if array.ndim == 3 and array.shape[2] == 4:
    array = array[..., :3]  # RGBA: alpha dropped, as image files' and PIL images' is.
  if array.dtype not in (np.uint8, np.uint16):
    raise ValueError(f'image= must be a uint8 array (0-255) or a 16-bit uint16 one, got '
                     f'{array.dtype}; e.g. np.round(x * 255).astype(np.uint8) for floats in '
                     '[0, 1].')
  if array.ndim not in (2, 3) or min(array.shape[:2]) == 0 or (
      array.ndim == 3 and array.shape[2] not in (1, 3)):
    raise ValueError(f'image= must be a [H, W, 3] RGB (or RGBA) or [H, W] gray image, got '
                     f'shape {array.shape}.')
  return array


def _stored_hint(image) -> Dict[str, Any]:
  """{'hint': a FrameHint saying the colour was stored at half resolution} for a path or
  PIL image of a 4:2:0 / 4:2:2 JPEG or a lossy WebP (`image_io.chroma_halved`), else {}."""
  from mixstereo_tf.core import hints  # pylint: disable=g-import-not-at-top
  from mixstereo_tf.data import image_io  # pylint: disable=g-import-not-at-top
  if isinstance(image, (str, bytes, os.PathLike)):
    halved = image_io.chroma_halved(os.fsdecode(image))
  else:
    filename = getattr(image, 'filename', '') if hasattr(image, 'getexif') else ''
    halved = bool(filename) and image_io.chroma_halved(filename)
  return hints.stored(halved)


def _pil_rgb(image) -> np.ndarray:
  """A PIL image as uint8 RGB, turned upright by its EXIF orientation: 16-bit gray ('I;16',
  or 'I' within 0..65535, as Pillow opens 16-bit PNGs) as uint16 RGB, as such a file is
  read; ValueError for float ('F') and other 32-bit images, which `convert` would clip."""
  from PIL import ImageOps  # pylint: disable=g-import-not-at-top
  image = ImageOps.exif_transpose(image)
  if image.mode.startswith('I;16') or image.mode == 'I':
    values = np.asarray(image)
    if values.size and (values.min() < 0 or values.max() > 65535):
      raise ValueError(f"image= is a 32-bit PIL image (mode 'I', values {values.min()} to "
                       f'{values.max()}); give an 8- or 16-bit image.')
    return np.repeat(values.astype(np.uint16)[..., None], 3, axis=2)
  if image.mode == 'F':
    raise ValueError("image= is a floating-point PIL image (mode 'F'), whose range is "
                     'unknown; give np.round(x * 255).astype(np.uint8) for values in [0, 1].')
  return np.asarray(image.convert('RGB'))  # Palette, CMYK, ... to RGB.


def _config(given: Dict[str, Any], search):
  """The PredictorConfig of `unmix`'s keywords (`given`, `...`: not given; `search`: the
  disparity_range keyword); TensorFlow imported quietly first."""
  from mixstereo_tf.core import quiet_import  # pylint: disable=g-import-not-at-top
  quiet_import.import_tensorflow()
  from mixstereo_tf.unmixing import predictors  # pylint: disable=g-import-not-at-top
  if given['max_network_pixels'] is not ... and given['method'] != 'model':
    raise ValueError(f"max_network_pixels= applies to method='model' (a network), not "
                     f"method={given['method']!r}.")
  # Paths as text (a pathlib.Path would reach the JSON-able info).
  given = {name: os.fspath(value) if isinstance(value, os.PathLike) else value
           for name, value in given.items() if value is not ...}
  return predictors.PredictorConfig(disparity_range=_search(search), **given)


@functools.lru_cache(maxsize=4)
def _unmixer(config):
  """The Unmixer of a PredictorConfig, built once (building loads the model)."""
  from mixstereo_tf.unmixing import predictors  # pylint: disable=g-import-not-at-top
  if config.method == 'oracle':
    raise ValueError("PredictorConfig.method='oracle' needs the clean stereo pair; it is "
                     'for evaluation only.')
  return predictors.build_unmixer(config)


def _search(value: Union[None, str, Tuple[int, int]]) -> Union[None, str, Tuple[int, int]]:
  """A `disparity_range` keyword as PredictorConfig.disparity_range (the CLI's text too)."""
  from mixstereo_tf.unmixing import disparity_range  # pylint: disable=g-import-not-at-top
  if value is None:
    return None
  if not isinstance(value, str) and not hasattr(value, '__iter__'):
    raise ValueError(f"disparity_range={value!r}: give (MIN, MAX) signed pixels, or text such "
                     "as '-40,120' or 'auto'.")
  try:  # A pair reads as the CLI's MIN,MAX text, so both check and round alike.
    text = value if isinstance(value, str) else ','.join(str(v) for v in value)
    return disparity_range.parse(text)
  except (TypeError, ValueError) as e:
    raise ValueError(f'disparity_range={value!r}: {e}') from None


def unmix(image: Union[str, bytes, os.PathLike, np.ndarray, Any], *,
          mixture: Optional[str] = 'auto',
          method: str = 'model', model: Optional[str] = None,
          checkpoint: Optional[str] = None, saved_model: Optional[str] = None,
          disparity_range: Union[None, str, Tuple[int, int]] = None,
          restore_colour: Optional[bool] = None, max_network_pixels: Optional[int] = ...,
          swap_eyes: Union[bool, str] = False, mixing_weight: Union[None, float, str] = None,
          descreen: Union[str, float] = 'auto', rectify: str = 'auto') -> Unmixed:
  """Separates one mixture image into its two views and their disparities.

  The keywords are the `mixstereo-unmix` flags of the same names (`model`: --pretrained),
  with PredictorConfig's defaults (`max_network_pixels=...` stands for its value) except
  `mixture`, `descreen` and `rectify` ('auto', as in the tool). The unmixer of each set of
  keywords is built once and kept (the four newest): many images load the model once. The
  first call imports TensorFlow quietly, as the tools do (`core.quiet_import`).

  Args:
    image: a uint8 (or uint16) RGB [H, W, 3] (alpha of RGBA dropped) or gray [H, W] array
      (OpenCV's cv2.imread / imdecode give BGR: pass `bgr[..., ::-1]`), a PIL image (as
      RGB, EXIF orientation applied, 16-bit gray as uint16), or the path (str, bytes,
      PathLike) of an image file (read like the CLI reads it, HEIC and AVIF too: gray
      files become RGB, 16-bit ones and 10- or 12-bit HEICs uint16, EXIF orientation
      applied); videos: the `mixstereo-unmix` tool.
    mixture: the image's mixture operator (`mixstereo_tf.core.mixtures` names, e.g. 'gray',
      'diplopia'); 'auto' detects an anaglyph's encoding; None: the model's own.
    method: 'model' (a network), 'classical' (training-free) or 'sgbm' (OpenCV's, a peer).
    model: a shipped model's name ('anaglyph', 'diplopia') or a folder in its format;
      None with neither checkpoint nor saved_model: the first shipped model that unmixes
      the mixture ('auto': the anaglyph model).
    checkpoint: a training run directory or checkpoint prefix, instead of a shipped model.
    saved_model: a SavedModel written by mixstereo_tf.export, instead of a shipped model.
    disparity_range: (min, max) signed pixels, or the CLI's text ('-40,120', 'auto').
    restore_colour: rebuild the views' exact channels (None: on for anaglyphs); 'model'.
    max_network_pixels: a network's input is reduced to at most this many pixels.
    swap_eyes: True: the left eye in the cyan (second) filter's channels; 'auto': detected.
    mixing_weight: a of double images a L + (1 - a) R (None: 1/2, 'auto': estimated).
    descreen: a scan's halftone screen smoothed: 'auto', 'off', a period (screen_period).
    rectify: 'auto' turns a tilted anaglyph or double image level if it helps; 'off'.

  Returns:
    An `Unmixed`: views and disparities the size of the input, and `info`.

  Raises:
    ValueError: an unreadable file, a bad image or keyword, or an image the unmixer cannot
      take (e.g. mixture='auto' on a photo that is no anaglyph), naming the keyword.
  """
  given = dict(method=method, checkpoint=checkpoint, saved_model=saved_model,
               mixture=mixture, restore_colour=restore_colour, swap_eyes=swap_eyes,
               max_network_pixels=max_network_pixels, pretrained=model,
               mixing_weight=mixing_weight, descreen=descreen, rectify=rectify)
  try:
    unmixer = _unmixer(_config(given, disparity_range))
    outputs = unmixer(_image(image), **_stored_hint(image))
  except ValueError as e:
    message = _keywords(str(e))
    if message == str(e):
      raise
    raise ValueError(message) from None
  return Unmixed(outputs['left'], outputs['right'], outputs['disparity_left'],
                 outputs['disparity_right'], outputs['info'])
