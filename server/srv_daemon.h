/*
 * srv_daemon.h - the whole daemon as one object: hub, simulation thread and
 * service thread.  build/oceand's main() and the integration tests use the
 * same calls, so the tests exercise the daemon itself in-process.
 */
#ifndef SRV_DAEMON_H
#define SRV_DAEMON_H

#include "srv_client.h"
#include "srv_config.h"

typedef struct srv_daemon srv_daemon;

/* Builds the ocean, listens, and starts both threads.  *out is NULL on
 * failure; msg says why. */
ocean_result srv_daemon_start(const srv_settings *s, srv_daemon **out, char *msg, size_t msglen);
/* The TCP port listened on (useful with server.port = 0). */
int srv_daemon_port(const srv_daemon *d);
srv_hub *srv_daemon_hub(srv_daemon *d);
/* Applies reloaded settings (SIGHUP): limits, rates, token, recording at
 * once; a changed sea or ocean takes effect at the next tick through a new
 * ocean announced to every client, once it has been built here (a sea that
 * cannot be built is not applied, and msg says why).  Port, bind address,
 * web root and workers need a restart; msg lists any such key that
 * changed. */
ocean_result srv_daemon_reload(srv_daemon *d, const srv_settings *s, char *msg, size_t msglen);
/* Sends every client BYE (shutdown) with a close reason, stops the threads
 * and frees everything.  Accepts NULL. */
void srv_daemon_stop(srv_daemon *d);

#endif
