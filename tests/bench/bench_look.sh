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

# Relief: from 5 m over the storm sea, level, 10 deg (27 rows a degree),
# downwind: do crests rise over the horizon as the exact sea's do?  The
# viewer as served (the layout-1 mesh at 8 px, server.flat_mesh_error_px), as
# served with that mesh at 16 px (layout 0's budget), on a stream without
# budgets, and on that stream with a mesh of 2 px error
# (server.flat_mesh_error_px 8 -> 2): which limit holds the crests down.
EW=960
EH=270
"$BUILD/ocean-sim" render --config config/oceand.conf --scene storm --pos 0,5,0 --yaw 0 --pitch 0 --fov 10 \
    --size "${EW}x$EH" --supersample 1 --time "$T" --out "$tmp/horizon-ref.png" >/dev/null || die "render of the horizon view failed"
for run in served mesh16 full fullmesh; do
    echo "[{\"name\":\"horizon-$run\",\"x\":0,\"y\":5,\"z\":0,\"yaw\":0,\"pitch\":0,\"fov\":10,\"t\":$T,\"width\":$EW,\"height\":$EH,\"ref\":\"$tmp/horizon-ref.png\",\"shot\":\"$tmp/horizon-$run.png\",\"edge\":true}]" \
        >"$tmp/horizon-$run.json"
    case $run in
    served) bench_daemon --scene storm ;;
    mesh16) bench_daemon --scene storm --set server.flat_mesh_error_px=16 ;;
    full) bench_daemon --scene storm --set server.px_per_sample=1 --set server.viewer_bytes_per_s=1e10 ;;
    fullmesh) bench_daemon --scene storm --set server.px_per_sample=1 --set server.viewer_bytes_per_s=1e10 \
        --set server.flat_mesh_error_px=2 ;;
    esac
    node tests/bench/look_chromium.mjs "$base" "$tmp/horizon-$run.json" >>"$tmp/look.jsonl" ||
        die "the viewer's horizon screenshot ($run) failed"
    bench_daemon_stop
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

echo
echo "### Relief: crests over the horizon (storm, 5 m, level, 10 deg, downwind)"
echo
echo "The sea's top edge in each column (row 0 at the top, ${EH} rows, 27 a degree; a flat sea's horizon is row"
echo "$((EH / 2 + 2)), 0.07 deg below the centre). Crests between the eye and the horizon lift the edge above it."
echo
echo "| picture | highest edge row | edge range, rows | mean edge row | columns within a row of the reference's edge | SSIM |"
echo "|---|---:|---:|---:|---:|---:|"
for run in served mesh16 full fullmesh; do
    line=$(grep "\"name\":\"horizon-$run\"" "$tmp/look.jsonl")
    node -e '
        const l = JSON.parse(process.argv[1]), run = process.argv[2];
        const what = { served: "viewer as served (config/oceand.conf)",
            mesh16: "viewer as served, layout-1 mesh at 16 px (server.flat_mesh_error_px = 16)",
            full: "viewer, stream without budgets",
            fullmesh: "viewer, stream without budgets, mesh at 2 px (server.flat_mesh_error_px = 2)" }[run];
        const row = (n, e, w, s) => console.log(`| ${n} | ${e.top} | ${e.range} | ${e.mean.toFixed(1)} | ${w} | ${s} |`);
        if (run === "served") row("reference (`ocean-sim render`, the exact sea)", l.edge_ref, "-", "-");
        row(what, l.edge_viewer, (100 * l.edge_within_1).toFixed(0) + " %", l.ssim.toFixed(3));
    ' "$line" "$run"
done
