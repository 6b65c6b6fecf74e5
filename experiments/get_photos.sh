#!/usr/bin/env bash
# The photographs of the matching features' training warps (data_lists/photos/warps.txt):
# downloads the Debian packages that hold them and copies the listed files into one folder.
#   bash experiments/get_photos.sh [FOLDER [LIST]]
#     (defaults: photos/warps, data_lists/photos/warps.txt; a list's optional fifth column
#     names the copied file, else it keeps its own name)
# Needs apt-get (Debian or Ubuntu with the bookworm packages available) and dpkg-deb.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-photos/warps}"
list="${2:-data_lists/photos/warps.txt}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"
packages=$(grep -v '^#' "$list" | awk '{print $1}' | sort -u)
(cd "$work" && apt-get download $packages)
for deb in "$work"/*.deb; do dpkg-deb -x "$deb" "$work/root"; done
grep -v '^#' "$list" | while read -r package version path licence name; do
  cp "$work/root$path" "$out/${name:-$(basename "$path")}"
done
echo "$(ls "$out" | wc -l) photographs in $out"
