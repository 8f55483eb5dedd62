#!/usr/bin/env bash
# README's main command: installs what is missing, builds, then runs the pickdetect element on
# sample data made on the spot from OpenCV's box.png (Debian's opencv-doc; nothing is
# downloaded): a conveyor clip with several boxes is recorded with the instances drawn
# (build/demo/conveyor-annotated.webm), and the instances are read back from the buffers'
# metadata and printed, one line per instance.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
build=${BUILD_DIR:-build}
data=/usr/share/doc/opencv-doc/examples/data
demo="$build/demo"
mkdir -p "$demo"
export PICKDETECT_BUILD_DIR="$build"

echo "== Making a 640x480 conveyor clip of OpenCV's box.png ($demo/conveyor.avi)"
"$build/tools/synth/pickdetect-synth" --video "$demo/conveyor.avi" --kind conveyor \
  --size 640x480 --scenes 20 --instances 3-4 --scale 0.5-0.55 --seed 3 "$data/box.png" >/dev/null

echo "== Recording it with pickdetect draw=true ($demo/conveyor-annotated.webm)"
pipelines/record-annotated.sh "$demo/conveyor-annotated.webm" "$demo/conveyor.avi" "$data/box.png"

echo "== The instances, read from the buffers' metadata"
/usr/bin/python3 pipelines/read-instances.py --model "$data/box.png" "$demo/conveyor.avi"
