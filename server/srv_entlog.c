/*
 * srv_entlog.c - the entities' timeline on disk (see srv_entlog.h).
 */
#include "srv_entlog.h"

#include <errno.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "proto_buf.h"
#include "srv_hub.h"

#define MAGIC "oceand entity log v1\n"
#define RECORD_MAX (1u << 16)   /* an ENTITY message is 96 + 256 bytes at most */

/* Entries are flushed to the file at least this often (and at close): a
 * 60 Hz host's entries cost no write each under hub.lock. */
#define FLUSH_EVERY_S 1.0

struct srv_entlog {
    pthread_mutex_t lock;
    FILE *f;                    /* [lock] NULL once a write failed */
    double flushed;             /* [lock] monotonic time of the last flush */
    char path[512];
};

ocean_result srv_entlog_open(const char *path, srv_entlog **out, char *why, size_t n)
{
    *out = NULL;
    srv_entlog *l = calloc(1, sizeof *l);
    if (!l) return OCEAN_ENOMEM;
    pthread_mutex_init(&l->lock, NULL);
    snprintf(l->path, sizeof l->path, "%s", path);
    l->f = fopen(path, "a+b");
    char head[sizeof MAGIC - 1];
    size_t got = l->f && fseek(l->f, 0, SEEK_SET) == 0 ? fread(head, 1, sizeof head, l->f) : 0;
    if (!l->f || (got && (got != sizeof head || memcmp(head, MAGIC, sizeof head)))) {
        snprintf(why, n, "server.entity_log %s: %s", path,
                 l->f ? "not an entity log (it does not begin with \"oceand entity log v1\")" : strerror(errno));
        srv_entlog_close(l);
        return OCEAN_EIO;
    }
    if (!got && (fputs(MAGIC, l->f) == EOF || fflush(l->f))) {
        snprintf(why, n, "server.entity_log %s: %s", path, strerror(errno));
        srv_entlog_close(l);
        return OCEAN_EIO;
    }
    *out = l;
    return OCEAN_OK;
}

void srv_entlog_close(srv_entlog *l)
{
    if (!l) return;
    if (l->f && fclose(l->f))
        fprintf(stderr, "oceand: server.entity_log %s: the last entries were not written: %s\n", l->path,
                strerror(errno));
    pthread_mutex_destroy(&l->lock);
    free(l);
}

/* One record's message entered into the hub; 1 when the table took it. */
static int record_enter(struct srv_hub *h, const uint8_t *b, size_t len)
{
    proto_msg m;
    char err[200];
    if (proto_decode(b, len, &m, err, sizeof err) != OCEAN_OK) return 0;
    int ok = m.hdr.type == PROTO_ENTITY &&
             (m.u.entity.op == PROTO_ENTITY_ANNOUNCE || m.u.entity.op == PROTO_ENTITY_GONE) &&
             srv_hub_entity_enter(h, &m, err, sizeof err) == OCEAN_OK;
    proto_msg_free(&m);
    return ok;
}

ocean_result srv_entlog_load(srv_entlog *l, struct srv_hub *h, int *entered, int *refused, char *why, size_t n)
{
    *entered = *refused = 0;
    uint8_t *b = malloc(RECORD_MAX);
    if (!b) return OCEAN_ENOMEM;
    long whole = (long)sizeof MAGIC - 1;   /* the end of the last whole record */
    ocean_result r = fseek(l->f, whole, SEEK_SET) == 0 ? OCEAN_OK : OCEAN_EIO;
    for (;;) {
        uint8_t len4[4];
        if (r != OCEAN_OK || fread(len4, 1, 4, l->f) != 4) break;
        uint32_t len = (uint32_t)len4[0] | (uint32_t)len4[1] << 8 | (uint32_t)len4[2] << 16 | (uint32_t)len4[3] << 24;
        if (len > RECORD_MAX || fread(b, 1, len, l->f) != len) break;
        if (record_enter(h, b, len)) ++*entered;
        else ++*refused;
        whole = ftell(l->f);
    }
    free(b);
    if (r == OCEAN_OK && ferror(l->f)) r = OCEAN_EIO;
    /* a record cut short ends the log: cut it off before appending */
    if (r == OCEAN_OK && (fflush(l->f) || ftruncate(fileno(l->f), whole))) r = OCEAN_EIO;
    if (r != OCEAN_OK) snprintf(why, n, "server.entity_log %s: %s", l->path, strerror(errno));
    return r;
}

void srv_entlog_append(srv_entlog *l, const proto_msg *m)
{
    proto_buf b;
    proto_buf_init(&b, 0);
    char err[200] = "";
    ocean_result r = proto_encode(&b, m, err, sizeof err);
    pthread_mutex_lock(&l->lock);
    if (l->f) {
        uint32_t len = (uint32_t)proto_buf_len(&b);
        uint8_t len4[4] = {(uint8_t)len, (uint8_t)(len >> 8), (uint8_t)(len >> 16), (uint8_t)(len >> 24)};
        double now = srv_now();
        int flush = now - l->flushed >= FLUSH_EVERY_S;
        if (flush) l->flushed = now;
        if (r != OCEAN_OK || fwrite(len4, 1, 4, l->f) != 4 || fwrite(proto_buf_data(&b), 1, len, l->f) != len ||
            (flush && fflush(l->f))) {
            fprintf(stderr, "oceand: server.entity_log %s: stopped: %s\n", l->path,
                    r != OCEAN_OK ? (err[0] ? err : ocean_strerror(r)) : strerror(errno));
            fclose(l->f);
            l->f = NULL;
        }
    }
    pthread_mutex_unlock(&l->lock);
    proto_buf_free(&b);
}
