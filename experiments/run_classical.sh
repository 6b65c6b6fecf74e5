#!/usr/bin/env bash
# The training-free classical baseline on the `sample` held-out scenes and the Middlebury
# Motorcycle pair, for anaglyph and diplopia; writes experiments/results/classical.md.
#
#   bash experiments/run_classical.sh
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p experiments/results
out=experiments/results/classical.md
echo "# Classical baseline (no training) on the sample held-out set" > "$out"
echo >> "$out"
echo "Written by \`bash experiments/run_classical.sh\`." >> "$out"
for mixture in anaglyph diplopia; do
  python -m mixstereo_tf.evaluate --protocol=sample --method=classical \
    --mixture="$mixture" --output_csv="experiments/results/classical_$mixture.csv" \
    --output_markdown="experiments/results/classical_$mixture.md"
  echo >> "$out"
  cat "experiments/results/classical_$mixture.md" >> "$out"
  rm "experiments/results/classical_$mixture.md"
done
