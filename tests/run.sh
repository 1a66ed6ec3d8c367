#!/usr/bin/env bash
# Runs every test program in BUILD/tests (cmocka) and every tests/test_*.sh
# script, then prints one closing line "N passed, N failed, N skipped".
#   usage: tests/run.sh BUILD LABEL        (TEST_JOBS=N: at most N at once)
# A cmocka program contributes its own pass/fail/skip counts (a skipped test
# is neither a pass nor a failure, but the closing line says how many); a
# script or a program that crashes before its summary counts as one failure.
#
# Tests run side by side, one per core by default (each starts its daemons
# on ports of its own, in directories of its own, and waits for conditions,
# not for time; packing more beside them by their CPU share made the
# real-time tests miss their deadlines on a busy host: replicas not
# listening within 20 s, a sea change late), longest first so the pass ends
# when its longest test does,
# except test_attacks, which runs alone at the end (see below); their lines
# are printed in name order once all are done.
set -u
build=${1:-build}
label=${2:-plain}
jobs=${TEST_JOBS:-$(nproc 2>/dev/null || echo 2)}
passed=0
failed=0
skipped=0
failures=()
logdir="$build/test-logs"
mkdir -p "$logdir"
# The scripts start a python3 for each JSON check (test_client_cli.sh 32).
# A version manager's python3 (pyenv's shim, a shell script that looks up
# the interpreter on every start) costs 0.5 CPU-s a start against 0.08 for
# the interpreter it finds; that interpreter's directory first on PATH runs
# the same python3 without the lookup.  No manager: the directory is
# already python3's own, PATH stays as it is.
if py=$(python3 -c 'import os, sys; print(os.path.dirname(sys.executable))' 2>/dev/null) &&
        [[ -x $py/python3 && $py != "$(dirname "$(command -v python3)")" ]]; then
    export PATH="$py:$PATH"
fi

count_cmocka() {  # file -> sets p f k
    p=$(grep -E '^\[  PASSED  \] [0-9]+ test' "$1" | awk '{s+=$4} END {print s+0}')
    f=$(grep -E '^\[  FAILED  \] [0-9]+ test' "$1" | awk '{s+=$4} END {print s+0}')
    k=$(grep -E '^\[  SKIPPED \] [0-9]+ test' "$1" | awk '{s+=$4} END {print s+0}')
}

# One test in the background: its output in LOG, then its exit status,
# seconds and CPU seconds (user + system, its children's included) in
# LOG.rc.
run_one() {  # name kind(c|sh) path
    local log="$logdir/$1.log" rc TIMEFORMAT='%R %U %S' t
    { t=$( { time {
        if [[ $2 == c ]]; then "$3" >"$log" 2>&1; else BUILD="$build" bash "$3" >"$log" 2>&1; fi
        echo $? >"$log.exit"
    } ; } 2>&1 ) ; }
    read -r rc <"$log.exit" 2>/dev/null || rc=1
    rm -f "$log.exit"
    echo "$rc $(awk -v t="$t" 'BEGIN {split(t, v, " "); printf "%.1f %.1f", v[1], v[2] + v[3]}')" >"$log.rc"
}

tests=()   # "name kind path"
for t in "$build"/tests/test_*; do
    [[ -x "$t" && -f "$t" ]] && tests+=("$(basename "$t") c $t")
done
# Script tests (integration, browser) run only in the plain pass: they drive
# the plain binaries; the daemon's sanitizer coverage comes from its own C tests.
if [[ "$label" == plain ]]; then
    for s in tests/test_*.sh; do
        [[ -f "$s" ]] && tests+=("$(basename "$s") sh $s")
    done
fi
# The longest first: by the seconds of the last run where there was one,
# else by tests/durations (a fresh clone, as CI runs: in name order the
# sanitizer pass's longest test started last and ran alone for a minute).
order=()
for e in "${tests[@]}"; do
    read -r name _ _ <<<"$e"
    secs=$(awk '{print $2}' "$logdir/$name.log.rc" 2>/dev/null)
    [[ -z "$secs" ]] && secs=$(awk -v l="$label" -v n="$name" '$1 == l && $2 == n {print $3}' tests/durations 2>/dev/null)
    order+=("${secs:-0} $e")
done
mapfile -t order < <(printf '%s\n' "${order[@]}" | sort -s -k1,1 -g -r)

# test_attacks judges a witness viewer's frame rate during each attack
# (frames kept, longest gap): beside the rest of the suite it judged the
# suite's load, not the attack.  It runs alone, after the others.
alone=" test_attacks "
for e in "${order[@]}"; do
    read -r _ name kind path <<<"$e"
    [[ $alone == *" $name "* ]] && continue
    rm -f "$logdir/$name.log.rc"
    while (($(jobs -rp | wc -l) >= jobs)); do wait -n; done
    run_one "$name" "$kind" "$path" &
done
wait
for e in "${order[@]}"; do
    read -r _ name kind path <<<"$e"
    [[ $alone == *" $name "* ]] || continue
    rm -f "$logdir/$name.log.rc"
    run_one "$name" "$kind" "$path"
done

for e in "${tests[@]}"; do
    read -r name kind _ <<<"$e"
    log="$logdir/$name.log"
    read -r rc secs cpu <"$log.rc" 2>/dev/null || { rc=1; secs=0; cpu=0; }
    if [[ $kind == c ]]; then
        count_cmocka "$log"
        if [[ $rc -ne 0 && $f -eq 0 ]]; then f=1; fi
    else
        k=0
        if [[ $rc -eq 0 ]]; then p=1; f=0; else p=0; f=1; fi
    fi
    passed=$((passed + p)); failed=$((failed + f)); skipped=$((skipped + k))
    printf '%-28s %4d passed %3d failed %3d skipped  %6ss  cpu %6ss  [%s]\n' "$name" "$p" "$f" "$k" "$secs" "${cpu:-0}" "$label"
    if [[ $f -ne 0 ]]; then
        failures+=("$name")
        # a script's failing checks first (CI shows only the end of the
        # output: a browser run's last scene passing hid which check failed)
        if [[ $kind == c ]]; then grep -E 'FAILED|ERROR|error|Assert|runtime error|Sanitizer' "$log" | head -20
        else grep -E '^not ok|FAIL|died|did not start' "$log" | head -12; tail -6 "$log"; fi
    fi
done

if ((${#failures[@]})); then echo "failing: ${failures[*]} (logs in $logdir)"; fi
echo "$passed $failed $skipped" > "$build/test-summary"
echo "$label: $passed passed, $failed failed, $skipped skipped"
[[ $failed -eq 0 && $passed -gt 0 ]]
