"""Markdown rendering of experiments/benchmark.py results (optionally beside a baseline)."""

from typing import Optional

from experiments import benchmark_video


def _get(run: Optional[dict], key: str) -> Optional[dict]:
  return None if run is None else run['results'].get(key)


def _time(result: Optional[dict]) -> str:
  """'median s (min-max), first call X s' or the error."""
  if result is None:
    return 'not run'
  if 'error' in result:
    return f'FAILED: {result["error"]}'
  return (f'{result["median"]:.3f} s ({result["min"]:.3f}-{result["max"]:.3f}); '
          f'first {result["first"]:.1f} s')


def _cells(run, baseline, key, fmt) -> str:
  now = fmt(_get(run, key))
  if baseline is None:
    return f'| {now} |'
  return f'| {fmt(_get(baseline, key))} | {now} |'


def _header(first: str, baseline, baseline_label: str, label: str) -> list:
  if baseline is None:
    return [f'| {first} | {label} |', '|---|---|']
  return [f'| {first} | {baseline_label} | {label} |', '|---|---|---|']


def _train_cell(result) -> str:
  if result is None or 'error' in result:
    return _time(result)
  return (f'{result["steps_per_s"]:.3f} steps/s; {_time(result)}; '
          f'peak {result["peak_gib"]:.2f} GiB')


def _machine_section(run) -> list:
  m = run['machine']
  return [f'Command: `{run["command"]}`', '',
          f'Machine: {m["cpu"]}, {m["cores"]} cores, {m["memory_gib"]} GiB RAM; '
          f'TensorFlow {m["tensorflow"]}, Python {m["python"]}; {m["date"]}; load average '
          f'{", ".join(f"{x:.2f}" for x in m["load"])} at start, '
          f'{", ".join(f"{x:.2f}" for x in m["load_after"])} at the end '
          '(the machine is shared).', '']


def _fraction(run, key) -> str:
  train, flops, peak = (_get(run, k) for k in (key, 'flops/' + key.split('/')[1],
                                                 'machine/conv3d'))
  if not train or not flops or not peak or any('error' in r for r in (train, flops, peak)):
    return 'n/a'
  achieved = flops['train_gflop'] / train['median']
  return f'{achieved:.1f} GFLOP/s = {100 * achieved / peak["gflop_per_s"]:.1f}%'


def render(run: dict, baseline: Optional[dict], baseline_label: str,
           baseline_note: str = '') -> str:
  """The full BENCHMARKS.md text."""
  label = run['label']
  lines = ['# Benchmarks', '']
  lines += _machine_section(run)
  if baseline is not None:
    lines += [f'Baseline ("{baseline_label}"):', ''] + _machine_section(baseline)
    if baseline_note:
      lines += [baseline_note, '']
  lines += ['Times: median of the timed repeats after one warm-up call (min-max in '
            'brackets); "first" = the first call, tracing / XLA compilation included. '
            'Peak = VmHWM of the measurement\'s own process.', '']
  for section in (_training_sections, _module_sections, _kernel_sections):
    lines += section(run, baseline, baseline_label, label)
  lines += _layer_sections(run)
  lines += _matcher_section(run)
  if any(key.startswith('video/') for key in run['results']):
    lines += benchmark_video.render_section(run, baseline, baseline_label, label)
  return '\n'.join(lines) + '\n'


def _training_sections(run, baseline, baseline_label: str, label: str) -> list:
  """Sections 1-3: the machine's limit, train steps, FLOPs and throughput fraction."""
  lines = ['## 1. Machine limit', ''] + _header('kernel', baseline, baseline_label, label)
  gflops = lambda r: ('not run' if r is None else f'FAILED: {r["error"]}' if 'error' in r
                      else f'{r["gflop_per_s"]:.1f} GFLOP/s ({r["gflop"]:.1f} GFLOP in '
                      f'{r["median"]:.3f} s)')
  for key, name in (('machine/conv3d', 'tf.nn.conv3d [1,48,128,256,32] -> 32, 3x3x3'),
                    ('machine/matmul', 'matmul 4096x4096x4096')):
    lines.append(f'| {name} ' + _cells(run, baseline, key, gflops))

  lines += ['', '## 2-3. Train step (joint, batch 1, RMSProp), FLOPs, throughput fraction',
            ''] + _header('configuration', baseline, baseline_label, label)
  for config in ('paper', 'demo'):
    for jit in (False, True):
      key = f'train/{config}/jit={jit}'
      lines.append(f'| {config}, XLA {"on" if jit else "off"} ' +
                   _cells(run, baseline, key, _train_cell))
  lines += ['', 'FLOPs are counted analytically from the static shapes of every conv op '
            'of the traced training forward pass (native strided ops; 2 FLOPs per '
            'multiply-add; elementwise ops, BN, losses not counted); a train step counts '
            '3x the forward (forward + input gradient + kernel gradient). Fraction = '
            'train FLOPs / median step time / the conv3d GFLOP/s of section 1.', '']
  lines += _header('configuration', baseline, baseline_label, label)
  for config in ('paper', 'demo'):
    flop = lambda r: ('n/a' if r is None or 'error' in r else
                      f'{r["forward_gflop"]:.1f} fwd / {r["train_gflop"]:.1f} train GFLOP ('
                      + ', '.join(f'{k} {v:.1f}' for k, v in r['per_module_gflop'].items())
                      + ')')
    lines.append(f'| {config}: FLOPs per step ' + _cells(run, baseline, f'flops/{config}',
                                                        flop))
    for jit in (False, True):
      key = f'train/{config}/jit={jit}'
      cells = (f'| {_fraction(run, key)} |' if baseline is None else
               f'| {_fraction(baseline, key)} | {_fraction(run, key)} |')
      lines.append(f'| {config}, XLA {"on" if jit else "off"}: achieved ' + cells)

  return lines


def _module_sections(run, baseline, baseline_label: str, label: str) -> list:
  """Sections 4-6: per-module times, the input pipeline, SavedModel inference."""
  lines = ['', '## 4. Per-module forward+backward time (paper configuration)', '',
            'Each part timed alone (its own tf.function, XLA off) at the shapes it has in the '
            'paper-configuration step, gradients w.r.t. its variables and inputs; the '
            'stereo parts see the batch of 2 (direct + mirrored pass).', '']
  lines += _header('module', baseline, baseline_label, label)
  modules = _get(run, 'modules/paper') or {}
  for name in [k for k in modules if k not in ('peak_gib', 'load', 'error')]:
    cell = lambda r, name=name: _time(None if r is None or name not in r else r[name])
    lines.append(f'| {name} ' + _cells(run, baseline, 'modules/paper', cell))
  if 'error' in modules:
    lines.append(f'| all | FAILED: {modules["error"]} |')
  lines += _module_throughput(run)

  lines += ['', '## 5. Input pipeline (train_dataset, 256x512 crops) vs consumption', '']
  lines += _header('source', baseline, baseline_label, label)
  pipe = _get(run, 'pipeline') or {}
  step = _get(run, 'train/paper/jit=False')
  for name in [k for k in pipe if k not in ('peak_gib', 'load', 'error')]:
    cell = lambda r, name=name: 'n/a' if r is None or name not in r else f'{r[name]:.1f} pairs/s'
    ratio = ('' if not step or 'error' in step else
             f' = {pipe[name] * step["median"]:.0f}x the paper step\'s consumption')
    lines.append(f'| {name} ' + _cells(run, baseline, 'pipeline', cell)[:-1] + ratio + ' |')

  lines += ['', '## 6. SavedModel inference (paper configuration, random weights)', '']
  lines += _header('frame', baseline, baseline_label, label)
  keys = sorted({k for r in (run, baseline) if r for k in r['results']
                 if k.startswith('inference/') and k != 'inference/export'})
  def infer(r):
    if r is None:
      return 'not run'
    if 'error' in r:
      return f'FAILED: {r["error"]}'
    return (f'{r["median"]:.2f} s = {r["frames_per_s"]:.3f} frames/s; first '
            f'{r["first"]:.1f} s; peak {r["peak_gib"]:.2f} GiB')
  for key in keys:
    lines.append(f'| {key.split("/")[1]} ' + _cells(run, baseline, key, infer))

  return lines


def _kernel_sections(run, baseline, baseline_label: str, label: str) -> list:
  """Sections 7-10: the warp, stride-2 3D convolutions, the forward pass, classical."""
  lines = ['', '## 7. Warp: forward+backward on [2, 256, 512, 3]', '']
  lines += _header('implementation', baseline, baseline_label, label)
  for name in ('warp.sample_horizontal', 'gather reference'):
    cell = lambda r, name=name: _time(None if r is None or name not in r else r[name])
    lines.append(f'| {name} ' + _cells(run, baseline, 'warp', cell))
  warp_result = _get(run, 'warp')
  if warp_result and 'max_abs_difference' in warp_result:
    lines.append(f'\nMax |difference| of the two outputs: '
                 f'{warp_result["max_abs_difference"]:.2e}.')

  lines += ['', '## 8. Stride-2 3D conv implementations (`ops/conv3d.py`)', '']
  lines += _header('measurement', baseline, baseline_label, label)
  for implementation in ('native', 'dense'):
    result = _get(run, f'conv3d/{implementation}') or {}
    for name in [k for k in result if k not in ('peak_gib', 'load', 'error')]:
      cell = lambda r, name=name: _time(None if r is None or name not in r else r[name])
      lines.append(f'| {implementation}: {name} ' +
                   _cells(run, baseline, f'conv3d/{implementation}', cell))

  lines += ['', '## 9. Forward pass at the paper crop (Keras model, inference, 256x512)', '']
  lines += _header('measurement', baseline, baseline_label, label)
  lines.append('| both disparities, batch 1 ' + _cells(
      run, baseline, 'forward/paper',
      lambda r: _time(r) + ('' if r is None or 'error' in r else
                            f'; peak {r["peak_gib"]:.2f} GiB')))

  lines += ['', '## 10. Classical baseline (no training), one held-out `sample` scene', '']
  lines += _header('mixture', baseline, baseline_label, label)
  for name in ('anaglyph', 'diplopia'):
    cell = lambda r, name=name: ('not run' if r is None else f'FAILED: {r["error"]}'
                                 if 'error' in r else f'{r[name]["first"]:.2f} s per '
                                 f'{r["size"]} frame')
    lines.append(f'| {name} ' + _cells(run, baseline, 'classical', cell))
  return lines


def _matcher_section(run) -> list:
  """Section 13 (this run only): `classical.matcher.match` against the NumPy sgm.match."""
  lines = ['', '## 13. Census-SGM matcher (red-cyan anaglyph of a held-out `sample` scene)',
           '', 'numba = `classical.matcher.match` (signed range, window-aligned pair); '
           'NumPy = `classical.sgm.match` on the unshifted pair over [0, max - min]. CPU = '
           'user + sys of all threads; peak = VmHWM of the case\'s process, "before" = its '
           'resident memory before the first timed call (imports incl. TensorFlow, inputs); '
           'bad-1 on the left pixels visible in the right view; load = 1-minute load '
           'average at the start.', '',
           '| size | range | method | wall s (min / median) | CPU s (min) | peak (before) '
           'GiB | bad-1 % | load |', '|---|---|---|---:|---:|---:|---:|---:|']
  keys = sorted((k for k in run['results'] if k.startswith('matcher/')),
                key=lambda k: (int(k.split('/')[1].split('x')[0]), k))
  notes = []
  for key in keys:
    result = run['results'][key]
    if 'error' in result:
      lines.append(f'| {key.split("/")[1]} | | {key} | FAILED: {result["error"]} | | | | |')
      continue
    for search in ('full', 'prior'):
      if search not in result:
        continue
      row = result[search]
      method = result['method']
      if method == 'numba' and search == 'prior':
        method += f' with a prior (mean window {result["mean_window"]:.1f} px)'
      elif method == 'numba' and result['coarse_factor'] > 1:
        method += f' (coarse-to-fine x{result["coarse_factor"]})'
      lines.append(f'| {result["size"]} | [{result["range"][0]}, {result["range"][1]}] | '
                   f'{method} | {row["wall_min"]:.2f} / {row["wall_median"]:.2f} | '
                   f'{row["cpu_min"]:.2f} | {result["peak_gib"]:.2f} '
                   f'({result["rss_before_gib"]:.2f}) | '
                   f'{100 * row["bad1"]:.1f} | {result["load"]:.1f} |')
    if 'load_s' in result:
      notes.append(f'{result["size"]} {result["load_s"]:.1f} s')
  if notes:
    lines += ['', 'numba kernels loaded from the on-disk cache (compiled when there is none) '
              f'on a tiny pair first, per process: {", ".join(notes)}.']
  return lines


def _layer_sections(run) -> list:
  """Sections 11-12 (this run only): the 3D encoder-decoder per layer and per kernel."""
  peak = _get(run, 'machine/conv3d')
  peak = None if not peak or 'error' in peak else peak['gflop_per_s']
  rate = lambda gflop, seconds: f'{gflop / seconds:.1f}' if seconds > 0 else 'n/a'
  lost = lambda gflop, seconds: f'{seconds - gflop / peak:.3f}' if peak else 'n/a'
  lines = ['', '## 11. 3D encoder-decoder per layer (paper step shapes, batch 2, '
           'forward + backward)', '',
           '"lost" = the time beyond what the layer\'s conv FLOPs take at the conv3d '
           'GFLOP/s of section 1 (batch norm, ReLU and slower kernels).', '',
           '| layer | input | seconds | train GFLOP | GFLOP/s | lost (s) |',
           '|---|---|---:|---:|---:|---:|']
  layers = _get(run, 'layers')
  if not layers or 'error' in layers:
    return lines + [f'| all | {_time(layers)} | | | | |']
  total_seconds = total_gflop = 0.0
  for row in layers['rows']:
    seconds, gflop = row['seconds'], row['train_gflop']
    total_seconds, total_gflop = total_seconds + seconds, total_gflop + gflop
    lines.append(f'| {row["layer"]} | {row["input"]} | {seconds:.3f} | {gflop:.1f} | '
                 f'{rate(gflop, seconds)} | {lost(gflop, seconds)} |')
  lines.append(f'| sum | | {total_seconds:.3f} | {total_gflop:.1f} | '
               f'{rate(total_gflop, total_seconds)} | {lost(total_gflop, total_seconds)} |')
  lines += ['', '## 12. TF\'s stride-2 kernels at the largest stride-2 layers', '',
            '| kernel | seconds | GFLOP | GFLOP/s |', '|---|---:|---:|---:|']
  kernels = _get(run, 'stride2_kernels')
  if not kernels or 'error' in kernels:
    return lines + [f'| all | {_time(kernels)} | | |']
  for name, row in kernels.items():
    if isinstance(row, dict):
      lines.append(f'| {name} | {row["seconds"]:.3f} | {row["gflop"]:.1f} | '
                   f'{rate(row["gflop"], row["seconds"])} |')
  return lines


_MODULE_FLOPS = {'separation (U-Net)': 'separation',
                 'feature tower (2D, 4 images)': 'feature tower',
                 '3D encoder-decoder': '3D encoder-decoder'}


def _module_throughput(run) -> list:
  """Achieved GFLOP/s of the conv-bearing modules timed alone, as a fraction of conv3d's."""
  modules, flops, peak = (_get(run, k) for k in ('modules/paper', 'flops/paper',
                                                 'machine/conv3d'))
  if not modules or not flops or not peak or any('error' in r for r in (modules, flops,
                                                                        peak)):
    return []
  lines = ['', f'Achieved by each module alone ({run["label"]}; 3 x its forward conv FLOPs '
           '/ its median time / the conv3d GFLOP/s of section 1):', '']
  for name, key in _MODULE_FLOPS.items():
    if name in modules and key in flops['per_module_gflop']:
      # The stereo parts run on the batch of 2 (direct + mirrored): FLOPs count both.
      rate = 3 * flops['per_module_gflop'][key] / modules[name]['median']
      lines.append(f'- {name}: {rate:.1f} GFLOP/s = '
                   f'{100 * rate / peak["gflop_per_s"]:.1f}% of conv3d')
  return lines
