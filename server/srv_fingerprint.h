/*
 * srv_fingerprint.h - the daemon's determinism fingerprint: what, besides
 * the sea timeline, decides a FRAME's bytes, so two daemons whose
 * fingerprints agree serve the same bytes for the same requests.
 *
 * Threads: any (a pure function of its arguments and the build).
 */
#ifndef SRV_FINGERPRINT_H
#define SRV_FINGERPRINT_H

#include "srv_config.h"

/* The determinism fingerprint (16 hex digits + NUL into out): FNV-1a 64 of
 * everything besides the sea timeline that decides a FRAME's bytes: the
 * compiler, the CPU features that pick code paths (target_clones' avx2;
 * FFTW's SIMD: avx, avx2, fma, avx512f), the FFTW version, plan mode and
 * threads, and the configuration that shapes frames.  Announced in HELLO's
 * server_version (PROTOCOL.md "HELLO"). */
void srv_fingerprint(const srv_settings *s, char out[17]);

#endif
