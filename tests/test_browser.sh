#!/usr/bin/env bash
# test_browser.sh - the web viewer (clients/web/) end to end.
#
#  1. Protocol cross-check: builds tests/browser/gen_vectors.c against the
#     current $BUILD/libocean_proto.a and runs tests/browser/protocol.test.mjs
#     (node --test): the viewer's JavaScript decoder/encoders and tile codecs
#     against the C ones, byte for byte, including hostile input, plus the
#     protocol's own vectors in tests/vectors/; the viewer's GLSL of "Where
#     each mip is read" run in headless Chromium against the C rule's points
#     (lod.test.mjs, tests/vectors/lod.txt and lod_mss.txt); and the
#     viewer's small modules (timeline.test.mjs, rate.test.mjs,
#     meshstore.test.mjs) and its whitecaps near the eye (foam.test.mjs:
#     coverage kept, continuous, streaked along the wind).
#  2. Real browser: starts $BUILD/oceand on a free loopback port with
#     config/oceand.conf and runs tests/browser/viewer.test.mjs: headless
#     Chromium (/usr/bin/chromium, software GL) driven by playwright-core
#     loads the page from the daemon, checks frames, pixels, overlay and two
#     viewers at once.  Screenshots: $BUILD/test-artifacts/viewer*.png.
#  3. The layout-1 viewer in ship-bridge, storm and flight (one daemon per
#     scene, --scene) at 25, 300 and 1500 m (tests/browser/scenes.test.mjs):
#     screenshots $BUILD/test-artifacts/scene-*.png, sun glitter spread by
#     roughness at 1500 m against a mirror control, no mesh edge; in the
#     storm, crests breaking the horizon from 5 m against `ocean-sim render`
#     of the exact sea (made in the background from the start).
#     SHOTS_OUT=DIR also copies the screenshots to DIR (tests/bench/out).
# The pages of 2 and 3 draw a quarter of the viewer's own resolution without
# multisampling (VIEW_QUERY, default scale=0.25&aa=0): nothing judged depends
# on it, and Chromium's software renderer draws 4 times the frames (11 fps
# against 3 on a quiet 2-core host); VIEW_QUERY= draws as a user's viewer.
# The daemon is stopped on exit, whatever happens (trap).
#   usage: BUILD=build bash tests/test_browser.sh
set -uo pipefail
cd "$(dirname "$0")/.."
# Chromium raises its browser and GPU processes to nice -8 when it may (as
# root); beside the rest of the suite that starves the tests that follow
# real-time streams.  Without CAP_SYS_NICE it runs at our priority.
if [[ -z ${OCEAN_BROWSER_NICE_DROPPED:-} ]] && command -v setpriv >/dev/null; then
    export OCEAN_BROWSER_NICE_DROPPED=1
    exec setpriv --bounding-set=-sys_nice bash "$0" "$@"
fi
BUILD=${BUILD:-build}
ART="$BUILD/test-artifacts"
WORK="$BUILD/browser-test"
mkdir -p "$ART" "$WORK"
daemon_pid=""
relief_pid=""
cleanup() {
    if [[ -n "$daemon_pid" ]] && kill -0 "$daemon_pid" 2>/dev/null; then
        kill -TERM "$daemon_pid" 2>/dev/null
        for _ in $(seq 50); do kill -0 "$daemon_pid" 2>/dev/null || break; sleep 0.1; done
        kill -KILL "$daemon_pid" 2>/dev/null
        wait "$daemon_pid" 2>/dev/null
    fi
}
# on exit the background render too (cleanup alone runs between sections,
# while the render may still be working for the storm's section)
on_exit() {
    [[ -n "$relief_pid" ]] && kill "$relief_pid" 2>/dev/null
    cleanup
}
trap on_exit EXIT INT TERM

die() { echo "test_browser: $*" >&2; exit 1; }

# start_daemon LOG [OCEAND ARGS...]: starts $BUILD/oceand on a free loopback
# port with config/oceand.conf (daemon_pid), waits up to 10 s for the URL it
# announces (url); status 1 if it did not announce one.  LOG is emptied
# here, not by the child's redirection: the grep must not read a previous
# run's log.
start_daemon() {
    local log=$1
    shift
    : >"$log"
    # admission (server.admit_share) prices layout 0 from this host's speed:
    # off, so a busy host does not refuse the viewer's layout-0 check
    "$BUILD/oceand" --config config/oceand.conf --bind 127.0.0.1 --port 0 --set server.admit_share=0 "$@" \
        >"$log" 2>&1 &
    daemon_pid=$!
    url=""
    for _ in $(seq 100); do
        url=$(grep -o 'listening on http://[^ ]*' "$log" 2>/dev/null | head -1 | sed 's/^listening on //')
        [[ -n "$url" ]] && return 0
        kill -0 "$daemon_pid" 2>/dev/null || return 1
        sleep 0.1
    done
    return 1
}

command -v node >/dev/null || die "node not found (apt-get install nodejs; .ci/deps.sh does it)"
[[ -x "${CHROMIUM:-/usr/bin/chromium}" ]] || die "${CHROMIUM:-/usr/bin/chromium} not found (apt-get install chromium)"
if [[ ! -d tests/browser/node_modules/playwright-core ]]; then
    echo "test_browser: installing the test's npm dev dependencies (npm ci in tests/browser)"
    (cd tests/browser && npm ci --no-audit --no-fund --loglevel=error) || die "npm ci failed"
fi
[[ -x "$BUILD/oceand" && -x "$BUILD/ocean-client" ]] || die "$BUILD/oceand or ocean-client not built"
[[ -f "$BUILD/libocean_proto.a" && -f "$BUILD/libocean_sim.a" ]] || die "$BUILD/libocean_proto.a / libocean_sim.a not built"
[[ -x "$BUILD/ocean-sim" ]] || die "$BUILD/ocean-sim not built"

# the exact sea of the storm's relief view (scenes.test.mjs RELIEF_REF), one
# core for a quarter of a minute, made while the tests before it run
RELIEF_T=123.25
"$BUILD/ocean-sim" render --config config/oceand.conf --scene storm --pos 0,5,0 --yaw 0 --pitch 0 --fov 10 \
    --size 960x270 --supersample 1 --time "$RELIEF_T" --out "$WORK/relief-ref.png" >"$WORK/relief-ref.log" 2>&1 &
relief_pid=$!

status=0
export VIEW_QUERY="${VIEW_QUERY-scale=0.25&aa=0}"

# ---- 1. protocol cross-check --------------------------------------------
echo "== protocol: JavaScript decoder vs C (protocol/) == (${SECONDS} s)"
${CC:-cc} -std=c11 -O1 -Wall -Wextra -Werror -Isim -Iprotocol tests/browser/gen_vectors.c \
    "$BUILD/libocean_proto.a" "$BUILD/libocean_sim.a" -lzstd -lOpenEXRCore-3_1 -lm \
    -o "$WORK/gen_vectors" || die "cannot build gen_vectors"
rm -rf "$WORK/vectors" && mkdir -p "$WORK/vectors"
"$WORK/gen_vectors" gen "$WORK/vectors" || die "gen_vectors gen failed"
if ! VECTOR_DIR="$WORK/vectors" GEN_VECTORS="$WORK/gen_vectors" PROTO_VECTORS=tests/vectors \
        node --test --test-reporter=tap tests/browser/protocol.test.mjs tests/browser/lod.test.mjs \
            tests/browser/timeline.test.mjs tests/browser/rate.test.mjs tests/browser/meshstore.test.mjs \
            tests/browser/foam.test.mjs; then
    echo "test_browser: protocol cross-check FAILED"
    status=1
fi

# ---- 2. the page in a real browser, served by the daemon -----------------
echo "== viewer: headless Chromium against oceand == (${SECONDS} s)"
log="$WORK/oceand.log"
ADMIN_TOKEN=browser-test-admin
ENTITY_TOKEN=browser-test-entity
# server.max_pending_queries 4: the viewer's stalled-daemon check needs a
# stall longer than the pending limit at two questions a second (3 s here)
start_daemon "$log" --set server.admin_token=$ADMIN_TOKEN --set server.entity_token=$ENTITY_TOKEN \
    --set server.max_pending_queries=4 ||
    { echo "test_browser: oceand did not start:"; cat "$log"; exit 1; }
echo "oceand at $url (pid $daemon_pid)"
# a ship far out of every view, the shape and speed of the one the viewer
# test enters: its wake pattern is built (at nice 10, which a busy host
# starves) while the test's first checks run, so that ship's wake is sent
# as soon as it is in view
"$BUILD/ocean-client" entity "${url/http/ws}" --set --token $ENTITY_TOKEN --id 76 --kind ship --x 20000 --z 20000 \
    --heading 90 --speed 8 --length 120 --beam 15 --draught 5 >/dev/null ||
    echo "test_browser: the ship built ahead was refused (the viewer's wake check waits for its build)"
if ! OCEAN_URL="$url" ARTIFACT_DIR="$ART" VIEWER_TIMEOUT_S="${VIEWER_TIMEOUT_S:-90}" ADMIN_TOKEN=$ADMIN_TOKEN \
        ENTITY_TOKEN=$ENTITY_TOKEN OCEAN_CLIENT="$BUILD/ocean-client" OCEAND_PID=$daemon_pid \
        timeout 300 node tests/browser/viewer.test.mjs; then
    echo "test_browser: viewer test FAILED (daemon log follows)"
    tail -30 "$log"
    status=1
fi
kill -0 "$daemon_pid" 2>/dev/null || { echo "test_browser: oceand died during the test"; tail -30 "$log"; status=1; }
cleanup
daemon_pid=""

# ---- 3. layout 1 at 25 m, 300 m and 1500 m in three scenes -------------
# One daemon per scene (--scene); screenshots $ART/scene-SCENE-Hm.png (and
# at 1500 m the far-sea and mirror controls), figures in $ART/scenes.jsonl.
# SHOTS_OUT=tests/bench/out copies the PNGs there for the benchmark report.
rm -f "$ART/scenes.jsonl"
for scene in ship-bridge storm flight; do
    echo "== viewer: layout 1 screenshots, scene $scene == (${SECONDS} s)"
    log="$WORK/oceand-$scene.log"
    if ! start_daemon "$log" --scene "$scene"; then
        echo "test_browser: oceand --scene $scene did not start:"; cat "$log"
        status=1
        continue
    fi
    relief_ref=""
    if [[ $scene == storm ]]; then
        if wait "$relief_pid"; then relief_ref="$WORK/relief-ref.png"
        else echo "test_browser: ocean-sim render of the relief view failed:"; cat "$WORK/relief-ref.log"; status=1; fi
        relief_pid=""
    fi
    if ! OCEAN_URL="$url" SCENE="$scene" ARTIFACT_DIR="$ART" SHOTS_OUT="${SHOTS_OUT:-}" RELIEF_REF="$relief_ref" \
            RELIEF_T="$RELIEF_T" VIEWER_TIMEOUT_S="${VIEWER_TIMEOUT_S:-90}" timeout 300 node tests/browser/scenes.test.mjs; then
        echo "test_browser: scene $scene FAILED (daemon log follows)"
        tail -20 "$log"
        status=1
    fi
    kill -0 "$daemon_pid" 2>/dev/null || { echo "test_browser: oceand died during scene $scene"; tail -30 "$log"; status=1; }
    cleanup
    daemon_pid=""
done
echo "test_browser: done in ${SECONDS} s"
exit $status
