#!/usr/bin/env bash
# Builds every tests/fuzz/fuzz_*.c with clang -fsanitize=fuzzer,address,undefined
# and runs each for $1 seconds (default 60) on its corpus tests/fuzz/corpus_<name>/.
# Sources are compiled directly with clang (not the gcc-built libraries):
# each target links protocol/*.c, sim/*.c and the client library
# (clients/c/*.c), whose unused parts cost nothing.
# Targets build and run FUZZ_JOBS (default: the number of cores) at a time;
# FUZZ_OPT sets the optimisation level (-O1).
#   usage: tests/fuzz/run.sh [SECONDS] [TARGET...]     (run from anywhere)
# Exit status: 0 when every target ran its time without a crash.
set -euo pipefail
cd "$(dirname "$0")/../.."
secs=${1:-60}
shift || true
out=${FUZZ_BUILD:-build/fuzz}
mkdir -p "$out"
# FUZZ_OPT: -O1 by default (executions per second); make test's short pass
# builds at -O0, in half the compile time (14 against 27 CPU-s here)
CFLAGS=(-std=c11 -g "${FUZZ_OPT:--O1}" -fno-omit-frame-pointer -D_GNU_SOURCE -Isim -Iprotocol -Iclients/c
        -I/usr/include/OpenEXR -I/usr/include/cjson
        -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined
        -Wno-unknown-pragmas)
LIBS=(-lwebsockets -lOpenEXRCore-3_1 -lfftw3f_threads -lfftw3f -lproj -lzstd -lcjson -lm -lpthread)
targets=("$@")
if ((${#targets[@]} == 0)); then
    for f in tests/fuzz/fuzz_*.c; do t=$(basename "$f" .c); targets+=("${t#fuzz_}"); done
fi
jobs=${FUZZ_JOBS:-$(nproc)}
mkdir -p "$out/obj"

# Build: every source once (a target's own object is the only one carrying
# LLVMFuzzerTestOneInput), compiled $jobs at a time, then one link per target.
srcs=(protocol/*.c sim/*.c clients/c/*.c)
for name in "${targets[@]}"; do srcs+=("tests/fuzz/fuzz_$name.c"); done
obj_of() { echo "$out/obj/$(echo "$1" | tr / _).o"; }
echo "== fuzz: build ${#targets[@]} targets"
export -f obj_of; export out
printf '%s\n' "${srcs[@]}" | xargs -P "$jobs" -I{} \
    bash -c 'clang "$@" -c {} -o "$(obj_of {})"' _ "${CFLAGS[@]}"
shared=()
for s in protocol/*.c sim/*.c clients/c/*.c; do shared+=("$(obj_of "$s")"); done
for name in "${targets[@]}"; do
    clang "${CFLAGS[@]}" "$(obj_of "tests/fuzz/fuzz_$name.c")" "${shared[@]}" "${LIBS[@]}" -o "$out/fuzz_$name"
done

# Run: each target for $secs on its own core ($jobs at once), so the suite
# waits for the longest, not the sum; every target still gets its full time.
run_one() {
    local name=$1 corpus=tests/fuzz/corpus_$1 work=$out/work_$1
    mkdir -p "$corpus" "$work"
    # New inputs go to a scratch dir so the seed corpus in the repo stays small.
    ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
        "$out/fuzz_$name" -max_total_time="$secs" -max_len=65536 -timeout=10 -rss_limit_mb=2048 \
        -artifact_prefix="$out/crash_${name}_" -print_final_stats=1 "$work" "$corpus" \
        >"$out/fuzz_$name.log" 2>&1
}
declare -A pid_of=()
trap 'kill $(jobs -p) 2>/dev/null || true' EXIT
for name in "${targets[@]}"; do
    while (( $(jobs -rp | wc -l) >= jobs )); do wait -n || true; done
    echo "== fuzz_$name: ${secs}s on tests/fuzz/corpus_$name"
    run_one "$name" &
    pid_of[$name]=$!
done
status=0
for name in "${targets[@]}"; do
    if ! wait "${pid_of[$name]}"; then
        echo "== fuzz_$name: FAILED (log $out/fuzz_$name.log)"
        tail -40 "$out/fuzz_$name.log"
        status=1
    else
        grep -E '^stat::number_of_executed_units|^#[0-9]+.*DONE' "$out/fuzz_$name.log" | tail -2 || true
        echo "== fuzz_$name: ok"
    fi
done
exit $status
