#!/usr/bin/env bash
# SPDX-License-Identifier: LGPL-2.1-or-later
# Records the annotated video and, at the same time, serves the instances as JSON lines (one
# per frame, pickdetectjson) over TCP to every client that connects: a tee after pickdetect.
#
#   pipelines/serve-json-tcp.sh [OUTPUT.webm] [INPUT] [MODEL]
#   nc 127.0.0.1 5555          # in another terminal: one JSON object per line
#
# OUTPUT defaults to annotated.webm. INPUT is a video file or a picture (default OpenCV's
# box_in_scene.png, made into a clip of FRAMES frames at 10 frames/s, played in real time);
# MODEL a model file or picture (default OpenCV's box.png). Environment: HOST (default
# 127.0.0.1; 0.0.0.0 serves the network) and PORT (default 5555) of the server, CALIBRATION (a
# file from pickdetect-calibrate: millimetres too), FRAMES (default 50).
#
# The plugin is found through GST_PLUGIN_PATH=<builddir>/gst (uninstalled) or
# PICKDETECT_BUILD_DIR=<builddir>, else in GStreamer's plugin folder after `meson install`.
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=robot-output-common.sh
source "$(dirname "${BASH_SOURCE[0]}")/robot-output-common.sh"

data=/usr/share/doc/opencv-doc/examples/data
output=${1:-annotated.webm}
input=${2:-$data/box_in_scene.png}
model=${3:-$data/box.png}
frames=${FRAMES:-50}
host=${HOST:-127.0.0.1}
port=${PORT:-5555}

find_pickdetect
read_input_model_calibration "$input" "$model" "$frames"

# The TCP branch keeps the clock (sync=true): lines go out as the frames would be shown.
gst-launch-1.0 -e "${source[@]}" ! videoconvert ! video/x-raw,format=I420 ! \
  pickdetect model="$model" "${calibration[@]}" draw=true post-messages=false ! tee name=t \
  t. ! queue ! vp8enc deadline=1 ! webmmux ! filesink location="$output" \
  t. ! queue ! pickdetectjson add-empty-results=true ! \
  tcpserversink host="$host" port="$port" sync=true
echo "wrote $output" >&2
