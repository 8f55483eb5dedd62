#!/usr/bin/env bash
# Soak: 10,000 frames (320x240, OpenCV's box.png at scale 0.5 on noise, a new buffer each frame)
# through appsrc ! videoconvert ! pickdetect ! fakesink. Prints the resident memory after the
# first 500 frames and at the end, each taken after malloc_trim (what glibc keeps free in its
# arenas is not counted: it grows to a plateau over the first thousand frames), and PASS when it
# grew by at most 5 % (exit status 0). Arguments go to pickdetect-soak (--frames N --baseline N
# --size WxH --scale S --tolerance F --every N; --every prints the trimmed and untrimmed RSS and
# glibc's malloc figures every N frames).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh >/dev/null
build=${BUILD_DIR:-build}
export GST_PLUGIN_PATH="$PWD/$build/gst"
export GST_REGISTRY_FORK=no
exec "$build/tools/soak/pickdetect-soak" --frames 10000 --baseline 500 --size 320x240 --scale 0.5 \
  --tolerance 0.05 "$@"
