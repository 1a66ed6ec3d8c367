#!/usr/bin/env bash
# test_build.sh - the build and test plumbing a newcomer meets first:
#  - `make` runs in parallel by default and keeps its objects: after a build,
#    `make -q all` finds nothing to do (no relinking of every program);
#  - tests/run.sh counts cmocka skips: a program with one pass and one skip
#    gives the closing line "1 passed, 0 failed, 1 skipped";
#  - the layering is the build's: an object of sim/ or protocol/ is compiled
#    without the include paths of server/ and clients/;
#  - `make run` installs Debian packages only (no npm: the browser test's
#    driver is `make test`'s), and `make run ARGS="--port 0 --scene storm"`
#    hands the arguments to oceand.
set -u
BUILD=${BUILD:-build}
tmp=$(mktemp -d /tmp/oc-build.XXXXXX)
runpid=
cleanup() { [[ -n $runpid ]] && kill -TERM -- "-$runpid" 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; exit 1; }
mk() { env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make --no-print-directory BUILD="$BUILD" "$@"; }

echo "== a second make has nothing to do ($SECONDS s)"
mk -q all || { mk -n all | head -20; fail "make -q all: the tree is not up to date after a build"; }
[[ -f $BUILD/obj/tests/test_ocean.o ]] || fail "objects of test programs were deleted"
mk -pq all 2>/dev/null | grep -E '^MAKEFLAGS = .*-j[0-9]' >/dev/null || fail "make is not parallel by default"
mk -j1 -pq all 2>/dev/null | grep -E '^MAKEFLAGS = .*-j1( |$)' >/dev/null || fail "-j1 on the command line is not kept"

echo "== run.sh counts skipped cmocka tests ($SECONDS s)"
mkdir -p "$tmp/b/tests"
cat >"$tmp/skip.c" <<'C'
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
static void passes(void **st) { (void)st; assert_int_equal(1, 1); }
static void skips(void **st) { (void)st; skip(); }
int main(void)
{
    const struct CMUnitTest t[] = {cmocka_unit_test(passes), cmocka_unit_test(skips)};
    return cmocka_run_group_tests(t, NULL, NULL);
}
C
cc -o "$tmp/b/tests/test_skip" "$tmp/skip.c" -lcmocka || fail "cannot build the cmocka probe"
bash tests/run.sh "$tmp/b" probe >"$tmp/run.log" 2>&1
tail -1 "$tmp/run.log" | grep -qx 'probe: 1 passed, 0 failed, 1 skipped' || fail "run.sh closing line: $(tail -3 "$tmp/run.log")"
[[ $(cat "$tmp/b/test-summary") == "1 0 1" ]] || fail "test-summary: $(cat "$tmp/b/test-summary")"

echo "== layering: sim/ and protocol/ cannot include server/ or clients/ headers ($SECONDS s)"
# The include paths make gives an object of each layer (its compile
# command, printed, not run), then probes compiled with them: the layer's
# own header and the one below compile, a header of a higher layer does not.
layer_incs() {  # layer source -> the -I flags of its compile command
    mk -n -B BUILD="$tmp/lay" "$tmp/lay/obj/$1/$2.o" 2>/dev/null | grep -E -- "-c $1/$2\.c" | head -1 |
        grep -o -- ' -I[^ ]*' | tr -d ' '
}
probe() {  # header flags... -> compiles a file including header with flags
    local h=$1
    shift
    printf '#include "%s"\nint probe_layer;\n' "$h" >"$tmp/probe.c"
    cc -D_GNU_SOURCE -fsyntax-only "$@" "$tmp/probe.c" 2>/dev/null
}
for spec in "sim spectrum ocean.h" "protocol codec codec.h proto.h ocean.h"; do
    read -r layer src own <<<"$spec"
    mapfile -t incs < <(layer_incs "$layer" "$src")
    ((${#incs[@]})) || fail "no compile command for $layer/$src.c from make -n"
    for h in $own; do probe "$h" "${incs[@]}" || fail "$layer/ cannot include its own $h with ${incs[*]}"; done
    for h in srv_client.h srv_net.h oceanclient.h oc_cascade.h; do
        probe "$h" "${incs[@]}" && fail "$layer/ can include $h (${incs[*]}): the build does not enforce the layering"
    done
done
[[ -f server/srv_client.h && -f clients/c/oceanclient.h ]] || fail "the probe headers moved"

echo "== make run needs no npm: its dependency step installs Debian packages only ($SECONDS s)"
grep -qE '^run: deps$' Makefile || fail "make run does not go through the deps target"
trace=$(bash -x .ci/deps.sh run 2>&1) || fail "deps.sh run failed: $(tail -5 <<<"$trace")"
grep -qE 'npm|node_modules' <<<"$(grep -v '^+ \[\[ run ==' <<<"$trace")" && fail "deps.sh run reaches for npm: $(grep -E 'npm|node' <<<"$trace" | head -3)"

echo "== make run ARGS=... reaches oceand ($SECONDS s)"
setsid env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make --no-print-directory BUILD="$BUILD" run \
    ARGS="--port 0 --scene storm" >"$tmp/run.out" 2>&1 &
runpid=$!
for _ in $(seq 400); do
    grep -q "listening on" "$tmp/run.out" && break
    kill -0 "$runpid" 2>/dev/null || break
    sleep 0.05
done
grep -q "oceand: listening on http://127.0.0.1:[1-9][0-9]*/ (scene storm" "$tmp/run.out" ||
    fail "make run ARGS: $(tail -5 "$tmp/run.out")"
kill -TERM -- "-$runpid"
wait "$runpid" 2>/dev/null
runpid=
grep -q 'ARGS="--port 0 --scene storm"' README.md || fail "README does not show make run ARGS"
echo "ok ($SECONDS s)"
