#!/usr/bin/env bash
# Installs the Debian 12 packages gst-pickdetect needs to build, test and run, if missing.
set -euo pipefail

packages=(
  g++ meson ninja-build pkg-config
  libopencv-dev libeigen3-dev libglib2.0-dev libjson-glib-dev
  libgstreamer1.0-dev libgstreamer-plugins-base1.0-dev
  gstreamer1.0-tools gstreamer1.0-plugins-base gstreamer1.0-plugins-good
  libgtest-dev opencv-doc
  python3 python3-gi python3-gst-1.0 gir1.2-gst-plugins-base-1.0
  valgrind clang libclang-rt-14-dev  # robustness: valgrind tests, scripts/fuzz.sh (libFuzzer)
  mosquitto mosquitto-clients        # pipelines/publish-mqtt.sh and its test (a broker on 127.0.0.1)
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

sudo=()
if [ "$(id -u)" -ne 0 ]; then
  sudo=(sudo)
fi
echo "Installing: ${missing[*]}" >&2
"${sudo[@]}" apt-get update -q
DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
