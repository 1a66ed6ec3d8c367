#!/usr/bin/env bash
# bench_look.sh BUILD - what the browser viewer draws, judged against a
# reference render of the exact sea (issue 45): for the storm, ship-bridge
# and flight scenes as `make run` serves them (config/oceand.conf + the
# scene), from 3, 25, 300, 1500 m and 10 km (yaw 30 deg, pitch steeper as
# the camera rises, 60 deg field of view, 1280x720, the sea of t = 123.25 s)
#   - the viewer's screenshot: headless Chromium on oceand's own viewer,
#     opened with ?t=T&x=..&overlay=0 (replay mode), at full resolution with
#     multisampling as a user's page draws (look_chromium.mjs);
#   - `ocean-sim render` of the same view (2 x 2 samples a pixel);
# and their SSIM (Wang et al. 2004) and mean |difference| per view, beside
# the figures of the viewer before issue 45's work (look_before.csv) and
# beside the same viewer on a stream without its budgets (every sample one
# pixel, server.px_per_sample = 1, and no byte limit): what the stream's
# byte budget costs in look, against what the viewer's drawing does.  Goal
# (issue 45): SSIM >= 0.9 at every view.  Side-by-side pictures (viewer
# left, reference right) in tests/bench/out/look/.  Prints the markdown
# section; CSV in tests/bench/out/look.csv.
set -u
BUILD=${1:-build}
. "$(dirname "$0")/helpers/bench_lib.sh" bench_look
mkdir -p "$OUT/look"
[[ -x ${CHROMIUM:-/usr/bin/chromium} && -d tests/browser/node_modules/ssim.js ]] ||
    die "needs Debian's chromium and tests/browser's npm packages (make bench installs them)"

T=123.25
W=1280
H=720
# BENCH_QUICK: the same views at a quarter of the pixels
[[ -n ${BENCH_QUICK:-} ]] && W=640 && H=360
# height pitch
VIEWS="3 -4
25 -8
300 -20
1500 -35
10000 -89"
BEFORE=tests/bench/look_before.csv
echo "scene,height_m,pitch_deg,ssim,mean_abs_diff,render_s,ssim_unbudgeted" >"$OUT/look.csv"

for scene in storm ship-bridge flight; do
    views="["
    sep=
    while read -r y pitch; do
        name="$scene-$y"
        t0=$(date +%s%N)
        "$BUILD/ocean-sim" render --config config/oceand.conf --scene "$scene" --pos "0,$y,0" --yaw 30 --pitch "$pitch" \
            --fov 60 --size "${W}x$H" --supersample 2 --time "$T" --out "$tmp/$name-ref.png" >/dev/null ||
            die "render of $name failed"
        echo "$name $(( ($(date +%s%N) - t0) / 1000000 ))" >>"$tmp/render_s"
        views+="$sep{\"name\":\"$name\",\"x\":0,\"y\":$y,\"z\":0,\"yaw\":30,\"pitch\":$pitch,\"fov\":60,\"t\":$T,"
        views+="\"width\":$W,\"height\":$H,\"ref\":\"$tmp/$name-ref.png\",\"shot\":\"$tmp/$name-viewer.png\","
        views+="\"pair\":\"$OUT/look/$name.jpg\"}"
        sep=,
    done <<<"$VIEWS"
    echo "$views]" >"$tmp/$scene.json"
    # the same views on a stream without budgets: names "-full", no pictures
    sed 's/"name":"\([^"]*\)"/"name":"\1-full"/g; s/-viewer\.png/-full.png/g; s/,"pair":"[^"]*"//g' \
        "$tmp/$scene.json" >"$tmp/$scene-full.json"
    for run in "" -full; do
        if [[ -z $run ]]; then bench_daemon --scene "$scene"
        else bench_daemon --scene "$scene" --set server.px_per_sample=1 --set server.viewer_bytes_per_s=1e10; fi
        node tests/bench/look_chromium.mjs "$base" "$tmp/$scene$run.json" >>"$tmp/look.jsonl" ||
            die "the viewer's screenshots of $scene$run failed"
        bench_daemon_stop
    done
done

echo "### What the viewer draws against the exact sea"
echo
echo "oceand on \`config/oceand.conf\` with each scene, the viewer at ${W}x$H, 60 deg, yaw 30 deg, the sea of t = $T s;"
echo "the reference is \`ocean-sim render\` of the same view (2 x 2 samples a pixel). SSIM: Wang et al. 2004 (ssim.js, 'original'); goal >= 0.9."
echo
echo "| scene | height | pitch | SSIM before | SSIM | mean abs diff (0-255) | SSIM, stream without budgets | reference render | pictures (viewer, reference) |"
echo "|---|---|---|---|---|---|---|---|---|"
for scene in storm ship-bridge flight; do
    while read -r y pitch; do
        name="$scene-$y"
        line=$(grep "\"name\":\"$name\"" "$tmp/look.jsonl")
        s=$(sed -n 's/.*"ssim":\([0-9.eE+-]*\).*/\1/p' <<<"$line")
        d=$(sed -n 's/.*"mean_abs_diff":\([0-9.eE+-]*\).*/\1/p' <<<"$line")
        full=$(grep "\"name\":\"$name-full\"" "$tmp/look.jsonl" | sed -n 's/.*"ssim":\([0-9.eE+-]*\).*/\1/p')
        rs=$(awk -v n="$name" '$1 == n {printf "%.0f", $2 / 1000}' "$tmp/render_s")
        before=$([[ -f $BEFORE ]] && awk -F, -v sc="$scene" -v h="$y" '$1 == sc && $2 == h {printf "%.3f", $4}' "$BEFORE")
        printf '| %s | %s m | %s deg | %s | %.3f | %.1f | %.3f | %s s | [%s](out/look/%s.jpg) |\n' "$scene" "$y" \
            "$pitch" "${before:--}" "$s" "$d" "$full" "$rs" "$name" "$name"
        echo "$scene,$y,$pitch,$s,$d,$rs,$full" >>"$OUT/look.csv"
    done <<<"$VIEWS"
done
