/*
 * srv_seabuild.c - sea changes' oceans built ahead (see srv_seabuild.h).
 *
 * One request (the change wanted next) and one finished build (its
 * result, kept until taken or until another change is wanted): at most
 * two oceans besides the one in force.
 *
 * Oceans the simulation thread is done with are freed here too: freeing
 * one takes FFTW's planner lock (ocean_fft_free), which a build holds
 * while it plans, and the builder runs at nice 10: on a busy host the
 * thread that serves clients would wait for a starved background thread.
 *
 * OOM policy: a build that runs out of memory is a failed build, taken as
 * such (the simulation thread keeps the sea in force and says so); an
 * ocean to free that finds no memory for its list node is freed where it
 * was handed over.
 */
#include "srv_seabuild.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "ocean_plan.h"
#include "srv_hub.h"

ocean_result srv_sea_ocean_build(const srv_settings *s, const ocean_params *p, int say_plan, srv_sea_ocean *out,
                                 char *msg, size_t msglen)
{
    memset(out, 0, sizeof *out);
    ocean_result r = ocean_create(p, &out->oc, msg, msglen);
    if (r != OCEAN_OK) return r;
    /* The scene plan's warnings go to the log (its refusals stopped
     * ocean_create); the near field and spacing are what this daemon serves. */
    ocean_plan plan;
    ocean_plan_init(&plan);
    ocean_plan_params(p, &plan);
    double patch, klo, khi;
    ocean_cascade_band(out->oc, p->cascades - 1, &patch, &klo, &khi);
    ocean_plan_serving sv = {(s->effects & OCEAN_FX_NEAR_FIELD) && s->srv.near_field_waves > 0, khi,
                             2 * M_PI / s->srv.near_field_min_wavelength};
    ocean_plan_ocean(out->oc, &sv, &plan);
    if (say_plan) ocean_plan_print(&plan, stderr, "oceand: scene plan");
    ocean_gerstner_params gp;
    if (srv_settings_near_field(s, p, &gp)) {
        gp.k_lo = khi; /* = p->k_max: the finest cascade's edge */
        r = ocean_gerstner_create(&gp, &out->g, msg, msglen);
        if (r == OCEAN_OK) r = ocean_gerstner_cascade_create(out->g, p, &out->nf, msg, msglen);
        if (r != OCEAN_OK) srv_sea_ocean_free(out);
    }
    return r;
}

void srv_sea_ocean_free(srv_sea_ocean *o)
{
    ocean_destroy(o->nf);
    ocean_gerstner_destroy(o->g);
    ocean_destroy(o->oc);
    memset(o, 0, sizeof *o);
}

/* An ocean waiting for the builder to free it. */
typedef struct trash_node {
    srv_sea_ocean o;
    struct trash_node *next;
} trash_node;

/* Which change a build is for. */
typedef struct build_key {
    uint64_t set_gen;
    double eff;
    ocean_params params;
} build_key;

struct srv_seabuild {
    pthread_t thread;
    int started;
    pthread_mutex_t lock;
    pthread_cond_t cond;
    /* below: [lock] */
    int stop;
    int wanted;              /* want holds a change to build */
    build_key want;
    srv_settings want_set;
    int building;            /* the thread builds `doing` */
    build_key doing;
    int done;                /* `result` and `built` are the build of done_key */
    build_key done_key;
    ocean_result result;
    srv_sea_ocean built;
    double built_s;          /* wall seconds the build took (the thread's priority included) */
    char why[256];
    trash_node *trash;       /* oceans to free */
};

static int key_eq(const build_key *a, const build_key *b)
{
    return a->set_gen == b->set_gen && a->eff == b->eff && memcmp(&a->params, &b->params, sizeof a->params) == 0;
}

static void key_make(build_key *k, uint64_t set_gen, const ocean_params *p, double eff)
{
    memset(k, 0, sizeof *k);  /* padding too: keys are compared whole */
    k->set_gen = set_gen;
    k->eff = eff;
    k->params = *p;
}

/* Frees a list of oceans (no lock held). */
static void trash_free(trash_node *t)
{
    while (t) {
        trash_node *next = t->next;
        srv_sea_ocean_free(&t->o);
        free(t);
        t = next;
    }
}

/* Waits for work (lock held): 1 a change to build (into *k, *s), -1
 * oceans to free (the list taken into *t), 0 asked to stop. */
static int next_job(srv_seabuild *b, build_key *k, srv_settings *s, trash_node **t)
{
    while (!b->stop && !b->trash && !(b->wanted && !(b->done && key_eq(&b->done_key, &b->want))))
        pthread_cond_wait(&b->cond, &b->lock);
    if (b->stop) return 0;
    if (b->trash) {
        *t = b->trash;
        b->trash = NULL;
        return -1;
    }
    *k = b->want;
    *s = b->want_set;
    b->building = 1;
    b->doing = *k;
    return 1;
}

static void *builder(void *arg)
{
    srv_seabuild *b = arg;
    /* a build is background work: the threads that serve clients go first
     * (Linux: a thread's nice value is its own, and the threads it starts
     * inherit it) */
    if (setpriority(PRIO_PROCESS, (id_t)syscall(SYS_gettid), 10) != 0) {}
    build_key k;
    srv_settings *s = malloc(sizeof *s);
    trash_node *t = NULL;
    int job;
    pthread_mutex_lock(&b->lock);
    while (s && (job = next_job(b, &k, s, &t)) != 0) {
        pthread_mutex_unlock(&b->lock);
        if (job < 0) {
            trash_free(t);
            pthread_mutex_lock(&b->lock);
            continue;
        }
        srv_sea_ocean o;
        char why[256] = "";
        double t0 = srv_now();
        ocean_result r = srv_sea_ocean_build(s, &k.params, 1, &o, why, sizeof why);
        double took = srv_now() - t0;
        srv_sea_ocean stale = {0};
        pthread_mutex_lock(&b->lock);
        b->building = 0;
        stale = b->built;
        b->built = o;
        b->result = r;
        b->done = 1;
        b->built_s = took;
        b->done_key = k;
        snprintf(b->why, sizeof b->why, "%s", why);
        pthread_cond_broadcast(&b->cond);
        pthread_mutex_unlock(&b->lock);
        srv_sea_ocean_free(&stale);
        pthread_mutex_lock(&b->lock);
    }
    pthread_mutex_unlock(&b->lock);
    free(s);
    return NULL;
}

ocean_result srv_seabuild_create(srv_seabuild **out)
{
    srv_seabuild *b = calloc(1, sizeof *b);
    if (!b) return OCEAN_ENOMEM;
    pthread_mutex_init(&b->lock, NULL);
    pthread_cond_init(&b->cond, NULL);
    if (pthread_create(&b->thread, NULL, builder, b) != 0) {
        srv_seabuild_destroy(b);
        return OCEAN_ENOMEM;
    }
    b->started = 1;
    *out = b;
    return OCEAN_OK;
}

void srv_seabuild_destroy(srv_seabuild *b)
{
    if (!b) return;
    if (b->started) {
        pthread_mutex_lock(&b->lock);
        b->stop = 1;
        pthread_cond_broadcast(&b->cond);
        pthread_mutex_unlock(&b->lock);
        pthread_join(b->thread, NULL);
    }
    trash_free(b->trash);
    srv_sea_ocean_free(&b->built);
    pthread_cond_destroy(&b->cond);
    pthread_mutex_destroy(&b->lock);
    free(b);
}

void srv_seabuild_discard(srv_seabuild *b, srv_sea_ocean *o)
{
    if (!o->oc && !o->g && !o->nf) return;
    trash_node *t = malloc(sizeof *t);
    if (!t) {
        srv_sea_ocean_free(o);
        return;
    }
    t->o = *o;
    memset(o, 0, sizeof *o);
    pthread_mutex_lock(&b->lock);
    t->next = b->trash;
    b->trash = t;
    pthread_cond_broadcast(&b->cond);
    pthread_mutex_unlock(&b->lock);
}

void srv_seabuild_want(srv_seabuild *b, const srv_settings *s, uint64_t set_gen, const ocean_params *p,
                       double eff)
{
    build_key k;
    key_make(&k, set_gen, p, eff);
    srv_sea_ocean stale = {0};
    pthread_mutex_lock(&b->lock);
    if (!b->wanted || !key_eq(&b->want, &k)) {
        b->want = k;
        b->want_set = *s;
        b->wanted = 1;
        if (b->done && !key_eq(&b->done_key, &k)) {
            stale = b->built;
            memset(&b->built, 0, sizeof b->built);
            b->done = 0;
        }
        pthread_cond_broadcast(&b->cond);
    }
    pthread_mutex_unlock(&b->lock);
    srv_seabuild_discard(b, &stale);
}

ocean_result srv_seabuild_take(srv_seabuild *b, const srv_settings *s, uint64_t set_gen, const ocean_params *p,
                               double eff, srv_sea_ocean *out, int *ahead, double *seconds, char *msg,
                               size_t msglen)
{
    build_key k;
    key_make(&k, set_gen, p, eff);
    pthread_mutex_lock(&b->lock);
    /* a change asked for ahead is the thread's to build: wait for it
     * (behind a build of a change no longer wanted, at most) */
    while (!b->stop && ((b->building && key_eq(&b->doing, &k)) ||
                        (b->wanted && key_eq(&b->want, &k) && !(b->done && key_eq(&b->done_key, &k)))))
        pthread_cond_wait(&b->cond, &b->lock);
    if (b->wanted && key_eq(&b->want, &k)) b->wanted = 0;  /* taken now, not built again */
    if (b->done && key_eq(&b->done_key, &k)) {
        ocean_result r = b->result;
        *out = b->built;
        memset(&b->built, 0, sizeof b->built);
        b->done = 0;
        if (msg && msglen) snprintf(msg, msglen, "%s", b->why);
        *seconds = b->built_s;
        pthread_mutex_unlock(&b->lock);
        *ahead = 1;
        return r;
    }
    pthread_mutex_unlock(&b->lock);
    *ahead = 0;
    double t0 = srv_now();
    ocean_result r = srv_sea_ocean_build(s, p, 1, out, msg, msglen);
    *seconds = srv_now() - t0;
    return r;
}
