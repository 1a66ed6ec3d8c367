/*
 * test_pcap.c - datagrams to pcap and back through tshark (see test_pcap.h).
 */
#include "test_pcap.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

FILE *test_pcap_open(char *path)
{
    strcpy(path, "/tmp/oceand_pcap_XXXXXX");
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    FILE *f = fdopen(fd, "wb");
    assert_non_null(f);
    /* pcap global header: magic, v2.4, no zone, snaplen 65535, LINKTYPE_RAW */
    static const uint8_t h[24] = {0xD4, 0xC3, 0xB2, 0xA1, 2, 0, 4, 0, 0, 0, 0, 0, 0, 0, 0, 0,
                                  0xFF, 0xFF, 0, 0, 101, 0, 0, 0};
    assert_int_equal(fwrite(h, 1, sizeof h, f), sizeof h);
    return f;
}

void test_pcap_datagram(FILE *f, int from_ig, const uint8_t *d, size_t n)
{
    uint8_t rec[16] = {0}, ip[20] = {0x45, 0}, udp[8];
    size_t total = 28 + n;
    assert_true(total <= 65535);
    rec[8] = rec[12] = (uint8_t)total, rec[9] = rec[13] = (uint8_t)(total >> 8);
    ip[2] = (uint8_t)(total >> 8), ip[3] = (uint8_t)total, ip[8] = 64, ip[9] = 17;
    static const uint8_t host[4] = {127, 0, 0, 1}, ig[4] = {127, 0, 0, 2};
    memcpy(ip + 12, from_ig ? ig : host, 4);
    memcpy(ip + 16, from_ig ? host : ig, 4);
    unsigned sp = from_ig ? 8005 : 8004, dp = from_ig ? 8004 : 8005, ul = (unsigned)(8 + n);
    const uint8_t u[8] = {(uint8_t)(sp >> 8), (uint8_t)sp, (uint8_t)(dp >> 8), (uint8_t)dp,
                          (uint8_t)(ul >> 8), (uint8_t)ul, 0, 0};
    memcpy(udp, u, 8);
    assert_int_equal(fwrite(rec, 1, 16, f), 16);
    assert_int_equal(fwrite(ip, 1, 20, f), 20);
    assert_int_equal(fwrite(udp, 1, 8, f), 8);
    assert_int_equal(fwrite(d, 1, n, f), n);
}

cJSON *test_pcap_tshark(FILE *f, const char *path)
{
    assert_int_equal(fclose(f), 0);
    if (system("command -v tshark > /dev/null 2>&1") != 0) fail_msg("tshark not installed (.ci/deps.sh test)");
    char cmd[300];
    snprintf(cmd, sizeof cmd, "tshark -r %s -T json --no-duplicate-keys 2>/dev/null", path);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    size_t cap = 4 << 20, len = 0, got;
    char *out = malloc(cap);
    assert_non_null(out);
    while (len < cap - 1 && (got = fread(out + len, 1, cap - 1 - len, p)) > 0) len += got;
    out[len] = 0;
    assert_int_equal(pclose(p), 0);
    unlink(path);
    if (strstr(out, "Malformed") || strstr(out, "_ws.expert")) fail_msg("tshark: malformed or expert info: %.300s", out);
    cJSON *js = cJSON_Parse(out);
    if (!js) fail_msg("tshark's JSON does not parse: %.200s", out);
    free(out);
    return js;
}

const cJSON *test_pcap_cigi(const cJSON *frames, int i)
{
    const cJSON *src = cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(frames, i), "_source");
    const cJSON *cigi = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(src, "layers"), "cigi");
    if (!cigi) fail_msg("tshark did not read frame %d as CIGI", i + 1);
    return cigi;
}
