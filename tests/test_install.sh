#!/usr/bin/env bash
# test_install.sh - `make install` into a temporary prefix, used the way a
# newcomer does:
#  - a program that includes <oceand/oceanclient.h>, built with `pkg-config
#    --cflags --libs oceanclient`, links the shared library (soname
#    liboceanclient.so.0) and runs without LD_LIBRARY_PATH; one built with
#    `--static` links the archive with Libs.private alone and runs; the
#    include path the .pc gives holds no generic header name;
#  - the client library pulls in no simulator: neither the installed
#    liboceanclient.so nor a program linked with `pkg-config --libs
#    oceanclient` needs FFTW or OpenMP (libgomp); a program that runs its
#    own ocean links `pkg-config --libs oceansim` (shared and static), and
#    the ship example's --offline run is built that way;
#  - the installed oceand, started from another directory with no config,
#    serves the viewer at / and streams a frame (scenes and web viewer found
#    under PREFIX/share/oceand); so does the systemd unit's ExecStart, which
#    reloads on its ExecReload signal and stops on SIGTERM with exit 0;
#  - DESTDIR stages the same tree with PREFIX compiled in.
set -u
BUILD=${BUILD:-build}
tmp=$(mktemp -d /tmp/oc-install.XXXXXX)
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null; wait "$p" 2>/dev/null; done; rm -rf "$tmp"; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; exit 1; }
# A make started from inside `make test` must not inherit its jobserver.
mk() { env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make --no-print-directory BUILD="$BUILD" "$@"; }

prefix=$tmp/prefix
echo "== make install PREFIX=$prefix ($SECONDS s)"
mk install PREFIX="$prefix" >"$tmp/install.log" 2>&1 || { tail -20 "$tmp/install.log"; fail "make install"; }
for f in bin/oceand bin/ocean-client bin/ocean-sim lib/liboceanclient.a lib/liboceanclient.so \
         lib/liboceanclient.so.0 lib/pkgconfig/oceanclient.pc include/oceand/oceanclient.h \
         lib/liboceansim.a lib/liboceansim.so lib/liboceansim.so.0 lib/pkgconfig/oceansim.pc \
         include/oceand/ocean.h include/oceand/oc_ship_offline.h \
         share/oceand/web/index.html share/oceand/web/main.js share/oceand/scenes/ship-bridge.conf \
         share/oceand/scenes/storm.conf etc/oceand/oceand.conf lib/systemd/system/oceand.service; do
    [[ -e $prefix/$f ]] || fail "not installed: $f"
done
# the installed daemon's --help says which file it reads without --config
"$prefix/bin/oceand" --help | grep -q "without it $prefix/etc/oceand/oceand.conf if readable" ||
    fail "installed oceand --help: $("$prefix/bin/oceand" --help | grep -A1 -- --config)"
# examples are source, not commands: a 'ship' in PREFIX/bin could shadow another
[[ -e $prefix/bin/ship ]] && fail "the ship example is installed as $prefix/bin/ship"
# private headers stay private; the .pc's comment is not rewritten by install
for f in include/oceand/ocean_internal.h include/oceand/mesh_internal.h include/oceand/ocean_reference.h; do
    [[ -e $prefix/$f ]] && fail "a private header is installed: $f"
done
grep -q "^#.*$prefix" "$prefix/lib/pkgconfig/oceanclient.pc" && fail "install rewrote the .pc's comment: $(head -3 "$prefix/lib/pkgconfig/oceanclient.pc")"
for lib in oceanclient oceansim; do
    soname=$(readelf -d "$prefix/lib/lib$lib.so" | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p')
    [[ $soname == lib$lib.so.0 ]] || fail "soname '$soname', want lib$lib.so.0"
done
# no simulator in the client library: nothing it needs, directly or through
# another library, is FFTW or libgomp (the simulator library needs both)
no_sim() {  # what file
    grep -E 'libfftw3f|libgomp' "$tmp/needs" && fail "$1 needs the simulator's libraries: $(cat "$tmp/needs")"
    return 0
}
readelf -d "$prefix/lib/liboceanclient.so" | grep NEEDED >"$tmp/needs"
grep -q 'libwebsockets' "$tmp/needs" || fail "readelf -d finds no NEEDED libwebsockets in liboceanclient.so: $(cat "$tmp/needs")"
no_sim "liboceanclient.so (readelf -d)"
ldd "$prefix/lib/liboceanclient.so" >"$tmp/needs"
no_sim "liboceanclient.so (ldd)"
readelf -d "$prefix/lib/liboceansim.so" | grep NEEDED >"$tmp/needs"
grep -q 'libfftw3f' "$tmp/needs" || fail "liboceansim.so does not need FFTW: $(cat "$tmp/needs")"
# the direct-sum reference is the tests' tool, in no installed library
nm -D --defined-only "$prefix/lib/liboceansim.so" "$prefix/lib/liboceanclient.so" | grep -q ocean_reference_ &&
    fail "an installed library exports the reference sum (ocean_reference_*)"
nm -D --defined-only "$prefix/lib/liboceansim.so" | grep -q ' T ocean_evaluate$' || fail "liboceansim.so lacks ocean_evaluate"

echo "== a program against the installed library, via pkg-config ($SECONDS s)"
export PKG_CONFIG_PATH=$prefix/lib/pkgconfig
pkg-config --exists oceanclient oceansim || fail "pkg-config does not find oceanclient and oceansim"
pkg-config --static --libs oceanclient | grep -Eq -- '-lfftw3f|-fopenmp' && fail "oceanclient's Libs.private names the simulator's: $(pkg-config --static --libs oceanclient)"
pkg-config --static --libs oceansim | grep -q -- -lfftw3f_omp || fail "oceansim's Libs.private lacks -lfftw3f_omp"
pkg-config --static --libs oceansim | grep -q -- -lfftw3f_threads && fail "oceansim's Libs.private names -lfftw3f_threads"
mkdir -p "$tmp/app"
cat >"$tmp/app/app.c" <<'C'
/* A user's first program: a client handle, and the library's result codes. */
#include <stdio.h>
#include <oceand/oceanclient.h>
int main(void)
{
    proto_subscribe s;
    oc_subscribe_default(&s);
    printf("oceanclient %s ok tile_size %u (%s)\n", OC_VERSION, (unsigned)s.tile_size, ocean_strerror(OCEAN_OK));
    return 0;
}
C
cat >"$tmp/app/simapp.c" <<'C'
/* A program that runs its own ocean beside the client library. */
#include <stdio.h>
#include <oceand/oceanclient.h>
#include <oceand/ocean.h>
int main(void)
{
    ocean_params p;
    ocean_params_default(&p);
    p.n = 64;
    char err[256];
    ocean *o = NULL;
    if (ocean_create(&p, &o, err, sizeof err) != OCEAN_OK) { fprintf(stderr, "%s\n", err); return 1; }
    ocean_destroy(o);
    proto_subscribe s;
    oc_subscribe_default(&s);
    printf("oceansim %s ok tile_size %u\n", OC_VERSION, (unsigned)s.tile_size);
    return 0;
}
C
# shellcheck disable=SC2046
cc -o "$tmp/app/app_shared" "$tmp/app/app.c" $(pkg-config --cflags --libs oceanclient) 2>"$tmp/cc.log" ||
    fail "shared link: $(head -20 "$tmp/cc.log")"
ldd "$tmp/app/app_shared" | grep -q 'liboceanclient.so.0 =>' || fail "app_shared does not use liboceanclient.so.0"
env -u LD_LIBRARY_PATH "$tmp/app/app_shared" | grep -q "ok" || fail "app_shared does not run without LD_LIBRARY_PATH"
ldd "$tmp/app/app_shared" >"$tmp/needs"
no_sim "a program linked with pkg-config --libs oceanclient"
# shellcheck disable=SC2046
cc -o "$tmp/app/simapp_shared" "$tmp/app/simapp.c" $(pkg-config --cflags --libs oceansim) 2>"$tmp/cc.log" ||
    fail "shared link against oceansim: $(head -20 "$tmp/cc.log")"
env -u LD_LIBRARY_PATH "$tmp/app/simapp_shared" | grep -q "ok" || fail "simapp_shared does not run without LD_LIBRARY_PATH"
# shellcheck disable=SC2046
cc -o "$tmp/app/simapp_static" "$tmp/app/simapp.c" \
    $(pkg-config --static --cflags --libs oceansim | sed 's/-locean\([a-z]*\)/-l:libocean\1.a/g') 2>"$tmp/cc.log" ||
    fail "static link against oceansim with Libs.private: $(head -20 "$tmp/cc.log")"
ldd "$tmp/app/simapp_static" | grep -Eq 'libocean(client|sim)\.so' && fail "simapp_static still needs a shared oceand library"
"$tmp/app/simapp_static" | grep -q "ok" || fail "simapp_static does not run"
# nothing generic on the include path the library gives: its headers are
# <oceand/...>, and a bare "codec.h" or "conf.h" is not found through it
for h in codec.h conf.h oceanclient.h; do
    printf '#include "%s"\n' "$h" >"$tmp/app/generic.c"
    # shellcheck disable=SC2046
    cc -fsyntax-only "$tmp/app/generic.c" $(pkg-config --cflags oceanclient) 2>/dev/null &&
        fail "pkg-config --cflags puts $h at the top of the include path"
done
# shellcheck disable=SC2046
cc -o "$tmp/app/app_static" "$tmp/app/app.c" \
    $(pkg-config --static --cflags --libs oceanclient | sed 's/-loceanclient/-l:liboceanclient.a/') 2>"$tmp/cc.log" ||
    fail "static link with Libs.private: $(head -20 "$tmp/cc.log")"
ldd "$tmp/app/app_static" | grep -q liboceanclient && fail "app_static still needs the shared library"
"$tmp/app/app_static" | grep -q "ok" || fail "app_static does not run"
# The project's own example, built as a user would.
# shellcheck disable=SC2046
cc -o "$tmp/app/ship" clients/examples/ship.c $(pkg-config --cflags --libs oceansim) -lm 2>"$tmp/cc.log" ||
    fail "ship.c against the installed library: $(head -20 "$tmp/cc.log")"
env -u LD_LIBRARY_PATH "$tmp/app/ship" --offline --seconds 2 --quiet >"$tmp/ship.out" 2>&1 ||
    fail "installed ship --offline: $(cat "$tmp/ship.out")"

# start_daemon LOG CMD... : runs CMD from an empty directory, waits for
# "listening", sets $port.
start_daemon() {
    local log=$1; shift
    mkdir -p "$tmp/elsewhere"
    (cd "$tmp/elsewhere" && exec "$@") >"$log" 2>&1 &
    dpid=$!
    pids+=("$dpid")
    port=
    for _ in $(seq 200); do
        port=$(sed -n 's|^oceand: listening on http://[0-9.]*:\([0-9]*\)/.*|\1|p' "$log")
        [[ -n $port ]] && return 0
        kill -0 "$dpid" 2>/dev/null || break
        sleep 0.05
    done
    fail "daemon did not start: $* : $(cat "$log")"
}
check_serves() {  # name
    curl -sf "http://127.0.0.1:$port/" -o "$tmp/index.html" || fail "$1: GET / failed"
    grep -qi "<html" "$tmp/index.html" || fail "$1: / is not the viewer"
    curl -sf "http://127.0.0.1:$port/main.js" -o /dev/null || fail "$1: GET /main.js failed"
    "$prefix/bin/ocean-client" watch "ws://127.0.0.1:$port/" --frames 1 --seconds 20 --mesh none --json \
        >"$tmp/watch.json" 2>"$tmp/watch.err" || fail "$1: no frame: $(cat "$tmp/watch.err")"
    python3 -c "import json,sys; d=json.load(open('$tmp/watch.json')); sys.exit(0 if d['frames'] >= 1 and d['decode_errors'] == 0 else 1)" ||
        fail "$1: watch: $(cat "$tmp/watch.json")"
}
stop_daemon() {  # name
    kill -TERM "$dpid"
    wait "$dpid"
    local rc=$?
    [[ $rc -eq 0 ]] || fail "$1: SIGTERM exit $rc"
}

echo "== installed oceand, no config, from another directory ($SECONDS s)"
start_daemon "$tmp/d1.log" "$prefix/bin/oceand" --port 0
grep -q "scene ship-bridge" "$tmp/d1.log" || fail "default scene not served: $(cat "$tmp/d1.log")"
# it reads PREFIX/etc/oceand/oceand.conf, the file `make install` put there
grep -q "reading $prefix/etc/oceand/oceand.conf" "$tmp/d1.log" || fail "installed config not read: $(cat "$tmp/d1.log")"
check_serves "no config"
stop_daemon "no config"
# a key changed in the installed config takes effect without --config
sed -i 's|^server.tick_rate = .*|server.tick_rate = 20|' "$prefix/etc/oceand/oceand.conf"
grep -q '^server.tick_rate = 20$' "$prefix/etc/oceand/oceand.conf" || fail "no server.tick_rate line in the installed config"
start_daemon "$tmp/d1b.log" "$prefix/bin/oceand" --port 0
grep -q "20 Hz" "$tmp/d1b.log" || fail "installed config's tick rate not used: $(cat "$tmp/d1b.log")"
stop_daemon "installed config edited"
sed -i 's|^server.tick_rate = 20$|server.tick_rate = 30|' "$prefix/etc/oceand/oceand.conf"

echo "== the systemd unit's commands ($SECONDS s)"
unit=$prefix/lib/systemd/system/oceand.service
grep -qx 'Type=simple' "$unit" || grep -qx 'Type=notify' "$unit" || fail "unit: no Type=simple/notify"
grep -qx 'ExecReload=/bin/kill -HUP $MAINPID' "$unit" || fail "unit: ExecReload is not SIGHUP"
grep -qx 'KillSignal=SIGTERM' "$unit" || fail "unit: stop is not SIGTERM"
exec_start=$(sed -n 's/^ExecStart=//p' "$unit")
[[ $exec_start == "$prefix/bin/oceand --config $prefix/etc/oceand/oceand.conf" ]] || fail "ExecStart: $exec_start"
if command -v systemd-analyze >/dev/null; then
    systemd-analyze verify "$unit" >"$tmp/verify.log" 2>&1 || fail "systemd-analyze verify: $(cat "$tmp/verify.log")"
fi
# shellcheck disable=SC2086
start_daemon "$tmp/d2.log" $exec_start --port 0 --scene storm
check_serves "unit ExecStart"
kill -HUP "$dpid"
for _ in $(seq 100); do grep -q "configuration reloaded" "$tmp/d2.log" && break; sleep 0.05; done
grep -q "configuration reloaded" "$tmp/d2.log" || fail "SIGHUP did not reload: $(cat "$tmp/d2.log")"
stop_daemon "unit"

echo "== DESTDIR staging ($SECONDS s)"
mk install DESTDIR="$tmp/stage" PREFIX=/opt/oceand >"$tmp/install2.log" 2>&1 || { tail -20 "$tmp/install2.log"; fail "make install DESTDIR"; }
[[ -x $tmp/stage/opt/oceand/bin/oceand ]] || fail "DESTDIR: no bin/oceand"
grep -q '^prefix=/opt/oceand$' "$tmp/stage/opt/oceand/lib/pkgconfig/oceanclient.pc" || fail "DESTDIR leaked into the .pc"
grep -qx 'server.web_root = /opt/oceand/share/oceand/web' "$tmp/stage/opt/oceand/etc/oceand/oceand.conf" || fail "DESTDIR: config web_root"
"$tmp/stage/opt/oceand/bin/oceand" --help | grep -q "web viewer /opt/oceand/share/oceand/web" || fail "DESTDIR: compiled-in data dir"
echo "ok ($SECONDS s)"
