/*
 * srv_handle.h - what oceand does with each message a client sends (see
 * srv_handle.c).  Service thread only.
 */
#ifndef SRV_HANDLE_H
#define SRV_HANDLE_H

#include <stddef.h>
#include <stdint.h>

#include "srv_session.h"

/* Handles one complete binary message from the client. */
void srv_handle(srv_session *s, const uint8_t *buf, size_t len);
/* Handles one complete text message (not part of ocean.v1): counts against
 * the message rate like any message, answered by at most one ERROR a
 * second. */
void srv_handle_text(srv_session *s);

#endif
