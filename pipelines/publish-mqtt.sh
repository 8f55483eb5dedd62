#!/usr/bin/env bash
# SPDX-License-Identifier: LGPL-2.1-or-later
# Publishes the instances of every frame to an MQTT broker, one message per frame holding its
# JSON line (pickdetectjson), through mosquitto_pub -l (Debian's mosquitto-clients): many cells
# and robots can share one broker.
#
#   pipelines/publish-mqtt.sh [INPUT] [MODEL]
#   mosquitto_sub -h 127.0.0.1 -t pickdetect/cell/instances     # elsewhere: the messages
#
# INPUT is a video file or a picture (default OpenCV's box_in_scene.png, made into a clip of
# FRAMES frames at 10 frames/s); MODEL a model file or picture (default OpenCV's box.png).
# Environment: MQTT_HOST (default 127.0.0.1), MQTT_PORT (default 1883), MQTT_TOPIC (default
# pickdetect/cell/instances), MQTT_QOS (default 0), CALIBRATION (a file from
# pickdetect-calibrate: millimetres too), FRAMES (default 50), EMPTY (true: also frames with no
# instance; default false).
#
# The plugin is found through GST_PLUGIN_PATH=<builddir>/gst (uninstalled) or
# PICKDETECT_BUILD_DIR=<builddir>, else in GStreamer's plugin folder after `meson install`.
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=robot-output-common.sh
source "$(dirname "${BASH_SOURCE[0]}")/robot-output-common.sh"

data=/usr/share/doc/opencv-doc/examples/data
input=${1:-$data/box_in_scene.png}
model=${2:-$data/box.png}
frames=${FRAMES:-50}

find_pickdetect
command -v mosquitto_pub >/dev/null || { echo "mosquitto_pub not found (Debian: mosquitto-clients)" >&2; exit 1; }
read_input_model_calibration "$input" "$model" "$frames"

# gst-launch -q writes nothing else to stdout: stdout is the JSON lines alone.
gst-launch-1.0 -q -e "${source[@]}" ! videoconvert ! \
  pickdetect model="$model" "${calibration[@]}" post-messages=false ! \
  pickdetectjson add-empty-results="${EMPTY:-false}" ! fdsink fd=1 sync=false |
  mosquitto_pub -h "${MQTT_HOST:-127.0.0.1}" -p "${MQTT_PORT:-1883}" -t "${MQTT_TOPIC:-pickdetect/cell/instances}" \
    -q "${MQTT_QOS:-0}" -l
