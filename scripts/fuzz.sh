#!/usr/bin/env bash
# libFuzzer runs (clang, ASan + UBSan) of the model loader (fuzz-model), the detector on
# fuzzed frames (fuzz-detect) and the element with fuzzed caps and buffers (fuzz-element), for
# FUZZ_SECONDS (60) each. Build dir: ${FUZZ_BUILD_DIR:-build-fuzz}. The seeds are in
# fuzz/corpus/<target>/ (kept small, in git); what a run adds goes to <build>/corpus/<target>/,
# crashes to <build>/artifacts/. Exit status 0 only when no target found anything.
# Usage: scripts/fuzz.sh [target...]   e.g. FUZZ_SECONDS=5 scripts/fuzz.sh fuzz-model
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
build=${FUZZ_BUILD_DIR:-build-fuzz}
seconds=${FUZZ_SECONDS:-60}
if [ ! -f "$build/build.ninja" ]; then
  CC=clang CXX=clang++ meson setup "$build" . -Dfuzz=enabled -Dtests=disabled \
    -Db_sanitize=address,undefined -Db_lundef=false -Dbuildtype=debugoptimized
fi
ninja -C "$build"

targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(fuzz-model fuzz-detect fuzz-element)
# fast_unwind_on_malloc=0: whole allocation stacks through GLib, for lsan.supp (see there).
export ASAN_OPTIONS=halt_on_error=1:detect_leaks=1:allocator_may_return_null=1:fast_unwind_on_malloc=0
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
export LSAN_OPTIONS="suppressions=$PWD/scripts/lsan.supp:print_suppressions=0"
export GST_REGISTRY_FORK=no
export GST_REGISTRY_1_0="$PWD/$build/fuzz-registry.bin"
status=0
for t in "${targets[@]}"; do
  name=${t#fuzz-}
  mkdir -p "$build/corpus/$name" "$build/artifacts/$name"
  echo "== $t: $seconds s" >&2
  # -rss_limit_mb: a model picture may be up to 4096 x 4096; PNG and JPEG pictures are checked
  # from their header, other formats once decoded.
  if "$build/fuzz/$t" -max_total_time="$seconds" -timeout=30 -rss_limit_mb=3072 \
      -max_len=65536 -print_final_stats=1 -artifact_prefix="$build/artifacts/$name/" \
      "$build/corpus/$name" "fuzz/corpus/$name" 2>"$build/$t.log"; then
    grep -E "^stat::number_of_executed_units|^Done" "$build/$t.log" | tr '\n' ' ' >&2
    echo "-> $t: OK" >&2
  else
    tail -40 "$build/$t.log" >&2
    echo "-> $t: FAILED (see $build/$t.log and $build/artifacts/$name/)" >&2
    status=1
  fi
done
exit $status
