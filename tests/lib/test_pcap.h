/*
 * test_pcap.h - datagrams written as a pcap file (raw IPv4/UDP, link type
 * 101) and read back by Debian's tshark, an independent dissector: the
 * CIGI tests hand it every byte they and the daemon write.
 *
 * For cmocka test programs only: the helpers assert.
 */
#ifndef TEST_PCAP_H
#define TEST_PCAP_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include <cJSON.h>

/* Opens a new pcap file at a temporary path (path gets it: 32 bytes). */
FILE *test_pcap_open(char *path);
/* One UDP datagram, host 127.0.0.1:8004 to IG 127.0.0.2:8005 (from_ig 0)
 * or back (from_ig 1). */
void test_pcap_datagram(FILE *f, int from_ig, const uint8_t *d, size_t n);
/* Closes f, runs `tshark -T json` on path, removes it and returns the
 * parsed array of frames (cJSON_Delete it); asserts tshark ran, reported
 * nothing malformed and no expert info. */
cJSON *test_pcap_tshark(FILE *f, const char *path);
/* Frame i's "cigi" layer, asserted present. */
const cJSON *test_pcap_cigi(const cJSON *frames, int i);

#endif
