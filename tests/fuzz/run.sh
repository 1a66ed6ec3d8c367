#!/usr/bin/env bash
# Builds every tests/fuzz/fuzz_*.c with clang -fsanitize=fuzzer,address,undefined
# and runs each for $1 seconds (default 60) on its corpus tests/fuzz/corpus_<name>/.
# Sources are compiled directly with clang (not the gcc-built libraries):
# each target links protocol/*.c and sim/*.c, whose unused parts cost nothing.
#   usage: tests/fuzz/run.sh [SECONDS] [TARGET...]     (run from anywhere)
# Exit status: 0 when every target ran its time without a crash.
set -euo pipefail
cd "$(dirname "$0")/../.."
secs=${1:-60}
shift || true
out=${FUZZ_BUILD:-build/fuzz}
mkdir -p "$out"
CFLAGS=(-std=c11 -g -O1 -fno-omit-frame-pointer -D_GNU_SOURCE -Isim -Iprotocol
        -I/usr/include/OpenEXR -I/usr/include/cjson
        -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined
        -Wno-unknown-pragmas)
LIBS=(-lOpenEXRCore-3_1 -lfftw3f_threads -lfftw3f -lzstd -lcjson -lm -lpthread)
targets=("$@")
if ((${#targets[@]} == 0)); then
    for f in tests/fuzz/fuzz_*.c; do t=$(basename "$f" .c); targets+=("${t#fuzz_}"); done
fi
status=0
declare -A built=()
for name in "${targets[@]}"; do
    src=tests/fuzz/fuzz_$name.c
    bin=$out/fuzz_$name
    echo "== fuzz_$name: build"
    # Each source compiles to its own object so a target's main object is
    # the only one carrying LLVMFuzzerTestOneInput.
    objs=()
    mkdir -p "$out/obj"
    for s in "$src" protocol/*.c sim/*.c; do
        [[ -f "$s" ]] || continue
        o="$out/obj/$(echo "$s" | tr / _).o"
        # shared sources are built once per run
        if [[ -z "${built[$o]:-}" ]]; then
            clang "${CFLAGS[@]}" -c "$s" -o "$o"
            built[$o]=1
        fi
        objs+=("$o")
    done
    clang "${CFLAGS[@]}" "${objs[@]}" "${LIBS[@]}" -o "$bin"
    corpus=tests/fuzz/corpus_$name
    work=$out/work_$name
    mkdir -p "$corpus" "$work"
    echo "== fuzz_$name: ${secs}s on $corpus"
    # New inputs go to a scratch dir so the seed corpus in the repo stays small.
    if ! ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
        "$bin" -max_total_time="$secs" -max_len=65536 -timeout=10 -rss_limit_mb=2048 \
        -artifact_prefix="$out/crash_${name}_" -print_final_stats=1 "$work" "$corpus" \
        >"$out/fuzz_$name.log" 2>&1; then
        echo "== fuzz_$name: FAILED (log $out/fuzz_$name.log)"
        tail -40 "$out/fuzz_$name.log"
        status=1
    else
        grep -E '^stat::number_of_executed_units|^#[0-9]+.*DONE' "$out/fuzz_$name.log" | tail -2 || true
        echo "== fuzz_$name: ok"
    fi
done
exit $status
