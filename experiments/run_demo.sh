#!/usr/bin/env bash
# The demo end to end: trains on the embedded `sample` source (nothing to download), then
# evaluates the run on the held-out `sample` scenes and the Middlebury Motorcycle pair
# (never trained on) and writes experiments/results/demo.md next to the trivial baseline,
# with the note of what varies between machines (experiments/demo_variation.md).
#
#   bash experiments/run_demo.sh [model_dir]
set -euo pipefail
cd "$(dirname "$0")/.."
model_dir="${1:-runs/demo}"
python -m mixstereo_tf.train --flagfile=experiments/demo.flags --model_dir="$model_dir"
mkdir -p experiments/results
python -m mixstereo_tf.evaluate --protocol=sample --checkpoint="$model_dir" \
  --output_csv=experiments/results/demo.csv \
  --output_markdown=experiments/results/demo.md
# Which figures vary between machines, and by how much (measured; see the note).
cat experiments/demo_variation.md >> experiments/results/demo.md
