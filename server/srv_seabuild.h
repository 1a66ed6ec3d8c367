/*
 * srv_seabuild.h - the ocean a sea change needs, built ahead, off the tick
 * path.
 *
 * An ocean is built when its change falls due: ocean_create plans FFTs and
 * fills the spectrum's tables (tens of milliseconds for the shipped scenes,
 * seconds for a large grid or FFTW's measuring planner), and the near field
 * is made beside it.  Built by the simulation thread at that tick it would
 * hold every client's frames for as long.  So the simulation thread names
 * the change it will need next (srv_seabuild_want) and this module's thread
 * builds it, at a lower priority than the threads that serve clients; when
 * the change falls due the simulation thread takes the built ocean
 * (srv_seabuild_take), waiting only for what is left of a build under way,
 * and building it itself only when it was never asked for ahead.
 *
 * The builder also frees the oceans the simulation thread is done with
 * (srv_seabuild_discard): freeing one takes FFTW's planner lock, which a
 * build holds while it plans, at its lower priority.
 *
 * Threads: want, take and discard from the simulation thread; the builder
 * thread owns the build in progress; the request, the finished build and
 * the oceans to free are under the module's lock.
 */
#ifndef SRV_SEABUILD_H
#define SRV_SEABUILD_H

#include <stdint.h>

#include "gerstner.h"
#include "ocean.h"
#include "srv_config.h"

/* What one sea runs on. */
typedef struct srv_sea_ocean {
    ocean *oc;
    ocean_gerstner *g;   /* the near field, or NULL */
    ocean *nf;           /* the near field as a lattice cascade (layout 1), or NULL */
} srv_sea_ocean;

/* Builds the ocean settings s serve sea p with into *out (say_plan: the
 * scene plan's notes go to stderr): OCEAN_OK, or why not in msg with *out
 * empty.  Any thread. */
ocean_result srv_sea_ocean_build(const srv_settings *s, const ocean_params *p, int say_plan, srv_sea_ocean *out,
                                 char *msg, size_t msglen);
/* Frees what o holds and empties it.  Accepts NULL members. */
void srv_sea_ocean_free(srv_sea_ocean *o);

typedef struct srv_seabuild srv_seabuild;

/* Starts the builder thread. */
ocean_result srv_seabuild_create(srv_seabuild **out);
/* Stops the thread (after the build under way) and frees everything.
 * Accepts NULL. */
void srv_seabuild_destroy(srv_seabuild *b);

/* The change needed next: sea p under settings s (generation set_gen),
 * effective at eff.  A build for another change is dropped once done. */
void srv_seabuild_want(srv_seabuild *b, const srv_settings *s, uint64_t set_gen, const ocean_params *p,
                       double eff);
/* Hands *o to the builder thread to free, and empties it; returns at once
 * (freed here only when no memory is left for the hand-over). */
void srv_seabuild_discard(srv_seabuild *b, srv_sea_ocean *o);
/* The ocean of that change into *out: if it was asked for ahead, the
 * thread's build (*ahead 1), waited for if not done yet; else built here
 * (*ahead 0).  *seconds gets the wall time the build took (at the
 * builder's priority when ahead).  Results as srv_sea_ocean_build. */
ocean_result srv_seabuild_take(srv_seabuild *b, const srv_settings *s, uint64_t set_gen, const ocean_params *p,
                               double eff, srv_sea_ocean *out, int *ahead, double *seconds, char *msg,
                               size_t msglen);

#endif
