#!/bin/sh
# SPDX-License-Identifier: LGPL-2.1-or-later
# Live detection from a V4L2 camera, drawn on screen. A template: adapt the caps to your camera.
#
#   pipelines/live-camera.sh MODEL [DEVICE]
#
# MODEL is a model file (.yml) or a picture of the object; DEVICE defaults to /dev/video0.
# Environment:
#   CAPS    caps asked of the camera (default video/x-raw,width=640,height=480); pickdetect's
#           cost grows with the frame size (SIFT): full SIFT at 640x480 runs at about 12
#           frames per second on two cores (see DETECT for more)
#   SOURCE  replaces the camera, e.g. SOURCE="videotestsrc is-live=true" to try the pipeline
#   SINK    replaces the display (default autovideosink), e.g. SINK=fakesink
#   DETECT  extra pickdetect properties, e.g. the camera-rate configuration of README's Speed
#           section: DETECT="detection-scale=0.6 min-matches=4 threads=2"
#   PICKDETECT_BUILD_DIR=<builddir> or GST_PLUGIN_PATH=<builddir>/gst to use the uninstalled
#           plugin
#
# The leaky queue drops camera frames while pickdetect is busy, so the picture stays live rather
# than lagging ever further behind; sync=false shows each frame as soon as it is ready. Bus
# messages with the instances are printed by -m (post-messages is on by default).
set -eu

if [ $# -lt 1 ]; then
  sed -n '3,22p' "$0" >&2
  exit 2
fi
model=$1
device=${2:-/dev/video0}
caps=${CAPS:-video/x-raw,width=640,height=480}
source=${SOURCE:-v4l2src device=$device}
sink=${SINK:-autovideosink}
detect=${DETECT:-}

if [ -n "${PICKDETECT_BUILD_DIR:-}" ]; then
  GST_PLUGIN_PATH="$PICKDETECT_BUILD_DIR/gst${GST_PLUGIN_PATH:+:$GST_PLUGIN_PATH}"
  export GST_PLUGIN_PATH
fi
gst-inspect-1.0 pickdetect >/dev/null 2>&1 || {
  echo "pickdetect not found: set GST_PLUGIN_PATH=<builddir>/gst or PICKDETECT_BUILD_DIR=<builddir>" >&2
  exit 1
}

# glibc hands SIFT's pyramid (about 200 MB a frame at 1280x960) back to the system after each
# frame and faults it in again; keeping freed memory in the process makes a frame about a third
# cheaper (docs/performance.md, "The process's heap"). A value already set is kept.
: "${GLIBC_TUNABLES:=glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=1073741824}"
export GLIBC_TUNABLES

# shellcheck disable=SC2086 # $source, $detect and $sink are pipeline fragments.
exec gst-launch-1.0 -m $source ! "$caps" ! videoconvert ! video/x-raw,format=I420 ! \
  queue leaky=downstream max-size-buffers=1 ! \
  pickdetect model="$model" draw=true $detect ! \
  videoconvert ! $sink sync=false
