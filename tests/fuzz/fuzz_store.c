/*
 * fuzz_store.c - libFuzzer target for the frame-store reader (clients/c
 * oc_store.h: the files `ocean-client record` and `replay` write and
 * `replay --check` reads back, which may come from anyone).
 *
 * The input is the file's bytes, given to the reader through a memfd.
 * Checks beyond "no crash, no sanitizer report":
 *   - the reader ends with OCEAN_ENOTFOUND (clean end) or a damage code
 *     (ETRUNC, EFORMAT, EVERSION, ETOOBIG) whose message is not empty;
 *   - every record it hands out lies within the input: length >= 32 (a
 *     message header) and the records' bytes add up to no more than the
 *     file holds, recv_time is what the file says (any double);
 *   - a readable store compares identical to itself, and the compare of a
 *     damaged one fails with the reader's code, not a verdict.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "oc_store.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    int fd = memfd_create("fuzz_store", MFD_CLOEXEC);
    if (fd < 0)
        return 0;
    if (size && write(fd, data, size) != (ssize_t)size) {
        close(fd);
        return 0;
    }
    char path[64], err[256] = "";
    snprintf(path, sizeof path, "/proc/self/fd/%d", fd);
    oc_store_reader *r = NULL;
    ocean_result res = oc_store_reader_open(path, &r, err, sizeof err);
    if (res != OCEAN_OK) {
        if (r != NULL || !err[0])
            abort();
        close(fd);
        return 0;
    }
    size_t total = OC_STORE_HEADER;
    int readable = 1;
    for (;;) {
        const uint8_t *msg = NULL;
        size_t len = 0;
        double t;
        err[0] = 0;
        res = oc_store_reader_next(r, &msg, &len, &t, err, sizeof err);
        if (res == OCEAN_ENOTFOUND)
            break;
        if (res != OCEAN_OK) {
            if (!err[0] || (res != OCEAN_ETRUNC && res != OCEAN_EFORMAT && res != OCEAN_ETOOBIG &&
                            res != OCEAN_ENOMEM && res != OCEAN_EIO))
                abort();
            readable = 0;
            break;
        }
        total += OC_STORE_RECORD_HEAD + len;
        if (!msg || len < 32 || total > size)
            abort();
        /* the bytes are the file's: read them all */
        if (memcmp(msg, data + total - len, len) != 0)
            abort();
    }
    oc_store_reader_close(r);
    oc_store_diff d;
    res = oc_store_compare(path, path, OC_STORE_COMPARE_DEFAULT, &d, err, sizeof err);
    if (readable ? (res != OCEAN_OK || !d.identical) : res == OCEAN_OK)
        abort();
    close(fd);
    return 0;
}
