/*
 * srv_net.h - the libwebsockets side of the daemon: one service thread owns
 * every connection.  It serves the protocol "ocean.v1" on WebSocket, the
 * browser viewer (server.web_root) at /, Prometheus text at /metrics and a
 * JSON summary at /status.
 *
 * The simulation thread never touches a connection: it fills a client's
 * queues and calls srv_hub_wake_net (lws_cancel_service); the service
 * thread then asks for LWS_CALLBACK_SERVER_WRITEABLE on every client with
 * bytes waiting and writes one message per callback.  Output limits (soft /
 * hard, as redis' client-output-buffer-limit) are checked on every wake.
 */
#ifndef SRV_NET_H
#define SRV_NET_H

#include "srv_client.h"

typedef struct srv_net srv_net;

/* Creates the lws context and listens (port 0: a free port). */
ocean_result srv_net_create(srv_hub *h, srv_net **out, char *msg, size_t msglen);
/* The port actually listened on. */
int srv_net_port(const srv_net *n);
/* Starts the service thread. */
ocean_result srv_net_start(srv_net *n);
/* Graceful stop: every client gets BYE (shutdown) and a close reason, then
 * the thread ends (at most `grace` seconds later).  Blocks until it has. */
void srv_net_stop(srv_net *n, double grace);
void srv_net_destroy(srv_net *n);  /* stops first; accepts NULL */

#endif
