#!/usr/bin/env bash
# bench_decode.sh BUILD - what the browser viewer's decoding costs, on the
# stream `make run` serves: oceand on config/oceand.conf (ship-bridge), a
# camera flying 25 m up at 60 m/s for 10 s (1280x720, 60 deg, 30 Hz),
# recorded with the viewer's subscription (ocean-client record: layout 1,
# every effect and cascade, qz at 5e-3, samples in time) and again with
# every tick's tiles (--time-interp off, the stream before); then every
# FRAME of each recording decoded on one core, as the viewer's decode
# workers do (message, then each tile into its texel block; with samples in
# time the frame applied to the held store and its instant blended), by
#   - the C decoders and store, native (helpers/decode_native.c: the floor);
#   - the viewer's build in Node.js (decode_viewer.mjs) and in headless
#     Chromium, in a module Worker (decode_chromium.mjs), both on
#     clients/web/codec.js and ocean.wasm (the JavaScript decoders they
#     replaced cannot read today's layout-1 frames: earlier REPORT.md);
# each run three times, interleaved; a frame's time is its median over the
# runs.  The planes each frame's instant reads are hashed by each decoder:
# the WebAssembly build must equal the native one bit for bit on every frame.
# Prints the markdown section; CSV in tests/bench/out/decode.csv.
set -u
BUILD=${1:-build}
. "$(dirname "$0")/helpers/bench_lib.sh" bench_decode

cc -std=c11 -O2 -Wall -Wextra -Werror -D_GNU_SOURCE -Isim -Iprotocol -Iclients/c tests/bench/helpers/decode_native.c \
    "$BUILD/libocean_client.a" "$BUILD/libocean_proto.a" "$BUILD/libocean_sim.a" -lzstd -lOpenEXRCore-3_1 \
    -lfftw3f_omp -lfftw3f -lcjson -lwebsockets -lm -fopenmp -o "$tmp/decode_native" || die "cannot build decode_native"

bench_daemon
url="ws://${base#http://}"
{
    echo '# oceand camera path v1'
    echo 't,x,y,z,vx,vy,vz,yaw_deg,pitch_deg,roll_deg,fov_y_deg,viewport_w,viewport_h'
    awk 'BEGIN { for (i = 0; i <= 300; i++) { t = i / 30; printf "%.17g,%.17g,25,0,60,0,0,0,-8,0,60,1280,720\n", t, 60 * t } }'
} >"$tmp/flight.csv"
# the viewer's stream (samples in time) and, as before, every tick's tiles
"$BUILD/ocean-client" record "$url" --path "$tmp/flight.csv" --out "$tmp/timed.frames" >"$tmp/record.log" 2>&1 ||
    die "record failed: $(tail -3 "$tmp/record.log")"
"$BUILD/ocean-client" record "$url" --path "$tmp/flight.csv" --out "$tmp/plain.frames" --time-interp off \
    >"$tmp/record.log" 2>&1 || die "record failed: $(tail -3 "$tmp/record.log")"
bench_daemon_stop

chromium=
[[ -x ${CHROMIUM:-/usr/bin/chromium} && -d tests/browser/node_modules/playwright-core ]] && chromium=1
for run in 1 2 3; do
    for s in plain timed; do
        "$tmp/decode_native" "$tmp/$s.frames" >"$tmp/$s.native.$run" || die "native decode failed ($s)"
        node tests/bench/decode_viewer.mjs "$tmp/$s.frames" >"$tmp/$s.wasm.$run" || die "WebAssembly decode failed ($s)"
        if [[ -n $chromium ]]; then
            node tests/bench/decode_chromium.mjs "$tmp/$s.frames" >"$tmp/$s.chromium.$run" ||
                die "Chromium decode failed ($s)"
        fi
    done
done

# per frame: the median of the three runs; then the median and p90 over frames
stats() {  # run-file prefix -> "median p90 frames"
    paste "$tmp/$1.1" "$tmp/$1.2" "$tmp/$1.3" | awk '{a = $5; b = $11; c = $17;
        hi = a > b ? a : b; hi = hi > c ? hi : c; lo = a < b ? a : b; lo = lo < c ? lo : c; print a + b + c - hi - lo}' |
        sort -g | awk '{v[NR] = $1} END {printf "%.2f %.2f %d", v[int((NR + 1) / 2)], v[int(0.9 * NR + 0.5)], NR}'
}
same() { paste "$tmp/$1.native.1" "$tmp/$1.$2.1" | awk '$6 == $12 && $2 == $8 {s++} END {print s + 0}'; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { if (b > 0 && a != "-") printf "%.2f", a / b; else printf "-" }'; }
mean_bytes() { awk '{b += $4} END {printf "%.0f", b / NR}' "$tmp/$1.native.1"; }
declare -A NAME=([wasm]="viewer, WebAssembly, Node.js" [chromium]="viewer, WebAssembly, headless Chromium (a module Worker)")
bad=0
rows=
echo "stream,decoder,bytes_per_frame,median_ms,p90_ms,frames,bit_identical_frames" >"$OUT/decode.csv"
for s in plain timed; do
    read -r n_med n_p90 frames <<<"$(stats "$s.native")"
    bytes=$(mean_bytes "$s")
    label="every tick's tiles (before)"
    [[ $s == timed ]] && label="samples in time (the viewer's)"
    echo "$s,native C,$bytes,$n_med,$n_p90,$frames,$frames" >>"$OUT/decode.csv"
    rows+="| $label | native C (-O2): the floor | $bytes | $n_med | $n_p90 | 1.00 | $frames of $frames |"$'\n'
    for d in wasm chromium; do
        [[ -f $tmp/$s.$d.1 ]] || continue
        read -r med p90 _ <<<"$(stats "$s.$d")"
        sm=$(same "$s" "$d")
        if [[ $sm -ne $frames ]]; then
            echo "bench_decode: $s/$d differs from the native decoder on $((frames - sm)) frames" >&2
            bad=1
        fi
        echo "$s,${NAME[$d]},$bytes,$med,$p90,$frames,$sm" >>"$OUT/decode.csv"
        rows+="| $label | ${NAME[$d]} | $bytes | $med | $p90 | $(ratio "$med" "$n_med") | $sm of $frames |"$'\n'
    done
done
cat <<EOF
The stream \`make run\` serves (ship-bridge), a camera 25 m up flying at 60 m/s for 10 s (1280x720), recorded
twice with the browser viewer's subscription: as the viewer takes it (samples in time: each mip once per its
update interval, two samples held and blended) and with every tick's tiles (\`--time-interp off\`, the stream
before). Each frame decoded on one core as the viewer's decode workers do: the message, then every tile into
its texel block; with samples in time the frame applied to the store and its instant blended into texel
blocks (the C library's store, \`clients/c/oc_held.c\`, in \`ocean.wasm\`). A frame's time is its median over
three interleaved runs; Chromium's clock is coarsened to 0.1 ms.

| stream | decoder | bytes / frame | median ms / frame | p90 ms / frame | x native | frames bit-identical to native |
|---|---|---:|---:|---:|---:|---:|
$rows
EOF
exit $bad
