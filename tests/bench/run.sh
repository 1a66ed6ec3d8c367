#!/usr/bin/env bash
# tests/bench/run.sh BUILD - the `make bench` driver.
#
# Runs every benchmark that exists, in a fixed order, then writes
# tests/bench/REPORT.md (machine, date, the command that reproduces it, each
# benchmark's markdown section) with CSV files and PNG plots in
# tests/bench/out/.  A benchmark that is not built is noted, not fatal; one
# that fails is reported and makes the run exit non-zero after the report is
# written.
#
#   make bench                  full run (about 40 minutes on 2 cores, 25 of them bench_look)
#   BENCH_QUICK=1 make bench    every sweep shortened (about 3 minutes)
#   BENCH_ONLY="bench_core bench_accuracy" make bench
#                               only those (the others are listed as skipped)
#
# Each benchmark prints markdown to stdout (captured as out/<name>.md),
# writes its own CSV into tests/bench/out/, and reads BENCH_QUICK (and the
# older OCEAN_BENCH_QUICK) to shorten itself.
set -u

BUILD=${1:-build}
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
cd "$ROOT" || exit 1
OUT=tests/bench/out
REPORT=tests/bench/REPORT.md
mkdir -p "$OUT"

QUICK=${BENCH_QUICK:-0}
[ "$QUICK" = "0" ] && QUICK=
if [ -n "$QUICK" ]; then
    export BENCH_QUICK=1 OCEAN_BENCH_QUICK=1
    CMD="BENCH_QUICK=1 make bench"
    LIMIT=600
else
    unset BENCH_QUICK OCEAN_BENCH_QUICK
    CMD="make bench"
    LIMIT=1500
fi
[ -n "${BENCH_ONLY:-}" ] && CMD="BENCH_ONLY=\"$BENCH_ONLY\" $CMD"

# ---- the machine ------------------------------------------------------------
NPROC=$(nproc 2>/dev/null || echo '?')
CPU=$(sed -n 's/^model name[[:space:]]*:[[:space:]]*//p' /proc/cpuinfo 2>/dev/null | head -n1)
[ -n "$CPU" ] || CPU=$(uname -m)
MEM=$(awk '/MemTotal/ {printf "%.1f GiB", $2 / 1048576}' /proc/meminfo 2>/dev/null)
KERNEL=$(uname -sr)
CCV=$(${CC:-gcc} --version 2>/dev/null | head -n1)
FFTWV=$(dpkg-query -W -f='${Version}' libfftw3-dev 2>/dev/null || echo '?')
DATE=$(date -u '+%Y-%m-%d %H:%M UTC')
REV=$(git rev-parse --short HEAD 2>/dev/null || echo 'no git')
# the report's own outputs (REPORT.md, out/, README-section.md) do not count
if [ -n "$(git status --porcelain -- . ':!tests/bench/out' ':!tests/bench/REPORT.md' \
           ':!tests/bench/README-section.md' ':!README.md' 2>/dev/null | head -n1)" ]; then
    REV="$REV (with uncommitted changes)"
fi
LOAD=$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null)
MACHINE="$NPROC x $CPU, $MEM"

echo "bench: $MACHINE; $DATE; $CMD" >&2

# ---- the benchmarks ----------------------------------------------------------
# name | how to run | what it is
declare -a NAMES=() TITLES=() STATUS=() SECS=()
ANY_FAILED=0

run_one() {  # name title command...
    local name=$1 title=$2
    shift 2
    local t0 t1 rc
    echo "bench: running $name ..." >&2
    t0=$(date +%s)
    # the look renders 15 reference images and 30 screenshots: twice the time
    local limit=$LIMIT
    [ "$name" = bench_look ] && limit=$((2 * LIMIT))
    timeout "$limit" "$@" >"$OUT/$name.md" 2>"$OUT/$name.log"
    rc=$?
    t1=$(date +%s)
    NAMES+=("$name"); TITLES+=("$title"); SECS+=("$((t1 - t0))")
    if [ $rc -eq 0 ]; then
        STATUS+=("ok")
    elif [ $rc -eq 124 ]; then
        STATUS+=("TIMED OUT after ${limit} s"); ANY_FAILED=1
    else
        STATUS+=("FAILED (exit $rc)"); ANY_FAILED=1
    fi
    echo "$DATE, revision $REV, \`$CMD\`, on $MACHINE" >"$OUT/$name.stamp"
    echo "bench: $name: ${STATUS[-1]} in $((t1 - t0)) s" >&2
}

missing() {  # name title
    NAMES+=("$1"); TITLES+=("$2"); SECS+=("-"); STATUS+=("not built")
    : >"$OUT/$1.md"
    echo "bench: $1 not built; skipped" >&2
}

# Known benchmarks first, in report order; then any other program in
# $BUILD/bench so a new benchmark is never left out.
declare -A KNOWN_TITLE=(
    [bench_core]="FFT core against FFTW alone, plans and contention (issues 2, 14)"
    [bench_accuracy]="Accuracy against cost (issue 8)"
    [bench_codec]="Tile codecs (issue 5)"
    [bench_mesh]="LOD meshes (issue 4)"
    [bench_meshqz]="Layout-0 mesh positions, f32 and qz (issue 14)"
    [bench_server]="Daemon under load"
    [bench_decode]="The viewer's decoding: WebAssembly against native C"
    [bench_link]="A viewer on a slow link: frames coarser, not older"
    [bench_cigi]="The CIGI service: 64 HAT/HOT Extended Requests a host frame at 60 Hz (issue 42)"
    [bench_wakes]="Ships' wakes: 16 ships in a viewer's view against none (issue 43)"
    [bench_wake_look]="Ships' wakes as the browser viewer draws them (issue 43)"
    [bench_look]="The look: the viewer against a reference render of the exact sea (issue 45)"
)
ORDER=(bench_core bench_accuracy bench_codec bench_mesh bench_meshqz bench_server bench_decode bench_link bench_cigi
       bench_wakes bench_wake_look bench_look)
declare -A DONE=()
ONLY=" ${BENCH_ONLY:-} "
selected() { [ -z "${BENCH_ONLY:-}" ] || [[ "$ONLY" == *" $1 "* ]]; }
# A benchmark BENCH_ONLY leaves out keeps the section of the run that last
# made it (out/NAME.md, its run stamped in out/NAME.stamp; a section older
# than the stamps is credited to the previous report's date and revision),
# labelled with that run, so a partial run does not erase the others.
PREV_RUN=$(sed -n 's/^| date | \(.*\) |$/\1/p' "$REPORT" 2>/dev/null | head -n1)
PREV_REV=$(sed -n 's/^| revision | \(.*\) |$/\1/p' "$REPORT" 2>/dev/null | head -n1)
skipped() {  # name title
    NAMES+=("$1"); TITLES+=("$2"); SECS+=("-")
    if [ -s "$OUT/$1.md" ]; then
        [ -s "$OUT/$1.stamp" ] || echo "${PREV_RUN:-an earlier run}, revision ${PREV_REV:-?} (from the previous report)" >"$OUT/$1.stamp"
        STATUS+=("skipped (BENCH_ONLY); section kept from the run of $(cat "$OUT/$1.stamp")")
    else
        STATUS+=("skipped (BENCH_ONLY)")
    fi
}
for name in "${ORDER[@]}"; do
    title=${KNOWN_TITLE[$name]}
    if ! selected "$name"; then
        skipped "$name" "$title"
    elif [ -x "$BUILD/bench/$name" ]; then
        run_one "$name" "$title" "$BUILD/bench/$name"
    elif [ -f "tests/bench/$name.sh" ]; then
        run_one "$name" "$title" bash "tests/bench/$name.sh" "$BUILD"
    elif [ -f "tests/bench/$name.py" ]; then
        run_one "$name" "$title" python3 "tests/bench/$name.py" "$BUILD"
    else
        missing "$name" "$title"
    fi
    DONE[$name]=1
done
for prog in "$BUILD"/bench/*; do
    [ -x "$prog" ] && [ -f "$prog" ] || continue
    name=$(basename "$prog")
    [ -n "${DONE[$name]:-}" ] && continue
    if selected "$name"; then run_one "$name" "$name" "$prog"; else skipped "$name" "$name"; fi
done

# ---- plots ---------------------------------------------------------------------
declare -A AXIS_TITLE=(
    [grid]="FFT resolution x cascade count"
    [cutoff]="cutoff policy and level"
    [gerstner]="Gerstner near-field wave count"
    [precision]="storage precision"
    [codec]="tile codec and quantisation step"
    [mesh]="mesh kind and density"
)
PLOTS=()
if ! selected bench_accuracy; then
    # the plots are bench_accuracy's: a run without it keeps them as they
    # are (re-drawn, they would carry this run's date on the other's data)
    for axis in grid cutoff gerstner precision codec mesh; do [ -f "$OUT/acc_$axis.png" ] && PLOTS+=("$axis"); done
elif command -v gnuplot >/dev/null 2>&1; then
    for axis in grid cutoff gerstner precision codec mesh; do
        dat="$OUT/acc_$axis.dat"
        [ -f "$dat" ] || continue
        png="$OUT/acc_$axis.png"
        xlab='time per client frame, tick included (ms, median)'
        [ "$axis" = codec ] && xlab='tile bytes per client frame (KiB)'
        if gnuplot -e "datafile='$dat'; outfile='$png'; axisname='${AXIS_TITLE[$axis]:-$axis}'; machine='$MACHINE'; stamp='$DATE, $REV'; cmd='$CMD'; xlab='$xlab'" \
            tests/bench/plot.gp 2>>"$OUT/gnuplot.log"; then
            PLOTS+=("$axis")
        else
            echo "bench: gnuplot failed for $axis (see $OUT/gnuplot.log)" >&2
        fi
    done
else
    echo "bench: gnuplot not found; no plots" >&2
fi

# ---- REPORT.md -------------------------------------------------------------------
{
    echo "# oceand benchmark report"
    echo
    echo "Generated by \`tests/bench/run.sh\` - do not edit; reproduce with \`$CMD\`."
    echo
    echo "| | |"
    echo "|---|---|"
    echo "| machine | $NPROC cores, $CPU, $MEM, $KERNEL |"
    echo "| compiler | $CCV, FFTW $FFTWV |"
    echo "| date | $DATE |"
    echo "| revision | $REV |"
    echo "| command | \`$CMD\` (from the repository root) |"
    echo "| load average at start | $LOAD |"
    echo "| mode | $([ -n "$QUICK" ] && echo 'quick (BENCH_QUICK=1): shortened sweeps, fewer repetitions' || echo 'full') |"
    echo
    echo "Every time is a median over repeated runs; every ratio is measured within one run. The"
    echo "machine, date and command above apply to every table and figure below; each plot repeats them."
    echo
    echo "| benchmark | status | seconds |"
    echo "|---|---|---:|"
    for i in "${!NAMES[@]}"; do
        echo "| [${TITLES[$i]}](#${NAMES[$i]}) (\`${NAMES[$i]}\`) | ${STATUS[$i]} | ${SECS[$i]} |"
    done
    echo
    if [ -s "$OUT/headline_viewer.md" ] || [ -s "$OUT/headline.md" ]; then
        echo "## Headline: what accuracy costs"
        echo
        if [ -s "$OUT/headline_viewer.md" ]; then
            cat "$OUT/headline_viewer.md"
            echo
        fi
        if [ -s "$OUT/headline.md" ]; then
            echo "Selected rows of the accuracy sweep (full tables below; all rows in \`out/accuracy.csv\`)."
            echo
            cat "$OUT/headline.md"
            echo
        fi
    fi
    if [ ${#PLOTS[@]} -gt 0 ]; then
        echo "## Error against time"
        echo
        echo "Each point is one setting; the red line joins the Pareto front (no other setting is both"
        echo "faster and more accurate); the black cross is the shipped default."
        echo
        for axis in "${PLOTS[@]}"; do
            echo "### ${AXIS_TITLE[$axis]:-$axis}"
            echo
            echo "![${AXIS_TITLE[$axis]:-$axis}](out/acc_$axis.png)"
            echo
        done
    fi
    for i in "${!NAMES[@]}"; do
        echo "<a id=\"${NAMES[$i]}\"></a>"
        echo
        echo "## ${TITLES[$i]}"
        echo
        kept=
        [ "${STATUS[$i]#skipped}" != "${STATUS[$i]}" ] && [ -s "$OUT/${NAMES[$i]}.md" ] && kept=1
        if [ -n "$kept" ]; then
            echo "\`${NAMES[$i]}\`: not run this time (BENCH_ONLY=\"${BENCH_ONLY:-}\"); **the section below is from the run of $(cat "$OUT/${NAMES[$i]}.stamp" 2>/dev/null)**, not from the date and machine above."
        else
            echo "\`${NAMES[$i]}\`: ${STATUS[$i]}$([ "${SECS[$i]}" != "-" ] && echo ", ${SECS[$i]} s"). Machine: $MACHINE. Date: $DATE. Reproduce: \`$CMD\`."
        fi
        echo
        if [ -s "$OUT/${NAMES[$i]}.md" ]; then
            cat "$OUT/${NAMES[$i]}.md"
            echo
        elif [ "${STATUS[$i]}" = "not built" ]; then
            echo "_Not built in this tree; nothing to report._"
            echo
        elif [ "${STATUS[$i]#skipped}" != "${STATUS[$i]}" ]; then
            echo "_Not run this time (BENCH_ONLY=\"${BENCH_ONLY:-}\")._"
            echo
        else
            echo "_No output. Last lines of its log (\`out/${NAMES[$i]}.log\`):_"
            echo
            echo '```'
            tail -n 20 "$OUT/${NAMES[$i]}.log" 2>/dev/null
            echo '```'
            echo
        fi
        if [ "${STATUS[$i]}" != "ok" ] && [ "${STATUS[$i]}" != "not built" ] && [ "${STATUS[$i]#skipped}" = "${STATUS[$i]}" ] && [ -s "$OUT/${NAMES[$i]}.md" ]; then
            echo "_The run ended with ${STATUS[$i]}; last lines of its log:_"
            echo
            echo '```'
            tail -n 20 "$OUT/${NAMES[$i]}.log" 2>/dev/null
            echo '```'
            echo
        fi
        # findings measured by hand beside a benchmark (dated, each with its
        # revision and commands) live in tests/bench/notes/NAME.md, so a run
        # that rewrites this file keeps them
        if [ -s "tests/bench/notes/${NAMES[$i]}.md" ]; then
            cat "tests/bench/notes/${NAMES[$i]}.md"
            echo
        fi
    done
    echo "## Files"
    echo
    echo "CSV and plots beside this report in \`tests/bench/out/\`:"
    echo
    for f in "$OUT"/*.csv "$OUT"/*.png; do
        [ -f "$f" ] && echo "- [\`out/$(basename "$f")\`](out/$(basename "$f"))"
    done
    echo
} >"$REPORT"

echo "bench: wrote $REPORT" >&2

# ---- the headline section (pasted by hand into docs/design.md, "Benchmarks") ----
QNOTE=
[ -n "$QUICK" ] && QNOTE='; a quick run - rerun `make bench` for the full figures'
# README's section is the headline of bench_accuracy: rewritten only by a
# run that made it, so its machine and date are that run's.
if ! selected bench_accuracy; then
    echo "bench: bench_accuracy not run; tests/bench/README-section.md kept" >&2
    exit $ANY_FAILED
fi
{
    echo "## What accuracy costs"
    echo
    echo "\`make bench\` measures every accuracy setting the server offers - FFT resolution, cascades,"
    echo "Gerstner near field, cutoff, storage precision, tile codec, mesh - against the same sea at"
    echo "N = 2048 summed directly in double, and writes [tests/bench/REPORT.md](tests/bench/REPORT.md)"
    echo "with every table, CSV and plot. Headline ($MACHINE; $DATE; \`$CMD\`; medians, ratios from one run$QNOTE):"
    echo
    if [ -s "$OUT/headline_viewer.md" ]; then
        cat "$OUT/headline_viewer.md"
        echo
    fi
    if [ -s "$OUT/headline.md" ]; then
        cat "$OUT/headline.md"
    else
        echo "_bench_accuracy did not run; see the report._"
    fi
    echo
    if [ -f "$OUT/acc_grid.png" ]; then
        echo "![Error against time: FFT resolution x cascades, Pareto front and shipped default](tests/bench/out/acc_grid.png)"
        echo
    fi
    if [ -s "$OUT/default_verdict.md" ]; then
        cat "$OUT/default_verdict.md"
        echo
    fi
    echo "The full report covers the cutoff policies, the near field, f16 storage, every tile codec, the"
    echo "three mesh kinds, the time each effects set and each scene in \`config/scenes/\` costs, the FFT"
    echo "core beside FFTW alone, and the daemon under load: [tests/bench/REPORT.md](tests/bench/REPORT.md)."
} >tests/bench/README-section.md
echo "bench: wrote tests/bench/README-section.md" >&2
exit $ANY_FAILED
