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
if (s.transforms !== 8) throw "transforms " + s.transforms;
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
expect_refused "--depth" stats --depth 0
expect_refused "unknown command" nonsense
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
grep -q "R, 32-bit floating-point" "$tmp/hdr" && grep -q "zip" "$tmp/hdr" || fail "EXR channels: $(cat "$tmp/hdr")"
exrheader "$tmp/bake/foam_c0_0000.exr" | grep -q "Y, 32-bit" || fail "foam EXR"
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
echo "ocean-sim CLI: all checks passed"
