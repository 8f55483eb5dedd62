#!/usr/bin/env bash
# Builds (installing what is missing), then times the pickdetect element per frame and per
# stage: bash scripts/bench.sh [--quick] [--json]. The build goes to ${BUILD_DIR:-build}.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh >&2
exec "${BUILD_DIR:-build}/tools/bench/pickdetect-bench" "$@"
