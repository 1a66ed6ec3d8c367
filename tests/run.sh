#!/usr/bin/env bash
# Runs every test program in BUILD/tests (cmocka) and every tests/test_*.sh
# script, then prints one closing line "N passed, N failed, N skipped".
#   usage: tests/run.sh BUILD LABEL
# A cmocka program contributes its own pass/fail/skip counts (a skipped test
# is neither a pass nor a failure, but the closing line says how many); a
# script or a program that crashes before its summary counts as one failure.
set -u
build=${1:-build}
label=${2:-plain}
passed=0
failed=0
skipped=0
failures=()
logdir="$build/test-logs"
mkdir -p "$logdir"

count_cmocka() {  # file -> sets p f k
    p=$(grep -E '^\[  PASSED  \] [0-9]+ test' "$1" | awk '{s+=$4} END {print s+0}')
    f=$(grep -E '^\[  FAILED  \] [0-9]+ test' "$1" | awk '{s+=$4} END {print s+0}')
    k=$(grep -E '^\[  SKIPPED \] [0-9]+ test' "$1" | awk '{s+=$4} END {print s+0}')
}

for t in "$build"/tests/test_*; do
    [[ -x "$t" && -f "$t" ]] || continue
    name=$(basename "$t")
    log="$logdir/$name.log"
    start=$(date +%s.%N)
    "$t" >"$log" 2>&1
    rc=$?
    secs=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN {printf "%.1f", b - a}')
    count_cmocka "$log"
    if [[ $rc -ne 0 && $f -eq 0 ]]; then f=1; fi
    passed=$((passed + p)); failed=$((failed + f)); skipped=$((skipped + k))
    printf '%-28s %4d passed %3d failed %3d skipped  %6ss  [%s]\n' "$name" "$p" "$f" "$k" "$secs" "$label"
    if [[ $f -ne 0 ]]; then failures+=("$name"); grep -E 'FAILED|ERROR|error|Assert|runtime error|Sanitizer' "$log" | head -20; fi
done

# Script tests (integration, browser) run only in the plain pass: they drive
# the plain binaries; the daemon's sanitizer coverage comes from its own C tests.
if [[ "$label" == plain ]]; then
    for s in tests/test_*.sh; do
        [[ -f "$s" ]] || continue
        name=$(basename "$s")
        log="$logdir/$name.log"
        start=$(date +%s.%N)
        BUILD="$build" bash "$s" >"$log" 2>&1
        rc=$?
        secs=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN {printf "%.1f", b - a}')
        if [[ $rc -eq 0 ]]; then passed=$((passed + 1)); r="1 passed   0"; else failed=$((failed + 1)); r="0 passed   1"; failures+=("$name"); tail -20 "$log"; fi
        printf '%-28s    %s failed   0 skipped  %6ss  [%s]\n' "$name" "$r" "$secs" "$label"
    done
fi

if ((${#failures[@]})); then echo "failing: ${failures[*]} (logs in $logdir)"; fi
echo "$passed $failed $skipped" > "$build/test-summary"
echo "$label: $passed passed, $failed failed, $skipped skipped"
[[ $failed -eq 0 && $passed -gt 0 ]]
