#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer build of everything (gcc, meson's b_sanitize) in
# ${ASAN_BUILD_DIR:-build-asan}, then the test suites with any sanitizer report fatal.
#
# Left out here, and run by scripts/test.sh in the plain build (each needs a program that is not
# built with the sanitizers to load our instrumented libraries, which ASan refuses):
#   meta-api-valgrind    valgrind cannot run an ASan binary
#   meta-api-pkg-config  links a plain cc program against the instrumented meta library
#   read-instances       python3 dlopens the instrumented plugin
#   count-objects        python3 dlopens the instrumented plugin, as read-instances
#   record-annotated     gst-launch-1.0 dlopens the instrumented plugin
#   eval-end-to-end      python3 + GStreamer's Python bindings, as read-instances
#   json-tcp, json-mqtt  gst-launch-1.0 (pipelines/serve-json-tcp.sh, publish-mqtt.sh) dlopens
#                        the instrumented plugin
# Extra arguments go to meson test (e.g. a test name).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
build=${ASAN_BUILD_DIR:-build-asan}
if [ ! -f "$build/build.ninja" ]; then
  meson setup "$build" . -Db_sanitize=address,undefined -Db_lundef=false
fi
ninja -C "$build"

supp="$PWD/scripts/lsan.supp"
# fast_unwind_on_malloc=0: whole allocation stacks through GLib (no frame pointers), which the
# suppressions in lsan.supp match on; it costs some 15 % more CPU time.
# intercept_tls_get_addr=0: GCC 12's runtime (Debian 12) takes a dynamic TLS block whose start
# lies 16 bytes into a page for a pre-2.25 glibc block with a header and reads a length from
# before it; a block of a worker thread (OpenCV's pool, GStreamer's) landing there by chance
# makes LeakSanitizer's tracer crash at exit ("Tracer caught signal 11", no leak reported):
# one run in the test-tracking suite, passing when run again. Fixed upstream after GCC 13. Heap
# leaks are still reported with it set (docs/robustness.md).
export ASAN_OPTIONS=halt_on_error=1:abort_on_error=0:detect_leaks=1:detect_stack_use_after_return=0:strict_string_checks=1:check_initialization_order=1:fast_unwind_on_malloc=0:intercept_tls_get_addr=0
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
export LSAN_OPTIONS="suppressions=$supp:print_suppressions=0"
# The GStreamer plugin scanner is a plain program: it could not load the instrumented plugin.
export GST_REGISTRY_FORK=no

skip=(meta-api-valgrind meta-api-pkg-config read-instances record-annotated eval-end-to-end
  json-tcp json-mqtt count-objects)
tests=()
if [ $# -eq 0 ]; then
  while read -r name; do
    name=${name##* / }
    keep=1
    for s in "${skip[@]}"; do
      [ "$name" = "$s" ] && keep=0
    done
    [ $keep -eq 1 ] && tests+=("$name")
  done < <(meson test -C "$build" --list 2>/dev/null | grep ' / ')
  echo "sanitize: running ${#tests[@]} tests; left out (see the header): ${skip[*]}" >&2
fi
meson test -C "$build" --print-errorlogs --num-processes 2 --timeout-multiplier 3 "${tests[@]}" "$@"
