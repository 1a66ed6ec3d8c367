/*
 * fuzz_cigi.c - libFuzzer target for the CIGI packet reader (protocol/cigi.h),
 * what the daemon's CIGI service does with every datagram a host sends.
 *
 * Checks beyond "no crash, no sanitizer report":
 *   - a message is framed (cigi_format_of) or refused with a reason;
 *   - the reader ends, each packet within the datagram, each error with a
 *     reason;
 *   - every packet read re-encodes in the message's format (its integers
 *     fit their fields by construction) and reads back as the same kind;
 *   - cigi_packet_check accepts or refuses with a reason, never crashes.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cigi.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    cigi_format f;
    char why[256];
    why[0] = 0;
    if (cigi_format_of(data, size, &f, why, sizeof why) != OCEAN_OK) {
        if (!why[0]) abort();
        return 0;
    }
    cigi_reader r;
    cigi_reader_init(&r, data, size, &f);
    proto_buf b;
    proto_buf_init(&b, 0);
    for (int guard = 0; guard < 70000; guard++) {
        cigi_packet p;
        int done;
        why[0] = 0;
        if (cigi_reader_next(&r, &p, &done, why, sizeof why) != OCEAN_OK) {
            if (!why[0]) abort();
            break;
        }
        if (done) break;
        if (p.size == 0 || p.size % 8) abort();
        why[0] = 0;
        if (cigi_packet_check(&p, why, sizeof why) != OCEAN_OK && !why[0]) abort();
        if (p.kind == CIGI_UNKNOWN) continue;
        proto_buf_reset(&b);
        if (cigi_put(&b, &f, &p) != OCEAN_OK) abort();
        cigi_reader back;
        cigi_reader_init(&back, proto_buf_data(&b), proto_buf_len(&b), &f);
        cigi_packet q;
        if (cigi_reader_next(&back, &q, &done, why, sizeof why) != OCEAN_OK || done || q.kind != p.kind) abort();
    }
    proto_buf_free(&b);
    return 0;
}
