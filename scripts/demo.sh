#!/usr/bin/env bash
# README's main command: installs what is missing, builds, and finds the box of OpenCV's
# box_in_scene.png (a real photograph shipped by Debian's opencv-doc), printing the instance
# and writing the picture with the instance drawn on it.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
build=${BUILD_DIR:-build}
data=/usr/share/doc/opencv-doc/examples/data
mkdir -p "$build/demo"
"$build/tools/detect/pickdetect-detect" --model "$data/box.png" \
  --annotate "$build/demo/box_in_scene-annotated.png" "$data/box_in_scene.png"
