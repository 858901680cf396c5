#!/usr/bin/env bash
# Measures a hardware GPU the way BENCHMARKS.md's "A hardware GPU" section was measured: the
# passes at 1920×1080 (no AO, every Bevy SSAO level, every preset), the far-field rows without
# the thousands-of-spheres ones (which stall a GPU with little rasterization hardware),
# `ao_capture --timings` of Bevy's SSAO against the default, then every GPU test in a process of
# its own with a time limit, stopping at the first test that outlives it: a GPU that stops
# answering fails every later test, so later results would say nothing.
#
#   docs/hardware_gpu.sh [OUT_DIR]
#
# OUT_DIR (default target/hardware_gpu) receives passes.txt, far.txt, capture.txt, tests.txt and
# one log per test. Environment: TESTS (a grep pattern choosing tests, default all), TEST_LIMIT
# (seconds per test, default 60), SIZE (default 1920x1080), BENCH=0 to leave the benchmarks out.
# On a machine without cargo, give binaries built elsewhere (`cargo bench --profile dev --bench
# gpu_passes --no-run`, `cargo test --test gpu --no-run`, `cargo build --example ao_capture`) as
# BENCH_BIN, TESTS_BIN and CAPTURE_BIN, and run from a checkout at the path they were built in
# (the tests read the crate's assets there); the tests that call cargo then fail.
set -uo pipefail
cd "$(dirname "$0")/.."
out=${1:-target/hardware_gpu}
mkdir -p "$out/logs"
size=${SIZE:-1920x1080}
width=${size%x*}
height=${size#*x}
limit=${TEST_LIMIT:-60}

bench=${BENCH_BIN:-$(cargo bench --profile dev --bench gpu_passes --no-run 2>&1 |
    sed -n 's/.*Executable .*(\(.*\))/\1/p')}
tests=${TESTS_BIN:-$(cargo test --test gpu --no-run 2>&1 |
    sed -n 's/.*Executable .*(\(.*\))/\1/p')}
[ -x "$bench" ] && [ -x "$tests" ] || { echo "the build failed" >&2; exit 1; }

if [ "${BENCH:-1}" != 0 ]; then
    "$bench" --width "$width" --height "$height" --frames 60 \
        --only "no AO,Bevy SSAO,preset" >"$out/passes.txt" 2>"$out/logs/passes.log"
    echo "passes: exit $? ($out/passes.txt)"
    "$bench" --width "$width" --height "$height" --frames 30 \
        --only "AO fields,voxels,near field,near + fields,near + voxels,near + spheres" \
        >"$out/far.txt" 2>"$out/logs/far.log"
    echo "far field: exit $? ($out/far.txt)"
    capture=${CAPTURE_BIN:-}
    if [ -z "$capture" ] && cargo build --example ao_capture >/dev/null 2>&1; then
        capture=${CARGO_TARGET_DIR:-target}/debug/examples/ao_capture
    fi
    if [ -x "$capture" ]; then
        # Bevy's SSAO and the default alternate, twice, so a GPU still raising its clocks shows.
        for round in 1 2; do for scene in toasters cube_on_plane; do
            for technique in bevy-ssao default; do
                printf '%s %s round %s: ' "$scene" "$technique" "$round"
                "$capture" --scene "assets/scenes/$scene.glb" --width "$width" --height "$height" \
                    --radius 0.75 --technique "$technique" --frames 60 --timings \
                    --out-ao "$out/$scene-$technique.png" 2>>"$out/logs/capture.log" |
                    grep '^timings: ao_gpu'
            done
        done; done | tee "$out/capture.txt"
    fi
fi

: >"$out/tests.txt"
"$tests" --list 2>/dev/null | sed -n 's/: test$//p' | grep -e "${TESTS:-.}" | while read -r name; do
    [ -n "$name" ] || continue
    start=$(date +%s)
    timeout "$limit" "$tests" --exact "$name" --nocapture >"$out/logs/$name.log" 2>&1
    code=$?
    echo "$name exit $code $(($(date +%s) - start)) s" | tee -a "$out/tests.txt"
    if [ "$code" -eq 124 ]; then
        echo "stopped: $name outlived ${limit} s; the GPU may no longer answer" | tee -a "$out/tests.txt"
        break
    fi
done
echo "tests: $(grep -c ' exit 0 ' "$out/tests.txt") passed of $(grep -c ' exit ' "$out/tests.txt") run"
