/*
 * srv_sim.h - the simulation thread: one clock, one ocean, frames for every
 * subscribed client.
 *
 * Per tick it evaluates only the union of what live subscriptions need: one
 * evaluation per (time, cutoff bucket, boost, cascades) with the union of
 * their effects on the cascades asked for; tiles from the shared tile cache;
 * per client only the mesh and the FRAME assembly.  With nobody subscribed
 * it sleeps.  Replay-mode clients name the time of each frame (evaluated on
 * demand, cached within the batch); queries are answered from a frame
 * evaluated with OCEAN_QUERY_EFFECTS, only when queries are pending.
 * Sea-state changes take effect at their stated sim time with a new ocean.
 */
#ifndef SRV_SIM_H
#define SRV_SIM_H

#include "ocean_result.h"
#include "srv_client.h"

typedef struct srv_sim srv_sim;

/* Builds the ocean (and near field) of the hub's settings.  msg gets the
 * reason on failure. */
ocean_result srv_sim_create(srv_hub *h, srv_sim **out, char *msg, size_t msglen);
/* Starts the thread. */
ocean_result srv_sim_start(srv_sim *s);
/* Asks the thread to stop and joins it. */
void srv_sim_stop(srv_sim *s);
void srv_sim_destroy(srv_sim *s);  /* stops first; accepts NULL */
/* Builds, then frees, the ocean (and near field) that settings s with sea
 * p would run, as the simulation thread builds it when p takes effect:
 * OCEAN_OK, or why it cannot be built (a wisdom file without the plans
 * of p's grid, memory) in msg.  For a sea about to be announced to every
 * client, so none is told of a sea this daemon would not serve.  Any
 * thread; takes about as long as the ocean's start. */
ocean_result srv_sim_sea_check(const srv_settings *s, const ocean_params *p, char *msg, size_t msglen);

#endif
