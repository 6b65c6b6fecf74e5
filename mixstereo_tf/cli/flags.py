"""Flags shared by several command-line tools, each declared once, and config translation.

Each `define_*` group declares its flags the first time it is called (later calls do
nothing), so tools that share a flag share one declaration. Defaults come from the frozen
config dataclasses. Library code raises errors naming config fields
(`PredictorConfig.checkpoint`); `flag_errors` turns them into the flags the user typed.
"""

import dataclasses
import functools
import os
import sys
from typing import Any, Dict, Optional, Tuple

from absl import app
from absl import flags

from mixstereo_tf import models
from mixstereo_tf.artifacts import pretrained
from mixstereo_tf.classical import halftone
from mixstereo_tf.cli import flag_parsers
from mixstereo_tf.cli import media
from mixstereo_tf.cli import stereo_formats
from mixstereo_tf.core import mixtures
from mixstereo_tf.unmixing import disparity_range
from mixstereo_tf.unmixing import predictors
from mixstereo_tf.unmixing import tilt
from mixstereo_tf.video import jobs
from mixstereo_tf.video import temporal

FLAGS = flags.FLAGS
# The flags of `define_predictor` and `define_unmix_predictor`: one per PredictorConfig field.
PREDICTOR_FLAGS = frozenset(f.name for f in dataclasses.fields(predictors.PredictorConfig))


def defaults(config_class: type) -> Dict[str, Any]:
  """{field: default} of a config dataclass (fields without a default are left out)."""
  return {f.name: f.default for f in dataclasses.fields(config_class)
          if f.default is not dataclasses.MISSING}


@functools.lru_cache(maxsize=None)
def define_mixture() -> None:
  """--mixture: the mixture operator of the inputs."""
  flags.DEFINE_string('mixture', None,
                      'Mixture operator f of I = f(I_L, I_R), one of ' +
                      ', '.join(mixtures.MIXTURE_NAMES) + '. Training: the one to learn '
                      "(default anaglyph), or a comma-separated list ('anaglyphs' = every "
                      "anaglyph encoding) to draw one per pair from; evaluate / unmix: the "
                      "inputs', or 'auto' to detect each image's anaglyph encoding "
                      "(default: detected for the shipped models, a --checkpoint / "
                      "--saved_model network's own mixture; required for "
                      "--method=classical).")


@functools.lru_cache(maxsize=None)
def define_max_disparity() -> None:
  """--max_disparity: the network's disparity levels at full resolution."""
  flags.DEFINE_integer('max_disparity', defaults(models.ModelConfig)['max_disparity'],
                       'Disparity levels at full resolution (paper: 96).')


@functools.lru_cache(maxsize=None)
def define_input() -> None:
  """--input: what to unmix (mixstereo-unmix and mixstereo-batch)."""
  flags.DEFINE_string('input', None, 'Image, folder, glob pattern or video.')


@functools.lru_cache(maxsize=None)
def define_output_dir() -> None:
  """--output_dir (each tool says whether it is required)."""
  flags.DEFINE_string('output_dir', None, 'Where to write the results.')


@functools.lru_cache(maxsize=None)
def define_output_options() -> None:
  """How results are written (`media.OutputOptions`): --layout, --max_display_disparity,
  --segment_frames, --keep_video_bits, --temporal, --temporal_prior, --output_format
  (mixstereo-unmix and mixstereo-batch)."""
  options = defaults(media.OutputOptions)
  flags.DEFINE_enum('layout', options['layout'], media.LAYOUTS,
                    'Views as two files (separate), side by side (sbs), side by side at '
                    'half width (sbs_half) or top-bottom (tb).')
  flags.DEFINE_float('max_display_disparity', options['max_display_disparity'],
                     'Disparity (pixels) shown brightest in the colour maps, fixed for the '
                     'run (default: the range found; videos: the range searched on their '
                     'first frame, recorded as display_range in the info JSON).')
  flags.DEFINE_integer('segment_frames', jobs.VideoConfig.segment_frames,
                       'Videos are written in resumable segments of this many frames: '
                       'running the same command again after an interruption continues '
                       'from the last finished segment.')
  flags.DEFINE_boolean('keep_video_bits', jobs.VideoConfig.keep_bits,
                       'Videos of more than 8 bits per sample (a 10-bit phone or HDR video): '
                       "write the views' video at 10 bits (H.264 High 10: VLC, mpv, Kodi "
                       'play it, QuickTime and browsers do not); --nokeep_video_bits writes '
                       'it at 8 bits, which every player plays.')
  flags.DEFINE_boolean('temporal', temporal.TemporalConfig.enabled,
                       'Videos: decide the encoding and the disparity range once per shot '
                       '(scene cuts found from colour histograms) and search each frame '
                       "around the previous frame's disparity, moved with the camera; "
                       '--notemporal unmixes every frame alone.')
  flags.DEFINE_boolean('temporal_prior', temporal.TemporalConfig.use_prior,
                       "With --temporal: search each frame around the previous frame's "
                       'disparities (steadier disparities, faster; the learned matching '
                       "stage then matches a shot's first frame and the census matcher the "
                       'others); --notemporal_prior matches every frame whole, as a still '
                       "(the learned stage on each: better disparities and views; slower), "
                       "the shot's encoding and range kept (experiments/results/temporal.md).")
  flags.DEFINE_multi(flag_parsers.NameListParser(stereo_formats.FORMAT_NAMES),
                     flags.CsvListSerializer(','), 'output_format',
                     [list(options['formats'])],
                     'Also write the pair in these stereo formats (comma-separated, or the '
                     'flag repeated): ' + '; '.join(f'{name}: {f.description}' for name, f in
                                                     stereo_formats.FORMATS.items()) +
                     '. Videos: rgbd and the anaglyphs (the others are skipped).')


def output_options(config: Optional[predictors.PredictorConfig] = None
                   ) -> media.OutputOptions:
  """`media.OutputOptions` from the flags of `define_output_options`; the settings recorded
  by video manifests and info files: `config`'s fields, the shipped model it loads named
  (`predictors.with_weights_named`), and `predictors.weights_identity`."""
  config = config and predictors.with_weights_named(config)
  settings = None if config is None else dict(
      dataclasses.asdict(config), weights=predictors.weights_identity(config))
  return media.OutputOptions(
      layout=FLAGS.layout, max_display_disparity=FLAGS.max_display_disparity,
      video_config=jobs.VideoConfig(FLAGS.segment_frames,
                                    keep_bits=FLAGS.keep_video_bits), settings=settings,
      temporal_config=temporal.TemporalConfig(enabled=FLAGS.temporal,
                                              use_prior=FLAGS.temporal_prior),
      formats=flag_parsers.flattened(FLAGS.output_format))


@functools.lru_cache(maxsize=None)
def define_shared_dir() -> None:
  """--shared_dir: a folder of real stereo frames (the experiments' extra scenes)."""
  flags.DEFINE_string('shared_dir', None, 'Folder of the shared stereo samples (e.g. '
                      '../shared/stereo_samples); left out: those scenes are skipped.')


@functools.lru_cache(maxsize=None)
def define_checkpoint() -> None:
  """--checkpoint: a trained model."""
  flags.DEFINE_string('checkpoint', None, 'A training run directory (its newest checkpoint) '
                      'or a checkpoint prefix such as runs/demo/ckpt-7000.')


@functools.lru_cache(maxsize=None)
def define_predictor() -> None:
  """The predictor group: --method, --checkpoint, --saved_model, --mixture, --restore_colour,
  --disparity_range, --max_network_pixels, --swap_eyes, --mixing_weight."""
  define_checkpoint()
  define_mixture()
  defaults = predictors.PredictorConfig()
  flags.DEFINE_enum('method', defaults.method, predictors.METHODS,
                    'model: a trained network (--checkpoint or --saved_model); classical: the '
                    'training-free baseline; sgbm: OpenCV StereoSGBM on the eye channels, a '
                    'peer baseline (anaglyph encodings); oracle: the stereo module of '
                    '--checkpoint (a stereo_only or joint run) on the clean pairs '
                    '(evaluation only).')
  flags.DEFINE_string('saved_model', defaults.saved_model,
                      'A SavedModel written by mixstereo_tf.export.')
  flags.DEFINE_boolean('restore_colour', defaults.restore_colour,
                       "Rebuild the views' exact channels from the mixture and disparities "
                       '(paper 4.2); default: on for channel anaglyphs. --method=model only.')
  flags.DEFINE_alias('restore_colors', 'restore_colour')
  flags.DEFINE_string('disparity_range', 'auto', "'auto' (estimated per image), MIN,MAX: "
                      'the signed disparities to search, pixels of the input (negative = '
                      "behind the screen), or 'network': the method's own range (a model's "
                      "levels [0, D - 1], the image as it is; evaluate's default).")
  flags.DEFINE_integer('max_network_pixels', defaults.max_network_pixels,
                       "A model's input is reduced to at most this many pixels.",
                       lower_bound=1)
  flags.DEFINE_flag(flags.Flag(
      flag_parsers.SwapEyesParser(), flags.ArgumentSerializer(), 'swap_eyes', defaults.swap_eyes,
      "Anaglyphs with the left eye in the cyan (second filter's) channels: cyan-red glasses, "
      "mirrored scans; --swap_eyes=auto detects it per image (a video: per shot) from the "
      "texture of the pixels hidden beside depth edges; the info JSON records the order "
      "(eye_order) and the detection's score (eye_order_score).",
      boolean=True))
  flags.DEFINE_string('mixing_weight', None,
                      'Double images I = a L + (1 - a) R (--mixture=diplopia): the left '
                      "view's weight a; unset: 1/2 exactly; 'auto': estimated per image (a "
                      "video: per shot) from the echoes of its edges; a number in (0, 1): that "
                      'weight. The info JSON records the a used (mixing_weight).')
  define_pretrained()


@functools.lru_cache(maxsize=None)
def define_pretrained() -> None:
  """--pretrained: a shipped model by name, or 'list'."""
  flags.DEFINE_string('pretrained', None, "A model shipped with the package (--method=model "
                      "without --checkpoint / --saved_model; default: the one marked default for "
                      "the mixture in --pretrained=list), a folder in its format, or 'list' "
                      "to list them.")


def require_unless_listing(*names: str) -> None:
  """Makes flags required, except with --pretrained=list (which only lists the models)."""
  define_pretrained()
  for name in names:
    flags.register_multi_flags_validator(
        [name, 'pretrained'],
        lambda values, name=name: (values[name] is not None or
                                   values['pretrained'] == pretrained.LIST),
        message=f'Flag --{name} must have a value other than None.')


def run_binary(main, doc: str, **kwargs) -> None:
  """`app.run(main, **kwargs)` with `doc` (the binary's module docstring) as the `--help`
  text, also under a console-script wrapper (`mixstereo-unmix`), whose `__main__` has
  none: absl printed a bare usage line there. A usage error raised by `main` (a bad flag
  value, a missing input, an output folder that cannot be made) is printed as its message
  alone: absl printed the whole help text above it."""
  module = sys.modules['__main__']
  if not getattr(module, '__doc__', None):
    module.__doc__ = doc

  def main_with_short_errors(argv):
    try:
      return main(argv)
    except app.UsageError as e:
      name = os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else 'error'
      sys.stderr.write(f'{name}: {e}\n(--help shows the usage)\n')
      sys.exit(e.exitcode)

  app.run(main_with_short_errors, **kwargs)


def exit_if_listing() -> None:
  """--pretrained=list: prints the shipped models (name, mixtures, recipe, held-out
  numbers) and exits."""
  if FLAGS.pretrained == pretrained.LIST:
    print(pretrained.describe())
    sys.exit(0)


@functools.lru_cache(maxsize=None)
def define_data() -> None:
  """--data_dir and --middlebury_scale, shared by training and evaluation."""
  flags.DEFINE_string('data_dir', None, 'Dataset root: KITTI raw (with the split list), KITTI '
                      'stereo (holding training/), or Middlebury scene folders; unused by '
                      'the embedded sample source.')
  flags.DEFINE_list('middlebury_scale', [], 'Ground-truth disparity scale per Middlebury '
                    'scene as scene:scale items, e.g. tsukuba:16,venus:8 (replaces the '
                    "layout's scale).")


def predictor_config() -> predictors.PredictorConfig:
  """The PredictorConfig of the parsed predictor flags."""
  try:
    search = disparity_range.parse(FLAGS.disparity_range)
  except ValueError as e:
    raise app.UsageError(f'--disparity_range: {e}') from None
  if FLAGS['max_network_pixels'].present and FLAGS.method != 'model':
    raise app.UsageError(f'--max_network_pixels applies to --method=model (a network), not '
                         f'--method={FLAGS.method}.')
  return predictors.PredictorConfig(
      method=FLAGS.method, checkpoint=FLAGS.checkpoint, saved_model=FLAGS.saved_model,
      mixture=FLAGS.mixture, restore_colour=FLAGS.restore_colour, disparity_range=search,
      max_network_pixels=FLAGS.max_network_pixels, pretrained=FLAGS.pretrained,
      swap_eyes=FLAGS.swap_eyes, mixing_weight=flag_parsers.parse_mixing_weight(
          FLAGS.mixing_weight))


@functools.lru_cache(maxsize=None)
def define_unmix_predictor() -> None:
  """The predictor group of the tools that unmix files, and --descreen, --rectify."""
  define_predictor()
  flags.DEFINE_string('descreen', halftone.AUTO, "A scanned print's halftone dots, smoothed "
                      "first: 'auto' finds them per image (a video: per shot); 'off'; or "
                      'their period in pixels (info: screen_period).')
  flags.DEFINE_enum('rectify', tilt.AUTO, (tilt.AUTO, tilt.OFF), "'auto': a tilted anaglyph "
                    '(a crooked scan) or double image (a rolled camera) turned level where '
                    'the matcher gains, the outputs turned back (info: tilt).')


def unmix_predictor_config() -> predictors.PredictorConfig:
  """`predictor_config` for the tools that unmix files (mixstereo-unmix, mixstereo-batch),
  with --descreen and --rectify.

  Raises:
    ValueError: --method=oracle, which needs the clean stereo pair.
  """
  config = dataclasses.replace(predictor_config(), rectify=FLAGS.rectify,
                               descreen=flag_parsers.parse_descreen(FLAGS.descreen))
  if config.method == 'oracle':
    raise ValueError('--method=oracle needs the clean stereo pair; it is for evaluation '
                     'only.')
  return config


def middlebury_scales() -> Tuple[Tuple[str, float], ...]:
  """The parsed --middlebury_scale items as (scene, scale) pairs.

  Raises:
    app.UsageError: an item is not scene:scale with a number as scale.
  """
  return flag_parsers.parse_scene_scales(FLAGS.middlebury_scale)
