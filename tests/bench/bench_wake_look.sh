#!/usr/bin/env bash
# bench_wake_look.sh BUILD - the browser viewer draws the ships' wakes
# (issue 43): a 120 m ship (5 m draught) steaming at 8 m/s along +x, fed
# over ENTITY a sample a second as a simulator would (ocean-client entity),
# on `make run`'s sea (ship-bridge, Beaufort 6) and on a calm one (the base
# sea at 3 m/s of wind), each from a chase camera 25 m up behind the ship
# and a helicopter 300 m up beside its wake, at the instant 40 s after the
# ship entered (?t=, replay mode: the same picture however long the page
# took).  Screenshots in tests/bench/out/wake/; prints the markdown section.
set -u
BUILD=${1:-build}
. "$(dirname "$0")/helpers/bench_lib.sh" bench_wake_look
mkdir -p "$OUT/wake"
[[ -x ${CHROMIUM:-/usr/bin/chromium} && -d tests/browser/node_modules/playwright-core ]] ||
    die "needs Debian's chromium and tests/browser's npm packages (make bench installs them)"
SIZE=1280x720
[[ -n ${BENCH_QUICK:-} ]] && SIZE=640x360
SPEED=8

echo "A 120 m ship drawing 5 m steams at $SPEED m/s along +x, entered over ENTITY a sample a second (\`ocean-client entity\`); the browser viewer at the instant 40 s after it entered (\`?t=\`), ${SIZE/x/ x } (\`$0\`). The ship's hull is not drawn; its wake is the WAKE patterns the viewer places along the track (PROTOCOL.md \"WAKE\")."
echo
echo "| sea | chase camera, 25 m up, 200 m astern | helicopter, 300 m up, beside the wake |"
echo "|---|---|---|"
for sea in ship-bridge calm; do
    if [[ $sea == calm ]]; then bench_daemon --set 'server.scene=""' --set sea.wind=3 --set server.entity_token=bench
    else bench_daemon --scene ship-bridge --set server.entity_token=bench; fi
    ws=${base/http/ws}
    s0=$(curl -s "${base}status" | sed -n 's/.*"sim_time":[[:space:]]*\([0-9.]*\).*/\1/p')
    [[ -n $s0 ]] || die "no sim_time in ${base}status"
    # the feeder: a sample a second at the daemon's clock (the tool's)
    (
        t0=$(date +%s.%N)
        for _ in $(seq 150); do
            x=$(echo "($(date +%s.%N) - $t0) * $SPEED" | bc -l)
            "$BUILD/ocean-client" entity "$ws" --set --token bench --id 5 --kind ship --x "$x" --z 0 --heading 0 \
                --speed $SPEED --length 120 --beam 15 --draught 5 >/dev/null 2>&1
            sleep 1
        done
    ) &
    feeder=$!
    T=$(echo "$s0 + 40" | bc -l)
    xs=$(echo "40 * $SPEED" | bc -l)
    sleep 5
    cells=
    for view in chase heli; do
        if [[ $view == chase ]]; then q="x=$(echo "$xs - 200" | bc -l)&y=25&z=-30&yaw=8&pitch=-7"
        else q="x=$(echo "$xs - 250" | bc -l)&y=300&z=-330&yaw=60&pitch=-38"; fi
        png="$OUT/wake/$sea-$view.png"
        if r=$(timeout 300 node tests/bench/wake_shot.mjs "$base?$q&t=$T&overlay=0&fov=60" "$png" "$SIZE" 2>"$tmp/shot.err"); then
            peak=$(echo "$r" | sed -n 's/.*"peak":\([0-9.]*\).*/\1/p')
            cells+=" ![$sea $view](out/wake/$sea-$view.png) largest wake on the viewer's square ${peak:0:5} m |"
        else
            cells+=" not drawn: $(tail -1 "$tmp/shot.err" | cut -c1-120) |"
        fi
    done
    echo "| $sea |$cells"
    kill "$feeder" 2>/dev/null
    wait "$feeder" 2>/dev/null
    bench_daemon_stop
done
