#!/usr/bin/env bash
# The paper's path on this machine's accelerator, meant for under 10 minutes (issue 29): the
# environment and the device line, training steps/s of the paper's network with XLA off / on
# and float32 / --mixed_precision (first step, i.e. compilation, apart), peak memory, and
# one SavedModel inference on a 375x1242 frame. Writes experiments/results/gpu_check.md.
#
#   bash experiments/gpu_check.sh            # the paper's configuration (on a GPU)
#   bash experiments/gpu_check.sh --small    # the demo's network: a CPU proof run
#   GPU_CHECK_CONFIG=small bash experiments/gpu_check.sh   # the same
#
# Further arguments go to experiments/gpu_check.py (--check_steps, --check_seconds,
# --check_output).
set -euo pipefail
cd "$(dirname "$0")/.."
config="${GPU_CHECK_CONFIG:-paper}"
if [[ "${1:-}" == "--small" ]]; then
  config=small
  shift
fi
exec python experiments/gpu_check.py --check_config="$config" "$@"
