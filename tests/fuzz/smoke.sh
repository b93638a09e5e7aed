#!/usr/bin/env bash
# Short libFuzzer run of every target (the readers, and the whole pipeline on a small block), for CI.
# Usage: tests/fuzz/smoke.sh BUILD_DIR   (a build configured with clang and -DDEXELMILL_BUILD_FUZZ=ON)
# Each target runs at most ~20 s on a seed corpus made from tests/data and tests/data/path.
set -euo pipefail
build=${1:?usage: smoke.sh BUILD_DIR}
here=$(cd "$(dirname "$0")" && pwd)
data="$here/../data"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

seed() {  # seed NAME PATTERN...
    local name=$1; shift
    mkdir -p "$work/$name"
    for pattern in "$@"; do
        find "$data" -type f -name "$pattern" -size -64k -exec cp {} "$work/$name/" \; 2>/dev/null || true
    done
    # Always have at least one seed.
    [ -n "$(ls -A "$work/$name")" ] || printf 'G0 X0\n' > "$work/$name/seed"
}
seed gcode_fuzz '*.ngc' '*.nc' '*.gcode'
seed pipeline_fuzz '*.ngc' '*.nc' '*.gcode'
seed apt_fuzz '*.apt'
seed camotics_fuzz '*.camotics'

status=0
for target in gcode_fuzz apt_fuzz camotics_fuzz pipeline_fuzz; do
    exe="$build/$target"
    if [ ! -x "$exe" ]; then echo "missing $exe" >&2; status=1; continue; fi
    echo "== $target"
    # A fixed seed keeps CI repeatable: a new finding shows up in a developer's longer runs,
    # not as a flaky red CI.
    "$exe" -seed=1 -max_total_time=15 -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
        -artifact_prefix="$work/" "$work/$target" || { status=1; cp "$work"/crash-* "$work"/timeout-* "$work"/oom-* . 2>/dev/null || true; }
done
exit $status
