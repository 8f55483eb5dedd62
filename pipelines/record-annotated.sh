#!/bin/sh
# SPDX-License-Identifier: LGPL-2.1-or-later
# Records an annotated clip: pickdetect draws every instance it finds (white outline, green
# centre circle with the number of matches, small circles on the principal points) and the
# result is encoded to WebM (VP8).
#
#   pipelines/record-annotated.sh [OUTPUT.webm] [INPUT] [MODEL]
#
# OUTPUT defaults to annotated.webm. INPUT is a video file or a picture; it defaults to OpenCV's
# box_in_scene.png (opencv-doc), made into a 5 s clip on the fly, so nothing is downloaded.
# MODEL (a .yml model file or a picture) defaults to OpenCV's box.png. FRAMES sets the clip's
# length for a picture (default 50, at 10 frames/s).
#
# The plugin is found through GST_PLUGIN_PATH=<builddir>/gst (uninstalled) or
# PICKDETECT_BUILD_DIR=<builddir>, else in GStreamer's plugin folder after `meson install`.
set -eu

data=/usr/share/doc/opencv-doc/examples/data
output=${1:-annotated.webm}
input=${2:-$data/box_in_scene.png}
model=${3:-$data/box.png}
frames=${FRAMES:-50}

if [ -n "${PICKDETECT_BUILD_DIR:-}" ]; then
  GST_PLUGIN_PATH="$PICKDETECT_BUILD_DIR/gst${GST_PLUGIN_PATH:+:$GST_PLUGIN_PATH}"
  export GST_PLUGIN_PATH
fi
if ! gst-inspect-1.0 pickdetect >/dev/null 2>&1; then
  echo "pickdetect not found: set GST_PLUGIN_PATH=<builddir>/gst or PICKDETECT_BUILD_DIR=<builddir>" >&2
  exit 1
fi
for file in "$input" "$model"; do
  [ -r "$file" ] || { echo "cannot read $file" >&2; exit 1; }
done

case "$input" in
  *.png|*.PNG|*.jpg|*.JPG|*.jpeg|*.bmp|*.tif|*.tiff)
    # A still picture made into a clip at 10 frames/s.
    source="filesrc location=\"$input\" ! decodebin ! imagefreeze num-buffers=$frames ! videorate ! video/x-raw,framerate=10/1" ;;
  *)
    source="filesrc location=\"$input\" ! decodebin" ;;
esac

# glibc hands SIFT's pyramid (about 200 MB a frame at 1280x960) back to the system after each
# frame and faults it in again; keeping freed memory in the process makes a frame about a third
# cheaper (docs/performance.md, "The process's heap"). A value already set is kept.
: "${GLIBC_TUNABLES:=glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=1073741824}"
export GLIBC_TUNABLES

# I420 before pickdetect: it draws in colour on the YUV planes and vp8enc takes I420 as is.
eval gst-launch-1.0 -e $source ! videoconvert ! video/x-raw,format=I420 ! \
  pickdetect model="\"$model\"" draw=true post-messages=false ! \
  vp8enc deadline=1 ! webmmux ! filesink location="\"$output\""
echo "wrote $output"
