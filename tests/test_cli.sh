#!/usr/bin/env bash
# ocean-sim from the command line: every subcommand's output, and refusal
# of bad options with a message naming them.  Run by tests/run.sh.
set -euo pipefail
B=${BUILD:-build}
sim="$B/ocean-sim"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# stats --json has every field the issue names, with sane values.
"$sim" stats --json --n 128 > "$tmp/stats.json"
for k in hs hs_spectrum tp mean min_jacobian folded_fraction transforms ms; do
    grep -q "\"$k\":" "$tmp/stats.json" || fail "stats --json lacks $k"
done
node -e '
const s = JSON.parse(require("fs").readFileSync(process.argv[1]));
if (!(s.hs > 1 && s.hs < 4)) throw "hs " + s.hs;
if (Math.abs(s.hs_spectrum - 2.2) > 0.3) throw "hs_spectrum " + s.hs_spectrum;
if (!(s.tp > 6 && s.tp < 9)) throw "tp " + s.tp;
if (s.transforms !== 9) throw "transforms " + s.transforms;
' "$tmp/stats.json" || fail "stats values"

# Only asked effects are transformed.
"$sim" stats --json --n 64 --effects height | grep -q '"transforms":	1' || fail "height-only stats ran more than one transform"

# Bad options are refused with their name, exit status 2.
expect_refused() {
    local what=$1; shift
    if "$sim" "$@" >"$tmp/out" 2>"$tmp/err"; then fail "accepted: $*"; fi
    grep -q -- "$what" "$tmp/err" || fail "message for '$*' does not name $what: $(cat "$tmp/err")"
}
expect_refused "--wind" stats --wind -3
expect_refused "--wind" stats --wind nan
expect_refused "--n" stats --n 4096
expect_refused "n = 100" stats --n 100
expect_refused "--spectrum" stats --spectrum bogus
expect_refused "--bogus" stats --bogus 1
expect_refused "--effects" stats --effects height,sparkle
# the near field is the daemon's: asked of ocean-sim it was ignored in silence
expect_refused "near-field is oceand's" query --effects height,near-field --points 0,0
expect_refused "--depth" stats --depth 0
expect_refused "unknown command" nonsense
# One time limit (sim/ocean_time.h): 2^27 s is served, the next second is
# refused with a message naming OCEAN_TIME_MAX, in every subcommand that
# takes a time, and a sample series may not run past it.
"$sim" stats --n 16 --time 134217728 >/dev/null || fail "stats at the time limit"
expect_refused "OCEAN_TIME_MAX" stats --n 16 --time 134217729
expect_refused "OCEAN_TIME_MAX" stats --n 16 --time -1e16
# the refused time is printed with every digit it has (15 digits said
# "134217728 s is beyond +-134217728 s")
expect_refused "134217728.00000003 s is beyond" query --n 16 --t 134217728.00000003 --points 0,0
expect_refused "OCEAN_TIME_MAX" query --n 16 --t 1e13 --points "0,0"
expect_refused "OCEAN_TIME_MAX" sample --n 16 --t0 134217729 --count 1
expect_refused "OCEAN_TIME_MAX" sample --n 16 --x 0 --z 0 --t0 134217728 --dt 1 --count 2
# The scene plan (sim/ocean_plan.h): a peak beyond the patch and a sea
# beyond its breaking height are refused with the numbers, a sea whose
# largest waves would break is run with a warning on stderr.
expect_refused "dominant wavelength 8708 m" stats --n 16 --wind 100
expect_refused "breaking height 0.0078 m" stats --n 16 --spectrum tma --depth 0.01
"$sim" stats --n 64 --spectrum tma --depth 2 >/dev/null 2>"$tmp/err" || fail "tma at 2 m refused"
grep -q "scene plan: warning (breaking)" "$tmp/err" || fail "no breaking warning: $(cat "$tmp/err")"
"$sim" stats --help | grep -q -- "--spreading" || fail "stats --help"

# Beaufort sets the wind: force 8 makes a bigger sea than force 4.
h4=$("$sim" stats --json --n 64 --beaufort 4 | sed -n 's/.*"hs_spectrum":\s*\([0-9.e+-]*\).*/\1/p')
h8=$("$sim" stats --json --n 64 --beaufort 8 | sed -n 's/.*"hs_spectrum":\s*\([0-9.e+-]*\).*/\1/p')
awk -v a="$h4" -v b="$h8" 'BEGIN { exit !(b > 2 * a) }' || fail "beaufort 8 ($h8) vs 4 ($h4)"

# --config applies a config file.
printf 'sea.wind = 20\nocean.n = 64\n' > "$tmp/c.conf"
hc=$("$sim" stats --json --config "$tmp/c.conf" | sed -n 's/.*"wind":\s*\([0-9.e+-]*\).*/\1/p')
[[ "$hc" == 20 ]] || fail "--config wind: $hc"
printf 'sea.wind = 200\n' > "$tmp/bad.conf"
expect_refused "bad.conf:1" stats --config "$tmp/bad.conf"

# sample: a CSV time series, FFT and direct summation agree at a grid point.
"$sim" sample --n 64 --x 31.25 --z 62.5 --t0 0 --dt 0.5 --count 5 > "$tmp/a.csv"
"$sim" sample --n 64 --x 31.25 --z 62.5 --t0 0 --dt 0.5 --count 5 --direct > "$tmp/b.csv"
[[ $(wc -l < "$tmp/a.csv") -eq 6 ]] || fail "sample rows"
paste -d, "$tmp/a.csv" "$tmp/b.csv" | tail -n +2 | awk -F, '{ d = $2 - $6; if (d < 0) d = -d; if (d > 1e-4) bad = 1 } END { exit bad }' \
    || fail "sample fft vs direct differ"

# bake: OpenEXR files OpenEXR's own tools read, with the documented channels.
"$sim" bake --n 32 --frames 2 --fps 10 --out "$tmp/bake" > /dev/null
for f in displacement_c0_0000 displacement_c0_0001 normal_c0_0001 foam_c0_0000; do
    [[ -s "$tmp/bake/$f.exr" ]] || fail "bake did not write $f.exr"
done
exrheader "$tmp/bake/displacement_c0_0000.exr" > "$tmp/hdr" || fail "exrheader cannot read the bake"
for ch in displacement.R displacement.G displacement.B; do
    grep -q "^ *$ch, 32-bit floating-point" "$tmp/hdr" || fail "EXR channel $ch: $(cat "$tmp/hdr")"
done
grep -q "zip" "$tmp/hdr" || fail "EXR compression: $(cat "$tmp/hdr")"
exrheader "$tmp/bake/normal_c0_0001.exr" | grep -q "^ *normal.G, 32-bit" || fail "normal EXR channels"
exrheader "$tmp/bake/foam_c0_0000.exr" | grep -q "^ *foam.Y, 32-bit" || fail "foam EXR"

# bake: every file's header says what it holds, read back with exrheader.
# Expected values are the bake's own inputs: the patch of cascade c is
# --size / --cascade-ratio^c, frame k is at --time + k / --fps.
"$sim" bake --n 32 --frames 3 --fps 24 --time 100 --cascades 2 --size 800 --cascade-ratio 4 \
    --spectrum jonswap --wind 14 --direction 30 --fetch 50000 --depth 200 --seed 7 --out "$tmp/bk" > /dev/null
exrheader "$tmp/bk/displacement_c1_0002.exr" > "$tmp/hdr2" || fail "exrheader on the attribute bake"
attr() { sed -n "s/^$1 (type [a-z0-9]*): //p" "$tmp/hdr2"; }
num_is() {  # name expected tolerance (awk: a python3 starts in 0.25 CPU-s here)
    awk -v v="$(attr "$1" | sed 's/ .*//')" -v w="$2" -v tol="$3" \
        'BEGIN { d = v - w; if (d < 0) d = -d; exit !(v != "" && d <= tol) }' ||
        fail "EXR $1 = '$(attr "$1")', want $2: $(cat "$tmp/hdr2")"
}
[[ $(attr framesPerSecond) == "24/1 (24)" ]] || fail "framesPerSecond: '$(attr framesPerSecond)'"
num_is oceand.patchSize 200 1e-9
# exrheader prints 6 significant digits.
num_is oceand.time 100.0833333333333 1e-3
num_is oceand.frame 2 0
num_is oceand.cascade 1 0
num_is oceand.gridSize 32 0
num_is oceand.sampleSpacing 6.25 1e-9
num_is oceand.windSpeed 14 0
num_is oceand.windDirection 30 0
num_is oceand.fetch 50000 0
num_is oceand.depth 200 0
[[ $(attr oceand.spectrum) == '"jonswap"' ]] || fail "EXR spectrum: $(attr oceand.spectrum)"
[[ $(attr oceand.seed) == '"7"' ]] || fail "EXR seed: $(attr oceand.seed)"
[[ -n $(attr oceand.significantWaveHeight) ]] || fail "EXR has no significant wave height"
attr oceand.channels | grep -q "displacement.G = height" || fail "EXR channel mapping: $(attr oceand.channels)"

# Help shows the defaults the commands really run with (issue 17 item 5):
# every "(default X)" of --help equals what --show-options reports with no
# option given, and every option is listed by both.
for cmd in stats bake sample bench query filter mesh; do
    "$sim" $cmd --help > "$tmp/help.txt" || fail "$cmd --help"
    "$sim" $cmd --show-options > "$tmp/show.txt" || fail "$cmd --show-options"
    n=0
    while IFS= read -r line; do
        name=$(sed -n 's/^  --\([a-z0-9-]*\) .*/\1/p' <<<"$line")
        [[ -n $name && $name != help && $name != show-options ]] || continue
        grep -q -- "^--$name=" "$tmp/show.txt" || fail "$cmd: --$name in --help but not in --show-options"
        def=$(sed -n 's/.* (default \(.*\))$/\1/p' <<<"$line")
        [[ -n $def ]] || continue
        real=$(sed -n "s/^--$name=//p" "$tmp/show.txt")
        [[ "$def" == "$real" ]] || fail "$cmd --help says --$name defaults to '$def', the parser gives '$real'"
        n=$((n + 1))
    done < "$tmp/help.txt"
    [[ $n -ge 10 ]] || fail "$cmd --help shows only $n defaults"
done
# No help text states a default of its own beside the generated one.
for cmd in stats bake sample bench query filter mesh; do
    "$sim" $cmd --help | grep -E '\(default [^)]*\).*\(default' && fail "$cmd: two defaults on one line"
done

# Names, not numbers (issue 17 item 6).
"$sim" stats --spectrum jonswap --show-options | grep -qx -- "--spectrum=jonswap" || fail "--spectrum jonswap"
expect_refused "--spectrum" stats --spectrum 2
expect_refused "--spreading" stats --spreading 1
"$sim" stats --plan measure --show-options | grep -qx -- "--plan=measure" || fail "--plan measure"
# A config file's sea is what the options start from.
printf 'sea.spectrum = tma\nsea.wind = 7\n' > "$tmp/sea.conf"
"$sim" stats --config "$tmp/sea.conf" --show-options > "$tmp/show.txt"
grep -qx -- "--spectrum=tma" "$tmp/show.txt" && grep -qx -- "--wind=7" "$tmp/show.txt" || fail "config not applied: $(cat "$tmp/show.txt")"
"$sim" stats --wind 9 --config "$tmp/sea.conf" --show-options | grep -qx -- "--wind=9" || fail "an option before --config lost to the file"
# sample needs its point; bake's usage agrees with its defaults.
expect_refused "--x" sample --z 3
expect_refused "--z" sample --x 3
"$sim" bake --help | head -1 | grep -q -- "\[--frames N\] \[--fps F\]" || fail "bake usage calls --frames/--fps required"
"$sim" bake --help | grep -- "--frames" | grep -q "(default 1)" || fail "bake --frames default not documented"
expect_refused "--out" bake --n 32
# mesh: the default budget is a viewer's, not a film's (1 px was 1.6 M vertices).
"$sim" mesh --camera 0,25,0 --json --n 64 > "$tmp/mesh.json"
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if d['vertices'] < 100000 else 1)" "$tmp/mesh.json" ||
    fail "mesh default makes $(grep vertices "$tmp/mesh.json")"
"$sim" bake --n 32 --frames 1 --out "$tmp/b2" --effects height > /dev/null
[[ ! -e "$tmp/b2/normal_c0_0000.exr" ]] || fail "bake wrote normals nobody asked for"

# query: JSON per point with height, normal, velocity, foam, error.
"$sim" query --n 64 --t 3 --points "1,2;30.5,-7" --json > "$tmp/q.json"
node -e '
const q = JSON.parse(require("fs").readFileSync(process.argv[1]));
if (q.points.length !== 2) throw "count";
for (const p of q.points) {
  for (const k of ["height", "normal", "velocity", "foam", "error"]) if (!(k in p)) throw k;
  // a bound against the exact waves: centimetres on this coarse N = 64 grid
  if (!(p.error > 0 && p.error < 0.1)) throw "error " + p.error;
}' "$tmp/q.json" || fail "query json"
expect_refused "point 2" query --points "1,2;x,3"
# query takes the common --time as it does --t (it evaluated t = 0 instead)
"$sim" query --n 64 --time 3 --points "1,2;30.5,-7" --json > "$tmp/q2.json" || fail "query --time"
python3 - "$tmp/q.json" "$tmp/q2.json" <<'PY' || fail "query --time 3 does not answer at t = 3"
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:3])
sys.exit(0 if b["t"] == 3 and [p["height"] for p in a["points"]] == [p["height"] for p in b["points"]] else 1)
PY
expect_refused "disagree" query --n 16 --t 3 --time 4 --points "1,2"
# query --geo: latitude and longitude onto the ocean's plane about --origin
# (x north, z east): the answer is the one at the mapped x, z, and a step
# of 0.001 deg north is 111.10 m and east 80.88 m (WGS 84 at 43.5 deg: M and N cos(lat))
"$sim" query --n 64 --t 3 --geo "43.5,-8.25;43.501,-8.25;43.5,-8.249" --origin 43.5,-8.25 --json > "$tmp/qg.json" ||
    fail "query --geo"
python3 - "$tmp/qg.json" <<'PY' || fail "query --geo does not map onto the plane"
import json, sys
p = json.load(open(sys.argv[1]))["points"]
ok = p[0]["x"] == 0 and p[0]["z"] == 0 and abs(p[1]["x"] - 111.10) < 0.01 and abs(p[1]["z"]) < 1e-6
ok = ok and abs(p[2]["z"] - 80.877) < 0.01 and 0 < p[2]["x"] < 0.01 and p[1]["lat"] == 43.501
sys.exit(0 if ok else 1)
PY
pts=$(python3 -c 'import json,sys; print(";".join("%r,%r" % (q["x"], q["z"]) for q in json.load(open(sys.argv[1]))["points"]))' "$tmp/qg.json")
"$sim" query --n 64 --t 3 --points "$pts" --json > "$tmp/qxz.json" || fail "query at the mapped points"
python3 - "$tmp/qg.json" "$tmp/qxz.json" <<'PY' || fail "query --geo and --points at the same x, z differ"
import json, sys
a, b = (json.load(open(f))["points"] for f in sys.argv[1:3])
sys.exit(0 if [p["height"] for p in a] == [p["height"] for p in b] else 1)
PY
expect_refused "latitude in" query --n 16 --geo "91,0"
expect_refused "--origin" query --n 16 --geo "1,2" --origin "1,2;3,4"
expect_refused "origin" query --n 16 --geo "1,2" --origin "95,0"
expect_refused "exactly one of" query --n 16 --geo "1,2" --points "1,2"
# a direct sum is priced before it starts (--count 1e6 at n 256: 7 hours)
expect_refused "more than --max-terms" sample --x 1 --z 2 --direct --count 1000000
"$sim" sample --n 16 --x 1 --z 2 --direct --count 3 --max-terms 1e3 >/dev/null || fail "sample --direct within --max-terms"
# the concentric mesh keeps its error budget (16 px) on steep chop: the
# sideways error grows with the choppiness, and with one roughness for
# every sea it was 16.2 px at choppiness 3 and 54 px at 10 (camera 25 m);
# up to 1.3 (the shipped scene's) the mesh is the calibrated one
for chop in 1 1.3 3 10; do
    "$sim" mesh --camera 0,25,0 --choppiness "$chop" --json > "$tmp/mesh_$chop.json" || fail "mesh --choppiness $chop"
done
python3 - "$tmp" <<'PY' || fail "mesh error budget on steep chop"
import json, sys
d = {c: json.load(open(f"{sys.argv[1]}/mesh_{c}.json")) for c in ("1", "1.3", "3", "10")}
for c, m in d.items():
    if not m["max_error_px"] <= 16:
        sys.exit(f"choppiness {c}: mesh error {m['max_error_px']:.1f} px over the 16 px budget")
if d["1.3"]["vertices"] != d["1"]["vertices"]:
    sys.exit(f"choppiness 1.3 densified the calibrated mesh: {d['1.3']['vertices']} vertices, {d['1']['vertices']} at 1")
PY
# a mesh priced beyond --max-vertices is refused before it is built (a
# 0.01-degree camera asked for gigabytes and ran for minutes)
expect_refused "max-vertices" mesh --n 16 --camera 0,20,0 --fov 0.01
expect_refused "max-vertices" mesh --n 16 --camera 0,20,0 --max-vertices 5000
# wisdom checks every scene and --out before it times the first plan (a
# minute at N = 1024): a typo fails at once, not after the planning
for args in "--out $tmp/w.wisdom config/scenes/nope.conf|nope.conf" "--out $tmp/no/such/w.wisdom|cannot write"; do
    rc=0
    timeout 20 "$sim" wisdom --n 1024 ${args%|*} >"$tmp/out" 2>"$tmp/err" || rc=$?
    [[ $rc -eq 2 ]] || fail "wisdom ${args%|*}: exit $rc (124: it planned first)"
    grep -q "${args#*|}" "$tmp/err" || fail "wisdom ${args%|*}: $(cat "$tmp/err")"
done
# a bake whose last frame passes the time limit is refused before it writes
expect_refused "last frame time" bake --n 16 --out "$tmp/late" --time 134217727 --fps 1 --frames 3
[[ ! -e $tmp/late ]] || fail "a refused bake left $tmp/late behind"
# sample --json is JSON, one entry per sample
"$sim" sample --n 16 --x 3 --z 4 --count 3 --json > "$tmp/sample.json"
node -e '
const j = JSON.parse(require("fs").readFileSync(process.argv[1]));
if (j.x !== 3 || j.z !== 4 || j.samples.length !== 3) throw "sample json " + JSON.stringify(j);
if (!(Math.abs(j.samples[1].t - 0.1) < 1e-12) || !isFinite(j.samples[2].height)) throw "samples";
' "$tmp/sample.json" || fail "sample --json"
# a point the library cannot answer (beyond 1e12 m) is refused, not printed as zeros
expect_refused "point 2 (1e+17, 0) refused" query --n 16 --points "1,2;1e17,0"
# wake --json: the fields the offline probe names, heights[iz * nx + ix] on
# a grid reaching 20 transverse wavelengths (2 pi U^2 / g) behind and both
# sides of the wedge; no wind sea, so no sea option is taken
"$sim" wake --speed 8 --length 40 --json > "$tmp/wake.json"
node -e '
const w = JSON.parse(require("fs").readFileSync(process.argv[1]));
for (const k of ["speed", "length", "depth", "x0", "z0", "dx", "nx", "nz", "heights"])
    if (!(k in w)) throw "wake lacks " + k;
const lam = 2 * Math.PI * 64 / 9.81;
if (w.heights.length !== w.nx * w.nz || !w.heights.every(Number.isFinite)) throw "heights";
if (!(w.x0 + (w.nx - 1) * w.dx >= 20 * lam && w.x0 < 0)) throw "reach behind " + (w.x0 + (w.nx - 1) * w.dx);
if (!(-w.z0 >= 20 * lam * Math.tan(19.47 * Math.PI / 180))) throw "reach across " + w.z0;
if (w.depth !== null || w.speed !== 8 || w.length !== 40) throw "echo " + JSON.stringify([w.depth, w.speed, w.length]);
' "$tmp/wake.json" || fail "wake --json"
expect_refused "speed" wake --speed 0 --length 40
expect_refused "required" wake --length 40
expect_refused "wind" wake --speed 8 --length 40 --wind 5
# query --entities: a ship's wake in the answers (issue 43: offline tools
# see the wakes), judged on the difference from the same query without it
# (the wind sea cancels) against the published laws: on the track behind a
# ship at 8 m/s heading +z the transverse waves' wavelength is
# 2 pi U^2 / g = 40.99 m (Kelvin 1887) within 3 %; the largest waves lie
# on the cusp lines at 19.47 deg either side, several times those at 25
# and 30 deg; an entry not yet in force, or its life gone, adds nothing.
ship() { # t z from: one sample of ship 5 heading +z at 8 m/s
    printf '{"id": 5, "kind": "ship", "t": %s, "x": 0, "z": %s, "heading_deg": 90, "speed": 8, "length_m": 120, "beam_m": 15, "draught_m": 5%s}' "$1" "$2" "${3:+, \"from\": $3}"
}
echo "[$(ship 0 0), $(ship 20 160)]" > "$tmp/ships.json"
echo "[$(ship 0 0), $(ship 20 160 26)]" > "$tmp/ships-later.json"
echo "[$(ship 0 0), $(ship 20 160), {\"id\": 5, \"gone\": true, \"from\": 24}]" > "$tmp/ships-gone.json"
python3 - > "$tmp/wake-pts.txt" <<'PY'
import math
for s in range(50, 652, 2): print("0,%g" % (200 - s))  # the track behind the ship, at (0, 200) at t = 25
for a in (19.47, 25, 30):
    for side in (-1, 1):
        for s in range(500, 801, 4): print("%.6f,%g" % (side * s * math.tan(math.radians(a)), 200 - s))
PY
for f in none ships ships-later ships-gone; do
    ents=()
    [[ $f != none ]] && ents=(--entities "$tmp/$f.json")
    "$sim" query --n 64 --t 25 --points-file "$tmp/wake-pts.txt" "${ents[@]}" --json > "$tmp/qw-$f.json" ||
        fail "query --entities $f.json"
done
python3 - "$tmp" <<'PY' || fail "query --entities: the wake is not the Kelvin wake"
import json, math, sys
pts = lambda f: json.load(open("%s/qw-%s.json" % (sys.argv[1], f)))["points"]
none = pts("none")
d = [q["height"] - p["height"] for p, q in zip(none, pts("ships"))]
s = [200 - p["z"] for p in none[:301]]
up = [s[i] + (s[i + 1] - s[i]) * d[i] / (d[i] - d[i + 1]) for i in range(300) if s[i] >= 100 and d[i] < 0 <= d[i + 1]]
lam, want = (up[-1] - up[0]) / (len(up) - 1), 2 * math.pi * 64 / 9.81
print("query --entities: transverse wavelength on the track %.2f m (2 pi U^2 / g = %.2f m) from %d crossings" % (lam, want, len(up)))
assert len(up) >= 10 and abs(lam / want - 1) < 0.03
ray = lambda k: max(abs(x) for x in d[301 + 76 * k: 301 + 76 * (k + 1)])
cusp, r25, r30 = min(ray(0), ray(1)), max(ray(2), ray(3)), max(ray(4), ray(5))
print("query --entities: largest wake 500-800 m astern at 19.47 deg %.4f m, 25 deg %.4f m, 30 deg %.4f m" % (cusp, r25, r30))
assert cusp > 0.02 and cusp > 5 * r25 and cusp > 5 * r30
for f in ("ships-later", "ships-gone"):  # the second sample not in force at 25 (on from the first: held at 10 s), or gone at 24
    dd = [q["height"] - p["height"] for p, q in zip(none, pts(f))]
    assert max(abs(x) for x in dd[:301]) == 0, f
PY
# a helicopter (16 m rotor) hovering 10 m over (0, 0) since t = 0: at
# t = 100 its downwash's dent alone (sim/rotor_wash.h), whose displaced
# water weighs the thrust (Archimedes): its depth at the centre is the
# thrust at 360 N/m^2 of disk over rho g pi c^2, c^2 = (D / 2 sqrt 2)^2 +
# H^2 / 114 (Beltaos & Rajaratnam's impinging jet)
echo '[{"id": 9, "kind": "rotorcraft", "t": 0, "x": 0, "z": 0, "altitude_m": 10, "heading_deg": 0, "speed": 0, "length_m": 16}]' > "$tmp/rotor.json"
for f in none rotor; do
    ents=()
    [[ $f != none ]] && ents=(--entities "$tmp/$f.json")
    "$sim" query --n 64 --t 100 --points "0,0;4,3;200,0" "${ents[@]}" --json > "$tmp/qr-$f.json" || fail "query --entities rotor.json"
done
python3 - "$tmp" <<'PY' || fail "query --entities: the rotorcraft's dent"
import json, math, sys
pts = lambda f: json.load(open("%s/qr-%s.json" % (sys.argv[1], f)))["points"]
d = [q["height"] - p["height"] for p, q in zip(pts("none"), pts("rotor"))]
thrust, c2 = 360 * math.pi * 16 ** 2 / 4, (16 / (2 * math.sqrt(2))) ** 2 + 10 ** 2 / 114
head = thrust / (1025 * 9.81 * math.pi * c2)
print("query --entities: hovering rotor's dent %.4f m at its centre (thrust / (rho g pi c^2) = %.4f m), %.4f m 5 m out "
      "(%.4f), %.1e m 200 m out" % (d[0], -head, d[1], -head * math.exp(-25 / c2), d[2]))
assert abs(d[0] + head) < 1e-4 and abs(d[1] + head * math.exp(-25 / c2)) < 1e-4 and abs(d[2]) < 1e-6
PY
echo '[{"id": 5, "kind": "ship", "t": 0, "x": 0, "z": 0, "heading_deg": 0, "speed": 8, "length_m": 120, "beam_m": 15, "draught_m": 5}, {"id": 5, "kind": "ship", "t": 1, "x": 900, "z": 0, "heading_deg": 0, "speed": 8, "length_m": 120, "beam_m": 15, "draught_m": 5}]' > "$tmp/teleport.json"
expect_refused "entry 1: entity 5 sample: .* (a teleport" query --n 16 --points 0,0 --entities "$tmp/teleport.json"
echo '{"id": 5}' > "$tmp/notarray.json"
expect_refused "not a JSON array" query --n 16 --points 0,0 --entities "$tmp/notarray.json"
echo '[{"id": 5, "kind": "ship", "t": 0, "x": 0, "z": "here", "heading_deg": 0, "speed": 8, "length_m": 120, "beam_m": 15, "draught_m": 5}]' > "$tmp/nan.json"
expect_refused "entry 0: entity 5 sample" query --n 16 --points 0,0 --entities "$tmp/nan.json"
expect_refused "cannot open" query --n 16 --points 0,0 --entities "$tmp/no-such.json"
# render: a PNG of the asked size from a shipped scene (IHDR width and
# height, big-endian at bytes 16-23), the same bytes from 1 and 2 threads
# (the sea is a pure function of its inputs), bad views refused.
"$sim" render --config config/oceand.conf --scene ship-bridge --pos 0,25,0 --pitch -5 --size 48x27 \
    --supersample 1 --time 12.5 --threads 1 --out "$tmp/r1.png" --json > "$tmp/render.json"
"$sim" render --config config/oceand.conf --scene ship-bridge --pos 0,25,0 --pitch -5 --size 48x27 \
    --supersample 1 --time 12.5 --threads 2 --out "$tmp/r2.png"
[[ $(od -An -tx1 -j16 -N8 "$tmp/r1.png" | tr -d ' \n') == 000000300000001b ]] || fail "render: PNG size"
cmp -s "$tmp/r1.png" "$tmp/r2.png" || fail "render: 1 and 2 threads differ"
grep -q '"sea_rays":' "$tmp/render.json" || fail "render --json lacks sea_rays"
expect_refused "--out" render --size 8x8
expect_refused "--size" render --size 0x8 --out "$tmp/x.png"
expect_refused "--pos" render --pos 0,nan,0 --out "$tmp/x.png"
expect_refused "scene" render --scene no-such-scene --out "$tmp/x.png"
expect_refused "--fov" render --fov 200 --out "$tmp/x.png"
expect_refused "--sun" render --sun 10,95 --out "$tmp/x.png"
echo "ocean-sim CLI: all checks passed"
