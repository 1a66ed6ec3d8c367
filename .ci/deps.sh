#!/usr/bin/env bash
# Installs the Debian packages oceand needs that are missing.  Idempotent and
# quick when everything is present (one dpkg-query, no network).
set -euo pipefail
pkgs=(gcc make clang lld wasi-libc pkg-config libclang-rt-14-dev
      libwebsockets-dev libopenexr-dev libfftw3-dev libzstd-dev libcjson-dev
      librandom123-dev libcmocka-dev libwslay-dev gnuplot-nox openexr chromium
      curl python3 haproxy redis-server libhiredis-dev)
missing=()
for p in "${pkgs[@]}"; do
    st=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
    [[ "$st" == "install ok installed" ]] || missing+=("$p")
done
# Node.js may come from elsewhere than Debian (an image's own node and npm
# conflict with Debian's npm package): only install it when absent.
command -v node >/dev/null 2>&1 || missing+=(nodejs)
command -v npm >/dev/null 2>&1 || missing+=(npm)
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
if [[ -f tests/browser/package.json && ! -d tests/browser/node_modules/playwright-core ]]; then
    (cd tests/browser && npm ci --no-audit --no-fund --loglevel=error)
fi
