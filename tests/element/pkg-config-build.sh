#!/bin/sh
# Builds meta-api.c the way an application would, with
#   cc $(pkg-config --cflags --libs gstreamer-pickdetect-meta-1.0)
# against the uninstalled build (meson writes <builddir>/meson-uninstalled/*-uninstalled.pc,
# which pkg-config prefers), then runs it.
# Usage: pkg-config-build.sh BUILD_ROOT SOURCE OUTPUT
set -eu
build_root=$1
source=$2
output=$3
PKG_CONFIG_PATH="$build_root/meson-uninstalled${PKG_CONFIG_PATH:+:$PKG_CONFIG_PATH}"
export PKG_CONFIG_PATH
flags=$(pkg-config --cflags --libs gstreamer-pickdetect-meta-1.0)
echo "pkg-config: $flags"
${CC:-cc} -std=c11 -Wall -Wextra -Werror -o "$output" "$source" $flags -lm
LD_LIBRARY_PATH="$build_root/gst-libs/gst/pickdetect${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" "$output"
