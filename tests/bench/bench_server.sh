#!/usr/bin/env bash
# bench_server.sh - the daemon's load benchmark (issue 6).
#
# Starts BUILD/oceand on config/oceand.conf (a free loopback port), then for
# N = 1, 16, 64, 256 co-located viewers runs `ocean-client load` at 30 Hz for SECONDS
# (default 20) and reports frames per viewer, tick-to-receipt latency p50/p99,
# frames skipped, the daemon's CPU (utime+stime over the run, in cores),
# bytes per viewer per second and the load generator's own CPU over its
# measured window (cores; a generator near a full core measures itself).
# Those rows have every viewer at one camera (the daemon encodes a FRAME once
# and shares it); two more rows, 64 and 256 viewers with --spread 20 (a grid
# of cameras 20 m apart), show the cost when no two viewers share a camera.
# Markdown table on stdout, CSV in tests/bench/out/server.csv.  Target: 256 viewers at 30 Hz with p99 <= 50 ms
# on 2 cores, and the default subscription under 4 MB/s per viewer.
#
#   usage: tests/bench/bench_server.sh [BUILD] [SECONDS] [extra load options...]
set -euo pipefail
build=${1:-build}
secs=${2:-20}
shift $(( $# > 2 ? 2 : $# )) || true
extra=("$@")
out=tests/bench/out
mkdir -p "$out"
csv="$out/server.csv"
log=$(mktemp)
"$build/oceand" --config config/oceand.conf --port 0 >"$log" 2>&1 &
pid=$!
trap 'kill -TERM $pid 2>/dev/null; wait $pid 2>/dev/null; rm -f "$log"' EXIT
port=""
for _ in $(seq 100); do
    port=$(grep -o '127.0.0.1:[0-9]*' "$log" | head -1 | cut -d: -f2 || true)
    [[ -n "$port" ]] && break
    sleep 0.1
done
[[ -n "$port" ]] || { echo "oceand did not start:"; cat "$log"; exit 1; }
tck=$(getconf CLK_TCK)
cpu() { awk '{print $14 + $15}' "/proc/$pid/stat"; }
echo "viewers,seconds,frames_per_viewer,frames_expected,latency_p50_ms,latency_p99_ms,frames_skipped_per_viewer,daemon_cpu_cores,bytes_per_viewer_per_s,disconnects,errors,generator_cpu_cores,decode_errors,camera_spread_m" >"$csv"
echo "| viewers | cameras | frames/viewer (expected) | p50 ms | p99 ms | skipped/viewer | daemon CPU (cores) | MB/s per viewer | generator CPU (cores) |"
echo "|---:|:---|---:|---:|---:|---:|---:|---:|---:|"
# viewers:spread_m (0: every viewer at the same camera)
for run in 1:0 16:0 64:0 256:0 64:20 256:20; do
    n=${run%%:*}; spread=${run##*:}
    cams=$(awk -v s="$spread" 'BEGIN {print (s > 0) ? s " m apart" : "shared"}')
    ramp=$(awk -v n="$n" 'BEGIN {print (n > 64) ? 3 : 1}')
    c0=$(cpu); t0=$(date +%s.%N)
    json=$("$build/ocean-client" load "ws://127.0.0.1:$port/" --clients "$n" --seconds "$secs" \
           --rate 30 --ramp "$ramp" --spread "$spread" --json "${extra[@]}" 2>/dev/null || true)
    c1=$(cpu); t1=$(date +%s.%N)
    cores=$(awk -v a="$c0" -v b="$c1" -v s="$t0" -v e="$t1" -v t="$tck" 'BEGIN {printf "%.2f", (b - a) / t / (e - s)}')
    row=$(python3 - "$json" <<'PY'
import json, sys
try:
    j = json.loads(sys.argv[1])
except Exception:
    print("nan,nan,nan,nan,nan,nan,nan,nan,nan,nan"); sys.exit()
g = lambda k: j.get(k, float("nan"))
cc = g("client_cpu_cores")
if cc != cc and g("seconds") > 0:
    cc = g("client_cpu_s") / g("seconds")
print("%.1f,%.1f,%.2f,%.2f,%.1f,%.0f,%d,%d,%.2f,%d" % (g("frames_per_viewer"), g("frames_expected_per_viewer"),
      g("latency_p50_ms"), g("latency_p99_ms"), g("frames_skipped_per_viewer"),
      g("bytes_per_viewer_per_s"), g("disconnects"), g("errors"), cc, g("decode_errors")))
PY
)
    IFS=, read -r fpv fexp p50 p99 skip bps disc err gcpu derr <<<"$row"
    echo "$n,$secs,$fpv,$fexp,$p50,$p99,$skip,$cores,$bps,$disc,$err,$gcpu,$derr,$spread" >>"$csv"
    mbs=$(awk -v b="$bps" 'BEGIN {printf "%.2f", b / 1e6}')
    echo "| $n | $cams | $fpv ($fexp) | $p50 | $p99 | $skip | $cores | $mbs | $gcpu |"
done
echo
echo "oceand on $(nproc) cores, config/oceand.conf (scene $(grep -o 'scene [a-z-]*' "$log" | head -1 | cut -d' ' -f2)), ocean-client load defaults ${extra[*]}; CSV: $csv"
