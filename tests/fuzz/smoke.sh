#!/usr/bin/env bash
# Short libFuzzer run of every target (the readers, the whole pipeline on a small block, and the
# check of a VDB file's framing), for CI.
# Usage: tests/fuzz/smoke.sh BUILD_DIR   (a build configured with clang and -DDEXELMILL_BUILD_FUZZ=ON)
# Each target runs at most ~15 s, from the checked-in seed corpus tests/fuzz/corpus/NAME (programs
# from tests/data and from the reader tests, and small VDB files dexelmill wrote; a G-code or
# project seed may carry the files it names after "//@file NAME" lines, see harness.h), copied so
# that the run does not write into the tree.
set -euo pipefail
build=${1:?usage: smoke.sh BUILD_DIR}
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

status=0
for name in gcode apt camotics pipeline vdb_frame; do
    target=${name}_fuzz
    exe="$build/$target"
    mkdir -p "$work/$target"
    cp "$here/corpus/$name"/* "$work/$target/"
    if [ ! -x "$exe" ]; then echo "missing $exe" >&2; status=1; continue; fi
    echo "== $target"
    # A fixed seed keeps CI repeatable: a new finding shows up in a developer's longer runs,
    # not as a flaky red CI. The timeout allows for the command line's block limit: an endless
    # loop that keeps counting stops after 50 million blocks, 2.4 s in a release build and over a
    # minute under the sanitizers.
    "$exe" -seed=1 -max_total_time=15 -timeout=300 -rss_limit_mb=2048 -print_final_stats=1 \
        -artifact_prefix="$work/" "$work/$target" || { status=1; cp "$work"/crash-* "$work"/timeout-* "$work"/oom-* . 2>/dev/null || true; }
done
exit $status
