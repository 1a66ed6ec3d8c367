#!/usr/bin/env bash
# Installs the Debian packages oceand needs that are missing.  Idempotent and
# quick when everything is present (one dpkg-query, no network).
#   usage: .ci/deps.sh [run|bench|test]
#   run    what building and running needs (make, make run): compilers, the
#          libraries, clang/lld/wasi-libc and compiler-rt's wasm32 builtins
#          (clang links them into every wasm32-wasi program) for the viewer's WebAssembly
#          decoders; no npm, so an air-gapped lab with a Debian mirror can run it
#   bench  + the tools the benchmarks drive (make bench)
#   test   + the browser test's Chromium and its npm driver, and tshark (the
#          independent reader of the CIGI packets test_cigi writes) (make test)
set -euo pipefail
what=${1:-run}
pkgs=(gcc make clang lld wasi-libc libclang-rt-14-dev-wasm32 pkg-config libclang-rt-14-dev
      libwebsockets-dev libopenexr-dev libfftw3-dev libzstd-dev libcjson-dev
      librandom123-dev libcmocka-dev libwslay-dev libhiredis-dev libpng-dev libproj-dev)
case "$what" in
run) ;;
bench|test) pkgs+=(gnuplot-nox openexr chromium curl python3 haproxy redis-server tshark) ;;
*) echo "deps: unknown set '$what' (run, bench or test)" >&2; exit 2 ;;
esac
missing=()
for p in "${pkgs[@]}"; do
    st=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
    [[ "$st" == "install ok installed" ]] || missing+=("$p")
done
# Node.js may come from elsewhere than Debian (an image's own node and npm
# conflict with Debian's npm package): only install it when absent.
if [[ $what == test ]]; then
    command -v node >/dev/null 2>&1 || missing+=(nodejs)
    command -v npm >/dev/null 2>&1 || missing+=(npm)
fi
if ((${#missing[@]})); then
    echo "deps: installing ${missing[*]}" >&2
    if [[ $(id -u) -ne 0 ]]; then
        echo "deps: missing packages and not root; run: sudo apt-get install ${missing[*]}" >&2
        exit 1
    fi
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
# The browser test's driver comes from npm (pinned in tests/browser/package.json;
# kept out of clients/web/ so the daemon never serves node_modules).
if [[ $what == test && -f tests/browser/package.json && ! -d tests/browser/node_modules/playwright-core ]]; then
    (cd tests/browser && npm ci --no-audit --no-fund --loglevel=error)
fi
