/*
 * srv_convert.c - the protocol's types as the simulation's and back (see
 * srv_convert.h).
 */
#include "srv_convert.h"

#include <math.h>
#include <string.h>

void srv_sea_from_params(const ocean_params *p, proto_sea *o)
{
    memset(o, 0, sizeof *o);
    o->spectrum = (uint8_t)p->sea.spectrum;
    o->spreading = (uint8_t)p->sea.spreading;
    o->seed = p->seed;
    o->wind_u10 = p->sea.wind_u10;
    o->wind_dir_deg = p->sea.wind_dir_deg;
    o->fetch_m = p->sea.fetch_m;
    o->depth_m = p->sea.depth_m;
    o->swell = p->sea.swell;
    o->phillips_a = p->sea.phillips_a;
    o->small_wave_m = p->sea.small_wave_m;
    o->choppiness = p->sea.choppiness;
    o->flags = p->sea.whitecaps ? 0 : PROTO_SEA_NO_WHITECAPS;
    double hs = ocean_spectrum_hs(&p->sea);
    double wp = ocean_spectrum_peak(&p->sea);
    o->hs = isfinite(hs) && hs >= 0 && hs <= 1000 ? hs : 0;
    o->tp = wp > 0 && 2 * M_PI / wp <= 1e4 ? 2 * M_PI / wp : 0;
}

void srv_params_from_sea(const proto_sea *s, const ocean_params *base, ocean_params *o)
{
    *o = *base;
    o->sea.spectrum = (ocean_spectrum_kind)s->spectrum;
    o->sea.spreading = (ocean_spreading_kind)s->spreading;
    o->seed = s->seed;
    o->sea.wind_u10 = s->wind_u10;
    o->sea.wind_dir_deg = s->wind_dir_deg;
    o->sea.fetch_m = s->fetch_m;
    o->sea.depth_m = s->depth_m;
    o->sea.swell = s->swell;
    o->sea.phillips_a = s->phillips_a;
    o->sea.small_wave_m = s->small_wave_m;
    o->sea.choppiness = s->choppiness;
    o->sea.whitecaps = !(s->flags & PROTO_SEA_NO_WHITECAPS);
}

void srv_mesh_camera(const proto_camera *pc, mesh_camera *c)
{
    mesh_camera_default(c);
    for (int i = 0; i < 3; i++) c->pos[i] = pc->pos[i];
    c->yaw_deg = pc->yaw_deg;
    c->pitch_deg = pc->pitch_deg;
    c->roll_deg = pc->roll_deg;
    c->fov_y_deg = pc->fov_y_deg;
    c->viewport_w = pc->viewport_w;
    c->viewport_h = pc->viewport_h;
}

void srv_sea_announce(const proto_sea *sea, double eff, double now, proto_msg *out)
{
    proto_msg_init(out, PROTO_SEA_STATE);
    out->hdr.sim_time = now;
    out->u.sea_state.op = PROTO_SEA_ANNOUNCE;
    out->u.sea_state.effective_time = eff;
    out->u.sea_state.sea = *sea;
}

void srv_entity_from_msg(const proto_entity *e, ocean_entity_desc *d, ocean_track_sample *s)
{
    *d = (ocean_entity_desc){.id = e->id, .kind = (ocean_entity_kind)e->kind, .length_m = e->length_m,
                             .beam_m = e->beam_m, .draught_m = e->draught_m};
    *s = (ocean_track_sample){.t = e->t, .x = e->x, .z = e->z, .altitude_m = e->altitude_m,
                              .heading_deg = e->heading_deg, .speed = e->speed};
}

void srv_entity_msg(unsigned op, const ocean_entity_desc *d, const ocean_track_sample *s, double from, proto_msg *out)
{
    proto_msg_init(out, PROTO_ENTITY);
    out->hdr.sim_time = from;
    proto_entity *e = &out->u.entity;
    e->op = (uint8_t)op;
    e->id = d->id;
    if (op != PROTO_ENTITY_ANNOUNCE) return;
    e->kind = (uint8_t)d->kind;
    e->length_m = (float)d->length_m;
    e->beam_m = (float)d->beam_m;
    e->draught_m = (float)d->draught_m;
    e->t = s->t;
    e->x = s->x;
    e->z = s->z;
    e->altitude_m = (float)s->altitude_m;
    e->heading_deg = (float)s->heading_deg;
    e->speed = (float)s->speed;
}
