# SPDX-License-Identifier: LGPL-2.1-or-later
# Sourced by the bash pipelines beside it (serve-json-tcp.sh, publish-mqtt.sh), not run: what
# they share to find the plugin and read their input, model and calibration.
# shellcheck shell=bash disable=SC2034 # source and calibration are set for those scripts.

# Finds the plugin through GST_PLUGIN_PATH=<builddir>/gst or PICKDETECT_BUILD_DIR=<builddir>,
# else in GStreamer's plugin folder; exits when pickdetectjson is not there. Keeps glibc's
# freed memory in the process (GLIBC_TUNABLES, unless set).
find_pickdetect() {
  if [ -n "${PICKDETECT_BUILD_DIR:-}" ]; then
    export GST_PLUGIN_PATH="$PICKDETECT_BUILD_DIR/gst${GST_PLUGIN_PATH:+:$GST_PLUGIN_PATH}"
  fi
  if ! gst-inspect-1.0 pickdetectjson >/dev/null 2>&1; then
    echo "pickdetect not found: set GST_PLUGIN_PATH=<builddir>/gst or PICKDETECT_BUILD_DIR=<builddir>" >&2
    exit 1
  fi
  # glibc hands SIFT's pyramid back to the system after each frame and faults it in again;
  # keeping freed memory in the process makes a frame about a third cheaper
  # (docs/performance.md, "The process's heap"). A value already set is kept.
  export GLIBC_TUNABLES=${GLIBC_TUNABLES:-glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=1073741824}
}

# read_input_model_calibration INPUT MODEL FRAMES: checks that INPUT, MODEL and $CALIBRATION
# (when set) can be read, then sets the arrays source (gst-launch elements up to decoded frames:
# a picture becomes a clip of FRAMES frames at 10 frames/s) and calibration (pickdetect's
# calibration property, or nothing).
read_input_model_calibration() {
  local input=$1 model=$2 frames=$3 file
  for file in "$input" "$model" ${CALIBRATION:+"$CALIBRATION"}; do
    [ -r "$file" ] || { echo "cannot read $file" >&2; exit 1; }
  done

  case "$input" in
    *.png|*.PNG|*.jpg|*.JPG|*.jpeg|*.bmp|*.tif|*.tiff)
      source=(filesrc location="$input" ! decodebin ! imagefreeze num-buffers="$frames" ! videorate !
              video/x-raw,framerate=10/1) ;;
    *)
      source=(filesrc location="$input" ! decodebin) ;;
  esac
  calibration=()
  if [ -n "${CALIBRATION:-}" ]; then
    calibration=(calibration="$CALIBRATION")
  fi
}
