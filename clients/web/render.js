/*
 * render.js - WebGL2 renderer of the streamed sea, for both layouts
 * (PROTOCOL.md "Layouts").
 *
 * Layout 1 (cascade tiles, the default): each cascade's mips live in two
 * mipmapped periodic textures (disp = DX, H, DZ; slope = ∂η/∂x, ∂η/∂z, and
 * the breaking index BI and its quadrature BQ, whose sum the frame's
 * whitecap table turns into foam);
 * the daemon's flat concentric mesh is placed per FRAME, morphed and
 * displaced in the vertex shader by the sum of the cascades read per "Where
 * each mip is read" (see CASCADE_GLSL, SEA1_VS); the fragment shader shades
 * from the summed slopes at the pixel's spacing and the unresolved slope
 * moments as a Beckmann lobe (SEA_SHADE_GLSL, Bruneton, Neyret & Holzschuch
 * 2010); the sky pass shades the sea beyond the mesh from the same cascades
 * with the same functions, only where the mesh did not draw.
 *
 * Layout 0 (world tiles): the daemon's concentric LOD mesh (indices once
 * per topology, positions every frame, relative to the frame origin in
 * double), displaced by the server; every tile level is packed by the
 * worker into one layer of two RGBA16F texture arrays, disp = (H, DX, DZ,
 * FOAM) and nrm = (normal xyz, coverage), blended fine to coarse with an
 * edge ramp and a footprint test so neither vertices nor normals alias.
 *
 * Precision: all positions are made relative to the eye on the CPU in
 * double (placement and frame origins, tile origins, the eye modulo each
 * cascade's patch), so the GPU only sees small float offsets however far
 * from the world origin the camera flies.
 *
 * Shading around the sea (seed 001's list): procedural sky (gradient, sun
 * disc and halo, drifting clouds) in a mipmapped cube map used as the
 * reflection environment, foam (layout 1: from the summed breaking index;
 * layout 0: the FOAM plane) broken up by drifting grain near the eye, cloud shadows, subsurface tint on crests,
 * haze.
 */

import { READ } from './protocol.js';

export const MAX_LEVELS = 16;
export const MAX_CASCADES = 4;
export const MIP_ENTRIES = 13;
export const FOAM_ROWS = 16;

const CLOUD_TEX = 512;          /* cloud texture size, texels */
const CLOUD_UV = 32;            /* noise lattice units the cloud texture spans (it tiles) */
const CLOUD_SCALE = 1 / 2500;   /* noise units per metre: cloud period CLOUD_UV / CLOUD_SCALE = 80 km */
const GRAIN_SCALE = 0.35;       /* foam grain: noise units per metre */
const SKY_CUBE = 128;           /* sky cube-map face size */

export const COMMON = `#version 300 es
precision highp float;
precision highp int;
precision highp sampler2DArray;
#define MAXL ${MAX_LEVELS}
uniform vec3 u_sunDir;
uniform vec3 u_sunColor;
uniform float u_time;
uniform vec2 u_cloudOff;    /* cloud texture offset of the eye (world, wind drift), texture units */
uniform vec2 u_grainOff;    /* foam grain texture offset of the eye, texture units */
uniform float u_eyeY;
uniform vec2 u_wind;        /* unit wind direction (x, z) */
uniform sampler2D u_cloudTex;
uniform samplerCube u_skyCube;
uniform float u_skyScale;   /* the cube map stores radiance / u_skyScale */

const float CLOUD_ALT = 2000.0;
const float CLOUD_K = ${CLOUD_SCALE / CLOUD_UV};
const float GRAIN_K = ${GRAIN_SCALE / CLOUD_UV};
/* cloud cover 0..1 at world xz given relative to the eye */
float clouds(vec2 relXZ) {
    float c = texture(u_cloudTex, relXZ * CLOUD_K + u_cloudOff).r;
    return smoothstep(0.48, 0.75, c);
}
/* the sun's halo at cosine sd of the angle from the sun */
vec3 skyHalo(float sd) {
    return u_sunColor * (0.25 * pow(sd, 8.0) + 0.45 * pow(sd, 64.0));
}
vec3 skyGradient(float y) {
    return mix(vec3(0.55, 0.68, 0.82), vec3(0.09, 0.25, 0.60), pow(max(y, 0.0), 0.45));
}
vec3 skyBase(vec3 d) {
    return skyGradient(d.y) + skyHalo(max(dot(d, u_sunDir), 0.0));
}
/* full sky (gradient, halo, clouds) in direction d; used to fill the cube map */
vec3 skyFull(vec3 d) {
    vec3 c = skyBase(d);
    if (d.y > 0.01) {
        float t = (CLOUD_ALT - u_eyeY) / d.y;
        if (t > 0.0) {
            float cl = clouds(d.xz * t);
            float lit = 0.78 + 0.3 * pow(max(dot(d, u_sunDir), 0.0), 4.0);
            float fade = smoothstep(0.01, 0.2, d.y);
            c = mix(c, vec3(0.92, 0.93, 0.95) * lit, cl * fade * 0.85);
        }
    }
    return c;
}
/* the sky as the sea reflects it: the cube map, upper hemisphere */
vec3 skyEnv(vec3 d) {
    return texture(u_skyCube, vec3(d.x, abs(d.y), d.z)).rgb * u_skyScale;
}
vec3 sunDisc(vec3 d) {
    float sd = dot(d, u_sunDir);
    return u_sunColor * 40.0 * smoothstep(0.99985, 0.99995, sd);
}
const vec3 WATER_DEEP = vec3(0.004, 0.028, 0.058);
const vec3 WATER_SCATTER = vec3(0.02, 0.21, 0.22);
/* shading of the sea surface seen along view dir V (from eye), normal N */
vec3 seaColor(vec3 V, vec3 N, float crest, float foam, float shadow, float roughness) {
    vec3 toEye = -V;
    float ndv = max(dot(N, toEye), 0.0);
    float F = 0.02 + 0.98 * pow(1.0 - ndv, 5.0);
    vec3 R = reflect(V, N);
    vec3 refl = skyEnv(R);
    float sunUp = clamp(u_sunDir.y * 2.0, 0.05, 1.0);
    vec3 water = WATER_DEEP * sunUp;
    /* light scattered in wave crests, strongest looking toward the sun */
    float sss = pow(max(dot(V, u_sunDir) * 0.5 + 0.5, 0.0), 3.0) * clamp(crest, 0.0, 1.0);
    water += WATER_SCATTER * sss * sunUp * 0.6;
    water += WATER_SCATTER * 0.06 * max(dot(N, u_sunDir), 0.0);
    vec3 col = mix(water, refl, F);
    /* Phong sun glint; the exponent drops with roughness (distance, coarse
     * normals) so far glitter widens instead of aliasing */
    float shin = mix(1200.0, 80.0, clamp(roughness, 0.0, 1.0));
    float spec = pow(max(dot(R, u_sunDir), 0.0), shin) * (shin + 2.0) / 8.0;
    col += u_sunColor * spec * F * 2.5 * shadow * step(0.0, u_sunDir.y);
    /* foam: diffuse white lit by sun and sky */
    vec3 foamCol = vec3(0.90, 0.94, 0.96) * (0.35 + 0.65 * max(dot(N, u_sunDir), 0.0) * shadow) * sunUp
                 + skyBase(vec3(0.0, 1.0, 0.0)) * 0.25;
    col = mix(col, foamCol, clamp(foam, 0.0, 1.0));
    return col * mix(0.62, 1.0, shadow);
}
/* Airlight: the sky just above the horizon, brightened toward the sun by
 * the angle between the view and the sun.  Not by the view's azimuth: a
 * view straight down has none, and the sky taken in the direction
 * (V.x, 0.03, V.z) turned to the zenith there (a dark spot at the nadir
 * with a bright cone toward the sun from 10 km). */
vec3 haze(vec3 col, vec3 V, float dist) {
    float f = 1.0 - exp(-dist / 42000.0);
    vec3 hc = skyGradient(0.03) + skyHalo(max(dot(V, u_sunDir), 0.0));
    return mix(col, hc, clamp(f, 0.0, 1.0));
}
vec3 tonemap(vec3 c) {
    c *= 0.85;
    vec3 x = (c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14);   /* ACES fit (Narkowicz) */
    return pow(clamp(x, 0.0, 1.0), vec3(1.0 / 2.2));
}
float cloudShadow(vec3 rel) {
    return 1.0 - 0.5 * clouds(rel.xz + u_sunDir.xz / max(u_sunDir.y, 0.05) * (CLOUD_ALT - rel.y));
}
/* Foam near the eye: the carried whitecap coverage c (the white fraction
 * of the sample's area) drawn as a foam texture whose brightness follows
 * c: the drifting grain scales it about its mean (0.3 + 1.4 g, g's mean
 * 0.5), so the drawn mean stays c and the luminance is continuous, with no
 * threshold turning it into opaque patches; the grain is read in the
 * wind's frame stretched 4 : 1 along the wind, so the texture streaks
 * downwind as wind-blown foam does.  Far away, where the grain would
 * alias, c is drawn as it is. */
float foamBreakUp(float c, vec2 rel, float dist) {
    vec2 q = vec2(dot(rel, u_wind) * 0.25, dot(rel, vec2(-u_wind.y, u_wind.x)));
    float grain = texture(u_cloudTex, q * GRAIN_K + u_grainOff).r;
    float tex = clamp(c * (0.3 + 1.4 * grain), 0.0, 1.0);
    return mix(c, tex, 1.0 - smoothstep(300.0, 3000.0, dist));
}
`;

const FULL_VS = `#version 300 es
out vec2 v_ndc;
void main() {
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2)) * 2.0 - 1.0;
    v_ndc = p;
    gl_Position = vec4(p, 0.999999, 1.0);
}`;

/* fills one face of the sky cube map */
const SKYGEN_FS = `${COMMON}
out vec4 o_color;
uniform int u_face;
uniform float u_size;
void main() {
    float sc = 2.0 * gl_FragCoord.x / u_size - 1.0, tc = 2.0 * gl_FragCoord.y / u_size - 1.0;
    vec3 d;
    if (u_face == 0) d = vec3(1.0, -tc, -sc);
    else if (u_face == 1) d = vec3(-1.0, -tc, sc);
    else if (u_face == 2) d = vec3(sc, 1.0, tc);
    else if (u_face == 3) d = vec3(sc, -1.0, -tc);
    else if (u_face == 4) d = vec3(sc, -tc, 1.0);
    else d = vec3(-sc, -tc, -1.0);
    d = normalize(d);
    d.y = abs(d.y);
    o_color = vec4(skyFull(d) / u_skyScale, 1.0);
}`;

const SKY_FS = `${COMMON}
in vec2 v_ndc;
out vec4 o_color;
uniform vec3 u_right, u_up, u_fwd;
uniform vec2 u_tanHalf;     /* tan(fov/2) * aspect, tan(fov/2) */
void main() {
    vec3 V = normalize(u_fwd + v_ndc.x * u_tanHalf.x * u_right + v_ndc.y * u_tanHalf.y * u_up);
    vec3 col;
    if (V.y >= 0.0) {
        col = skyEnv(V) + sunDisc(V);
    } else {
        /* the sea beyond the mesh: flat water seen at this distance */
        float dist = max(u_eyeY, 0.1) / max(-V.y, 1e-5);
        vec3 hit = V * dist;
        col = seaColor(V, vec3(0.0, 1.0, 0.0), 0.0, 0.0, cloudShadow(hit), 1.0);
        col = haze(col, V, dist);
    }
    o_color = vec4(tonemap(col), 1.0);
}`;

const SEA_SAMPLING = `
uniform sampler2DArray u_disp;
uniform sampler2DArray u_nrm;
uniform int u_nLevels;
uniform vec4 u_lvlA[MAXL];    /* origin x, z (eye-relative), spacing, layer */
uniform vec4 u_lvlB[MAXL];    /* samples w, h, edge ramp in samples, has data */
uniform vec2 u_texSize;       /* array texture size in texels */

/* weight of level L at eye-relative xz: 1 inside, ramping to 0 at its edge */
float levelCover(int L, vec2 xz, out vec3 uvw) {
    vec4 A = u_lvlA[L], B = u_lvlB[L];
    vec2 a = (xz - A.xy) / A.z;                 /* sample coordinates */
    vec2 e2 = min(a, B.xy - 1.0 - a);
    float e = min(e2.x, e2.y);
    uvw = vec3((a + 0.5) / u_texSize, A.w);
    return B.w * clamp(e / B.z, 0.0, 1.0);
}
`;

const SEA_VS = `${COMMON}
${SEA_SAMPLING}
in vec3 a_pos;
in float a_morph;
in float a_spacing;
in float a_level;
uniform vec3 u_meshOff;      /* mesh origin - eye */
uniform mat4 u_viewProj;
uniform float u_applyTiles;  /* 1: positions are flat, displace them here; 0: the server displaced them */
out vec3 v_rel;              /* displaced position relative to the eye */
out vec2 v_base;             /* undisplaced xz relative to the eye */
out float v_crest;
out float v_foam;
out float v_level;
void main() {
    vec3 p = u_meshOff + a_pos;
    vec4 acc = vec4(0.0);
    float rem = 1.0;
    /* geomorph: a vertex about to become the next ring's samples as if it
     * were already twice as coarse */
    float sv = max(a_spacing * (1.0 + a_morph), 1e-3);
    for (int L = 0; L < MAXL; L++) {
        if (L >= u_nLevels || rem < 0.002) break;
        vec3 uvw;
        float w = levelCover(L, p.xz, uvw);
        float foot = clamp(log2(u_lvlA[L].z / sv) + 1.0, 0.0, 1.0);
        if (L == u_nLevels - 1) foot = 1.0;     /* coarsest level: keep the swell */
        w *= foot;
        if (w <= 0.0) continue;
        vec4 d = textureLod(u_disp, uvw, 0.0);
        float cov = textureLod(u_nrm, uvw, 0.0).w;
        w *= cov;
        acc += rem * w * d;
        rem *= 1.0 - w;
    }
    if (u_applyTiles > 0.5) {
        v_rel = p + vec3(acc.y, acc.x, acc.z);
        v_base = p.xz;
        v_crest = acc.x;
    } else {
        /* displaced by the server (FFT height and chop, Gerstner near
         * field): keep the positions, and find the undisplaced point the
         * tiles are indexed by with one fixed-point step x0 = x - D(x) */
        v_rel = p;
        v_base = p.xz - acc.yz;
        v_crest = p.y;
    }
    v_foam = acc.w;
    v_level = a_level;
    gl_Position = u_viewProj * vec4(v_rel, 1.0);
}`;

const SEA_FS = `${COMMON}
${SEA_SAMPLING}
in vec3 v_rel;
in vec2 v_base;
in float v_crest;
in float v_foam;
in float v_level;
out vec4 o_color;
uniform float u_pixAngle;    /* radians per pixel */
uniform float u_debug;
uniform float u_hs;          /* significant wave height, m (for crest scaling) */
void main() {
    vec3 V = normalize(v_rel);
    float dist = length(v_rel);
    /* pixel footprint on the sea, stretched at grazing angles */
    float foot = dist * u_pixAngle / max(abs(V.y), 0.08);
    vec4 nacc = vec4(0.0);
    float facc = 0.0;
    float rem = 1.0;
    float lvlSeen = 0.0;
    for (int L = 0; L < MAXL; L++) {
        if (L >= u_nLevels || rem < 0.002) break;
        vec3 uvw;
        float w = levelCover(L, v_base, uvw);
        float f = clamp(1.0 - log2(foot / u_lvlA[L].z), 0.0, 1.0);
        if (L == u_nLevels - 1) f = 1.0;
        w *= f;
        if (w <= 0.0) continue;
        vec4 n = texture(u_nrm, uvw);
        float fo = texture(u_disp, uvw).w;
        w *= n.w;
        nacc += rem * w * vec4(n.xyz, 1.0);
        facc += rem * w * fo;
        lvlSeen += rem * w * float(L);
        rem *= 1.0 - w;
    }
    vec3 N = normalize(nacc.xyz + rem * vec3(0.0, 1.0, 0.0));
    /* detail lost to the footprint shows up as roughness */
    float rough = clamp(lvlSeen * 0.12 + rem * 0.8 + dist / 20000.0, 0.0, 1.0);
    float foam = foamBreakUp(clamp(facc, 0.0, 1.0), v_base, dist);
    float shadow = cloudShadow(v_rel);
    float crest = v_crest / max(u_hs * 0.5, 0.2);
    vec3 col = seaColor(V, N, crest, foam, shadow, rough);
    col = haze(col, V, dist);
    if (u_debug > 0.5) {
        vec3 tint = 0.5 + 0.5 * cos(6.2831 * (lvlSeen * 0.17 + vec3(0.0, 0.33, 0.67)));
        col = mix(col, tint, 0.5);
    }
    o_color = vec4(tonemap(col), 1.0);
}`;

/* ---- layout 1: cascades summed on the GPU (PROTOCOL.md "Layouts") ------
 *
 * Each cascade c is a periodic field on its patch P_c, held in two
 * mipmapped textures with GL REPEAT: disp = (DX, H, DZ, 0) and slope =
 * (∂η/∂x, ∂η/∂z, BI, BQ).  GL mip level m is the server's mip m (n_c/2^m texels).
 * The server's mip samples are co-sited with the level-0 grid (sample j of
 * mip m at x = j·σ_c·2^m), unlike GL's box-filter mips, so each level is
 * read at its own half-texel offset and the trilinear blend of "Where each
 * mip is read" is done here with two explicit-level reads.
 *
 * Precision: the eye's position modulo each patch is reduced in double on
 * the CPU (u_casEye, texture units); the GPU adds eye-relative offsets.
 *
 * This text is the viewer's only copy of the rule: tests/browser/lod.test.mjs
 * runs it in Chromium's WebGL against tests/vectors/lod.txt (the mips read)
 * and lod_mss.txt (the unresolved slope moments, casMss), the points
 * protocol/lod.c computes.
 */
export const CASCADE_GLSL = `
#define MAXC ${MAX_CASCADES}
#define MIPE ${MIP_ENTRIES}
uniform int u_nCas;
uniform vec4 u_cas[MAXC];        /* patch P, native spacing sigma, mips, fades */
uniform vec2 u_casEye[MAXC];     /* (eye xz mod P) / P */
uniform vec4 u_mipTab[MAXC * MIPE]; /* kc, mss_x, mss_z, mss_xz (PROTOCOL.md "Cascade entry") */
/* per cascade c and mip m, at [(c MIPE + m) / 4][(c MIPE + m) % 4]: the
 * share of the mip's breaking-index variance the shading's reading of it
 * holds (the read table's Keys share at mip 0, bilinear beyond; 1 without
 * the table) */
uniform vec4 u_mipHeld[(MAXC * MIPE + 3) / 4];
uniform vec3 u_blk;              /* the block's q = spacing_per_m, min_spacing_m, camera y */
uniform float u_casQ[MAXC];      /* each cascade's own q (its entry's spacing_per_m) */
uniform vec2 u_blkCam;           /* the block's camera xz relative to the eye */
uniform vec3 u_tailMss;          /* moments no cascade holds */
uniform float u_roughScale;      /* 1; 0 draws the unresolved moments as a mirror (test control) */
uniform float u_foamScale;       /* 1; 0 draws no foam (test control) */
uniform vec3 u_foamTab[${FOAM_ROWS}]; /* the whitecap table: sigma, a, omega (PROTOCOL.md "Whitecaps in layout 1") */
uniform int u_foamRows;          /* its rows; 0: no foam */
uniform sampler2D u_cd0, u_cd1, u_cd2, u_cd3;   /* disp per cascade */
uniform sampler2D u_wakeTex;     /* the wakes on a square around the camera: height, dh/dx, dh/dz, the
                                    slope variance a side the square does not hold (oc_wakes_grid) */
uniform vec4 u_wake;             /* its first point x, z (eye-relative), spacing, points a side (0: none) */

/* the ships' wakes and the rotors' downwash at eye-relative rel
 * (PROTOCOL.md "WAKE", read by the worker's WebAssembly on a square around
 * the camera): height, slopes and the slope variance the square leaves to
 * the roughness, fading out over the square's outer eighth, 0 beyond it.
 * Only the programs made with WAKES read them: a sea without ships pays
 * nothing (a software GL runs both sides of a branch) */
vec4 wakeAt(vec2 rel) {
#ifdef WAKES
    vec2 uv = ((rel - u_wake.xy) / u_wake.z + 0.5) / u_wake.w;
    vec2 e = min(uv, 1.0 - uv);
    float fade = clamp(8.0 * min(e.x, e.y), 0.0, 1.0);
    return fade * textureLod(u_wakeTex, uv, 0.0);
#else
    return vec4(0.0);
#endif
}

/* s_c(x, z): the spacing cascade c is read at, at eye-relative rel, raised
 * to floorS (the vertex's lattice g_L, or the pixel's footprint) */
float wantSpacing(int c, vec2 rel, float floorS) {
    vec2 d = rel - u_blkCam;
    float h = max(abs(u_blk.z), 1.0);
    return max(floorS, max(u_blk.y, u_casQ[c] * sqrt(dot(d, d) + h * h)));
}
/* continuous level of cascade c for spacing s, clamped to its mips; *w
 * the fade of a cascade that fades beyond its last mip */
float casLod(int c, float s, out float w) {
    vec4 C = u_cas[c];
    float lam = log2(s / C.y);
    float top = C.z - 1.0;
    w = (lam >= top && C.w > 0.5) ? clamp(C.z - lam, 0.0, 1.0) : 1.0;
    return clamp(lam, 0.0, top);
}
vec4 casRead(sampler2D t, int c, vec2 rel, float lam) {
    float m0 = floor(lam), f = lam - m0;
    float n = u_cas[c].x / u_cas[c].y;
    vec2 uv = u_casEye[c] + rel / u_cas[c].x;
    vec4 a = textureLod(t, uv + exp2(m0 - 1.0) / n, m0);
    if (f > 1e-4) a = mix(a, textureLod(t, uv + exp2(m0) / n, m0 + 1.0), f);
    return a;
}
/* Mip 0 of an n-texel periodic texture at texture coordinate p (texel
 * centres at (j + 1/2) / n) by Keys' cubic convolution, a = -1/2 (Keys
 * 1981; Catmull-Rom), as 9 bilinear reads: the two middle taps of each
 * axis share one read placed between them by their weights (both weights
 * are positive).  Mip 0 holds waves up to its Nyquist, where GL's bilinear
 * filter keeps (2 + cos th) / 3 of a wave's power per axis; the C library
 * reads every mip this way, and the whitecap table's ramps and the mip
 * tables' moments are for the waves as they are. */
vec4 keys0(sampler2D t, float n, vec2 p) {
    vec2 x = p * n - 0.5, i = floor(x), f = x - i;
    vec2 w0 = f * (-0.5 + f * (1.0 - 0.5 * f)), w1 = 1.0 + f * f * (-2.5 + 1.5 * f);
    vec2 w2 = f * (0.5 + f * (2.0 - 1.5 * f)), w3 = f * f * (-0.5 + 0.5 * f);
    vec2 w12 = w1 + w2;
    vec2 a = (i - 0.5) / n, b = (i + 0.5 + w2 / w12) / n, d = (i + 2.5) / n;
    return (textureLod(t, vec2(a.x, a.y), 0.0) * w0.x + textureLod(t, vec2(b.x, a.y), 0.0) * w12.x +
            textureLod(t, vec2(d.x, a.y), 0.0) * w3.x) * w0.y +
           (textureLod(t, vec2(a.x, b.y), 0.0) * w0.x + textureLod(t, vec2(b.x, b.y), 0.0) * w12.x +
            textureLod(t, vec2(d.x, b.y), 0.0) * w3.x) * w12.y +
           (textureLod(t, vec2(a.x, d.y), 0.0) * w0.x + textureLod(t, vec2(b.x, d.y), 0.0) * w12.x +
            textureLod(t, vec2(d.x, d.y), 0.0) * w3.x) * w3.y;
}
/* casRead for shading: mip 0 by keys0 */
vec4 casReadShade(sampler2D t, int c, vec2 rel, float lam) {
    if (lam >= 1.0) return casRead(t, c, rel, lam);
    float n = u_cas[c].x / u_cas[c].y;
    vec2 uv = u_casEye[c] + rel / u_cas[c].x;
    vec4 a = keys0(t, n, uv + 0.5 / n);
    if (lam > 1e-4) a = mix(a, textureLod(t, uv + 1.0 / n, 1.0), lam);
    return a;
}
/* unresolved slope moments of cascade c read at (unclamped) level lam */
vec3 casMss(int c, float lam) {
    vec4 C = u_cas[c];
    int base = c * MIPE;
    float top = C.z - 1.0;
    if (lam <= 0.0) return u_mipTab[base].yzw;
    /* entries blended with weights 1 - f, f also add f (1 - f) (coarser -
     * finer): the slope variance the linear blend of two band-limited
     * fields loses (PROTOCOL.md "Where each mip is read") */
    if (lam < top) {
        int m = int(floor(lam));
        float f = lam - float(m);
        vec3 e0 = u_mipTab[base + m].yzw, e1 = u_mipTab[base + m + 1].yzw;
        return mix(e0, e1, f) + f * (1.0 - f) * (e1 - e0);
    }
    vec3 e = u_mipTab[base + int(top)].yzw;
    if (C.w > 0.5) {
        vec3 all = u_mipTab[base + int(C.z)].yzw;
        float w = clamp(C.z - lam, 0.0, 1.0);
        e = mix(all, e, w) + w * (1.0 - w) * (all - e);
    }
    return e;
}
/* displacement (DX, H, DZ) summed over cascades, each at its own spacing
 * raised to floorS */
vec3 casDisp(vec2 rel, float floorS) {
    vec3 acc = vec3(0.0);
    float w, lam;
#define CAS_D(C, T) if (u_nCas > C) { lam = casLod(C, wantSpacing(C, rel, floorS), w); acc += w * casRead(T, C, rel, lam).xyz; }
    CAS_D(0, u_cd0) CAS_D(1, u_cd1) CAS_D(2, u_cd2) CAS_D(3, u_cd3)
    return acc;
}
float casHeldOf(int c, int m) {
    int i = c * MIPE + m;
    return u_mipHeld[i / 4][i % 4];
}
/* the share of the breaking-index variance of the mips cascade c's
 * shading reads at (unclamped) level lam that the reading holds: the read
 * mips' shares with their weights, over the weights' sum (lod.c
 * proto_lod_held) */
float casHeld(int c, float lam) {
    float top = u_cas[c].z - 1.0;
    if (lam <= 0.0) return casHeldOf(c, 0);
    if (lam < top) {
        int m = int(floor(lam));
        return mix(casHeldOf(c, m), casHeldOf(c, m + 1), lam - float(m));
    }
    return casHeldOf(c, int(top));
}
/* the breaking-index variance cascade c's shading holds read at level lam:
 * its whole slope variance less what casMss leaves unresolved there, times
 * casHeld (lod.c proto_lod_breaking_var) */
float casBreakVar(int c, float lam, vec3 unresolved) {
    vec4 all = u_mipTab[c * MIPE + int(u_cas[c].z)];
    return max(all.y + all.z - unresolved.x - unresolved.y, 0.0) * casHeld(c, lam);
}
/* Whitecap foam (lod.c proto_lod_foam, foam.h ocean_foam_value) from the
 * summed breaking index beta, its quadrature q and the variance v the reads
 * hold: the table's ramp foot a and band frequency omega, linear in
 * sigma = sqrt(v) between the rows around it; the active foam, or the last
 * crest's foam decayed over the phase since it passed (Monahan 1971's
 * 3.85 s), whichever is whiter */
const float FOAM_BREAK = 0.5, FOAM_DECAY_S = 3.85;
float foamRamp(float a, float x) {
    float span = FOAM_BREAK - a;
    return span > 1e-6 ? clamp((x - a) / span, 0.0, 1.0) : step(FOAM_BREAK, x);
}
float foamAt(float beta, float q, float v) {
    if (u_foamRows < 1) return 0.0;
    float sg = sqrt(max(v, 0.0));
    vec3 r = u_foamTab[0];
    for (int i = 1; i < ${FOAM_ROWS}; i++) {
        if (i >= u_foamRows || sg <= r.x) break;
        vec3 n = u_foamTab[i];
        if (sg >= n.x) { r = n; continue; }
        r = mix(r, n, (sg - r.x) / (n.x - r.x));
        break;
    }
    float fi = foamRamp(r.y, beta);
    float e = length(vec2(beta, q));
    if (r.z <= 0.0 || fi >= 1.0 || !(e > r.y)) return fi;
    float th = atan(q, beta);
    th += th < 0.0 ? 6.2831853 : 0.0;
    return max(fi, foamRamp(r.y, e) * exp(-th / (r.z * FOAM_DECAY_S)));
}
`;

export const CASCADE_FRAG_GLSL = `
uniform sampler2D u_cs0, u_cs1, u_cs2, u_cs3;   /* slope per cascade */
/* mean slope, unresolved slope moments (x, z, xz) and foam, each cascade
 * at its own spacing raised to floorS: the slope textures hold (slope x,
 * slope z, BI, BQ), and foam is the whitecap table applied to the summed
 * breaking index at the variance the reads hold */
void seaSample(vec2 rel, float floorS, out vec2 slope, out vec3 mss, out float foam) {
    slope = vec2(0.0);
    mss = u_tailMss;
    vec2 bq = vec2(0.0);
    float w, lam, lu, s, bvar = 0.0;
    vec3 un;
#define CAS_S(C, TS) if (u_nCas > C) { s = wantSpacing(C, rel, floorS); lam = casLod(C, s, w); vec4 d = w * casReadShade(TS, C, rel, lam); slope += d.xy; bq += d.zw; lu = log2(s / u_cas[C].y); un = casMss(C, lu); mss += un; bvar += casBreakVar(C, lu, un); }
    CAS_S(0, u_cs0) CAS_S(1, u_cs1) CAS_S(2, u_cs2) CAS_S(3, u_cs3)
    vec4 wk = wakeAt(rel);
    slope += wk.yz;
    mss.xy += wk.w;
    foam = foamAt(bq.x, bq.y, bvar) * u_foamScale;
    mss *= u_roughScale;
}
`;

/* Shading from slopes: mean normal from the mean slope, and the slope
 * distribution the pixel does not resolve (covariance mss) as a Beckmann
 * (Gaussian-slope) lobe, as in Bruneton, Neyret & Holzschuch 2010 ("Real-time
 * realistic ocean lighting using seamless transitions from geometry to
 * BRDF", eqs. for the reflected sun and the mean Fresnel / sky terms): the
 * sun's glitter and the sky reflection keep their average from any
 * distance, spread by roughness instead of aliasing or turning to a mirror. */
const SEA_SHADE_GLSL = `
const float SUN_E = 6.0;          /* sun irradiance relative to the sky radiance scale */
const float SUN_MSS = 1e-5;       /* the sun's own angular radius (~4.7 mrad) as slope variance */
float lambdaSmith(float c, float s2) {
    float v = c / sqrt(max((1.0 - c * c) * 2.0 * s2, 1e-12));
    return v > 4.0 ? 0.0 : exp(-v * v) / (2.0 * v * 1.7724539);   /* Bruneton's approximation of Smith's Lambda */
}
vec3 seaShade(vec3 V, vec2 slope, vec3 mss, float foam, float crest, float shadow) {
    vec3 N = normalize(vec3(-slope.x, 1.0, -slope.y));
    vec3 E = -V;
    float sxx = mss.x + SUN_MSS, szz = mss.y + SUN_MSS, sxz = mss.z;
    float det = max(sxx * szz - sxz * sxz, 1e-12);
    vec2 az = normalize(V.xz + vec2(1e-7, 0.0));
    float sv2 = max(az.x * az.x * sxx + 2.0 * az.x * az.y * sxz + az.y * az.y * szz, 1e-7);
    float zV = max(dot(E, N), 0.01);
    /* mean Fresnel over the slopes (Bruneton et al. 2010, their fit) */
    float F = 0.02 + 0.98 * pow(1.0 - zV, 5.0 * exp(-2.69 * sqrt(sv2))) / (1.0 + 22.7 * pow(sqrt(sv2), 1.5));
    /* sky: mirror direction of the mean normal, blurred by the reflected
     * slope spread (twice the slope angle) through the cube map's mips */
    vec3 R = reflect(V, N);
    float spread = 2.0 * sqrt(0.5 * (sxx + szz));
    float lod = log2(max(1.0, spread * float(${SKY_CUBE}) / 1.5708));
    vec3 refl = textureLod(u_skyCube, vec3(R.x, abs(R.y), R.z), lod).rgb * u_skyScale;
    float sunUp = clamp(u_sunDir.y * 2.0, 0.05, 1.0);
    vec3 water = WATER_DEEP * sunUp;
    float sss = pow(max(dot(V, u_sunDir) * 0.5 + 0.5, 0.0), 3.0) * clamp(crest, 0.0, 1.0);
    water += WATER_SCATTER * sss * sunUp * 0.6;
    water += WATER_SCATTER * 0.06 * max(dot(N, u_sunDir), 0.0);
    vec3 col = mix(water, refl, F);
    /* sun: Gaussian density of facet slopes zeta (those that mirror the sun
     * to the eye) about the mean slope, over 4 cos(view) cos^4(half) and
     * Smith's shadowing */
    vec3 L = u_sunDir;
    vec3 H = normalize(L + E);
    if (H.y > 0.0 && L.y > 0.0) {
        vec2 zeta = vec2(-H.x / H.y, -H.z / H.y) - slope;
        float qf = (szz * zeta.x * zeta.x - 2.0 * sxz * zeta.x * zeta.y + sxx * zeta.y * zeta.y) / det;
        float p = exp(-0.5 * qf) / (6.2831853 * sqrt(det));
        float zH = max(dot(H, N), 0.01);
        vec2 azL = normalize(L.xz + vec2(1e-7, 0.0));
        float sl2 = max(azL.x * azL.x * sxx + 2.0 * azL.x * azL.y * sxz + azL.y * azL.y * szz, 1e-7);
        float zL = max(dot(L, N), 0.01);
        float Fh = 0.02 + 0.98 * pow(1.0 - max(dot(E, H), 0.0), 5.0);
        float g = 1.0 + lambdaSmith(zL, sl2) + lambdaSmith(zV, sv2);
        col += u_sunColor * SUN_E * shadow * Fh * p / (4.0 * zV * zH * zH * zH * zH * g);
    }
    vec3 foamCol = vec3(0.90, 0.94, 0.96) * (0.35 + 0.65 * max(dot(N, u_sunDir), 0.0) * shadow) * sunUp
                 + skyBase(vec3(0.0, 1.0, 0.0)) * 0.25;
    col = mix(col, foamCol, clamp(foam, 0.0, 1.0));
    return col * mix(0.62, 1.0, shadow);
}
`;

const SEA1_VS = `${COMMON}
${CASCADE_GLSL}
in vec2 a_flat;
in float a_level;
uniform vec4 u_zone[MAXL];       /* lattice spacing g_L, zone radius R_L, blend half-width b_L, 0 */
uniform int u_lodLevels;
uniform vec3 u_meshOff;          /* placement origin - eye */
uniform mat4 u_viewProj;
out vec3 v_rel;
out vec2 v_base;
out float v_crest;
out float v_level;
void main() {
    int L = int(a_level + 0.5);
    vec2 p = a_flat;
    float g = u_zone[L].x;
    if (L < u_lodLevels - 1) {
        /* PROTOCOL.md "Mesh in layout 1": morph weight from the distance to
         * the block's camera, odd vertices slide onto the coarser lattice */
        vec4 Z = u_zone[L];
        float d = length(u_meshOff.xz + p - u_blkCam);
        float w;
        if (Z.z > 0.0) {
            float u = clamp((d - (Z.y - Z.z)) / (2.0 * Z.z), 0.0, 1.0);
            w = u * u * (3.0 - 2.0 * u);
        } else {
            w = d >= Z.y ? 1.0 : 0.0;
        }
        float gc = u_zone[L + 1].x;
        p -= w * (p - gc * floor(p / gc + 0.5));
        /* a vertex on its way to the coarser ring samples as that ring does */
        g = mix(g, gc, w);
    }
    vec2 rel = u_meshOff.xz + p;
    vec3 D = casDisp(rel, g);
    D.y += wakeAt(rel).x;
    v_rel = vec3(rel.x + D.x, u_meshOff.y + D.y, rel.y + D.z);
    v_base = rel;
    v_crest = D.y;
    v_level = a_level;
    gl_Position = u_viewProj * vec4(v_rel, 1.0);
}`;

const SEA1_FS = `${COMMON}
${CASCADE_GLSL}
${CASCADE_FRAG_GLSL}
${SEA_SHADE_GLSL}
in vec3 v_rel;
in vec2 v_base;
in float v_crest;
in float v_level;
out vec4 o_color;
uniform float u_pixAngle;
uniform float u_debug;
uniform float u_hs;
void main() {
    vec3 V = normalize(v_rel);
    float dist = length(v_rel);
    /* the pixel's footprint (geometric mean of its across and along-view
     * extents): where it is coarser than s, a coarser mip is read and the
     * mip tables account for what it leaves out, so nothing aliases */
    float foot = dist * u_pixAngle / sqrt(max(abs(V.y), 0.02));
    vec2 slope; vec3 mss; float foam;
    seaSample(v_base, foot, slope, mss, foam);
    foam = foamBreakUp(foam, v_base, dist);
    float shadow = cloudShadow(v_rel);
    vec3 col = seaShade(V, slope, mss, foam, v_crest / max(u_hs * 0.5, 0.2), shadow);
    col = haze(col, V, dist);
    if (u_debug > 0.5) {
        vec3 tint = 0.5 + 0.5 * cos(6.2831 * (v_level * 0.17 + vec3(0.0, 0.33, 0.67)));
        col = mix(col, tint, 0.5);
    }
    o_color = vec4(tonemap(col), 1.0);
}`;

/* sky, and the sea beyond the mesh shaded with the same functions (flat
 * at y = 0: from there on the displacement is far below a pixel) */
const SKY1_FS = `${COMMON}
${CASCADE_GLSL}
${CASCADE_FRAG_GLSL}
${SEA_SHADE_GLSL}
in vec2 v_ndc;
out vec4 o_color;
uniform vec3 u_right, u_up, u_fwd;
uniform vec2 u_tanHalf;
uniform float u_pixAngle;
void main() {
    vec3 V = normalize(u_fwd + v_ndc.x * u_tanHalf.x * u_right + v_ndc.y * u_tanHalf.y * u_up);
    vec3 col;
    if (V.y >= 0.0) {
        col = skyEnv(V) + sunDisc(V);
    } else {
        float dist = max(u_eyeY, 0.1) / max(-V.y, 1e-5);
        vec3 hit = V * dist;
        float foot = dist * u_pixAngle / sqrt(max(-V.y, 0.02));
        vec2 slope = vec2(0.0); vec3 mss = vec3(0.02, 0.02, 0.0); float foam = 0.0;
        if (u_nCas > 0) seaSample(hit.xz, foot, slope, mss, foam);
        col = seaShade(V, slope, mss, foamBreakUp(foam, hit.xz, dist), 0.0, cloudShadow(hit));
        col = haze(col, V, dist);
    }
    o_color = vec4(tonemap(col), 1.0);
}`;

function compile(gl, type, src) {
    const s = gl.createShader(type);
    gl.shaderSource(s, src);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) {
        const log = gl.getShaderInfoLog(s);
        const lines = src.split('\n').map((l, i) => `${i + 1}: ${l}`).join('\n');
        throw new Error(`shader compile failed: ${log}\n${lines.slice(0, 200)}`);
    }
    return s;
}

function program(gl, vs, fs, attribs) {
    const p = gl.createProgram();
    gl.attachShader(p, compile(gl, gl.VERTEX_SHADER, vs));
    gl.attachShader(p, compile(gl, gl.FRAGMENT_SHADER, fs));
    (attribs || []).forEach((name, i) => gl.bindAttribLocation(p, i, name));
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(`program link failed: ${gl.getProgramInfoLog(p)}`);
    const u = {};
    const n = gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS);
    for (let i = 0; i < n; i++) {
        const info = gl.getActiveUniform(p, i);
        const name = info.name.replace(/\[0\]$/, '');
        u[name] = gl.getUniformLocation(p, info.name);
    }
    return { p, u };
}

function perspective(fovY, aspect, near, far) {
    const f = 1 / Math.tan(fovY / 2), nf = 1 / (near - far);
    return new Float32Array([f / aspect, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) * nf, -1, 0, 0, 2 * far * near * nf, 0]);
}

function mul4(a, b) {
    const o = new Float32Array(16);
    for (let c = 0; c < 4; c++)
        for (let r = 0; r < 4; r++) {
            let s = 0;
            for (let k = 0; k < 4; k++) s += a[k * 4 + r] * b[c * 4 + k];
            o[c * 4 + r] = s;
        }
    return o;
}

export class Renderer {
    constructor(canvas, opts = {}) {
        const gl = canvas.getContext('webgl2', { antialias: opts.antialias ?? true, preserveDrawingBuffer: false, powerPreference: 'high-performance' });
        if (!gl) throw new Error('WebGL2 is not available in this browser');
        this.gl = gl;
        this.canvas = canvas;
        this.sky = program(gl, FULL_VS, SKY_FS);
        this.skygen = program(gl, FULL_VS, SKYGEN_FS);
        this.sea = program(gl, SEA_VS, SEA_FS, ['a_pos', 'a_morph', 'a_spacing', 'a_level']);
        this.sea1 = program(gl, SEA1_VS, SEA1_FS, ['a_flat', 'a_level']);
        this.sea1w = null;         /* the same reading the ships' wakes: made at the first (setWakes) */
        this.sky1 = program(gl, FULL_VS, SKY1_FS);
        const info = gl.getExtension('WEBGL_debug_renderer_info');
        this.rendererName = String(info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER));
        this.software = /swiftshader|llvmpipe|software|softpipe/i.test(this.rendererName);
        /* software GL (no GPU): render fewer pixels so the viewer stays usable */
        this.scale = opts.scale > 0 ? opts.scale : this.software ? 0.5 : 1;
        this.cloudTex = makeCloudTexture(gl);
        this.initSkyCube();
        this.vao = gl.createVertexArray();
        this.emptyVao = gl.createVertexArray();
        this.posBuf = gl.createBuffer();
        this.morphBuf = gl.createBuffer();
        this.spacingBuf = gl.createBuffer();
        this.levelBuf = gl.createBuffer();
        this.idxBuf = gl.createBuffer();
        this.indexCount = 0;
        this.vertexCount = 0;
        this.topology = null;
        this.mesh = null;          /* {origin[3], meshId} of the positions in posBuf */
        this.needSpacing = false;
        this.levels = [];          /* per layer: {originX, originZ, spacing, width, height} */
        this.texW = 0; this.texH = 0; this.texL = 0;
        this.dispTex = gl.createTexture();
        this.nrmTex = gl.createTexture();
        this.allocTextures(2, 2, 1);
        this.sunDir = normalize3([0.55, 0.35, 0.45]);
        this.sunColor = [1.0, 0.92, 0.80];
        this.wind = [1, 0];
        this.hs = 2;
        this.debug = false;
        this.applyTiles = 1;
        /* layout 1 */
        this.vao1 = gl.createVertexArray();
        this.flatBuf = gl.createBuffer();
        this.level1Buf = gl.createBuffer();
        this.idx1Buf = gl.createBuffer();
        this.topology1 = null;     /* FLAT topology: {meshId, vertexCount, lodLevels, zones} */
        this.indexCount1 = 0;
        this.cas = [];             /* per cascade: {key, patch, n, sigma, mips, fades, disp, slope} */
        this.block = null;         /* the newest FRAME's cascade block */
        this.placement = null;     /* {meshId, origin} of the newest FRAME */
        this.roughScale = 1;       /* 0: unresolved slopes ignored (a mirror; the test's control) */
        this.foamScale = 1;        /* 0: no foam (the test's glitter comparison) */
        this.dummyTex = gl.createTexture();
        gl.bindTexture(gl.TEXTURE_2D, this.dummyTex);
        gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA8, 1, 1, 0, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
        this.wakeTex = gl.createTexture();
        this.wake = null;          /* {x0, z0, dx, n} of the wakes in wakeTex (world, m) */
    }

    /* The ships' wakes on n x n points from (x0, z0) (world, double) at
     * spacing dx: data holds 4 floats a point (height, dh/dx, dh/dz, 0),
     * row z after row (codec.js WakeStore.grid); null: none. */
    setWakes(w) {
        const gl = this.gl;
        if (!w) { this.wake = null; return; }
        if (!this.sea1w) {
            const withWakes = (src) => src.replace('#version 300 es\n', '#version 300 es\n#define WAKES 1\n');
            this.sea1w = program(gl, withWakes(SEA1_VS), withWakes(SEA1_FS), ['a_flat', 'a_level']);
        }
        gl.bindTexture(gl.TEXTURE_2D, this.wakeTex);
        gl.pixelStorei(gl.UNPACK_ALIGNMENT, 4);
        gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA16F, w.n, w.n, 0, gl.RGBA, gl.FLOAT, w.data);
        gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
        gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
        gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
        gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
        this.wake = { x0: w.x0, z0: w.z0, dx: w.dx, n: w.n };
    }

    /* Layout 1: a FRAME's cascade block, its decoded tiles (texel blocks,
     * see assemble.js assembleCascadeTile) and the mesh placement.
     * Textures are (re)made when a cascade's patch, grid or mip count
     * changes; each tile is written to its place (tile (ix, iz) of mip m of
     * cascade c).  Tiles not in this frame keep their older texels: the
     * server sends every tile the read rule needs at this camera. */
    setCascadeFrame(block, blocks, placement) {
        const gl = this.gl;
        const nc = Math.min(block.cascadeCount, MAX_CASCADES);
        for (let c = 0; c < nc; c++) {
            const e = block.cascade[c];
            const key = `${e.patchM}/${e.n}/${e.mips}`;
            const old = this.cas[c];
            if (!old || old.key !== key) {
                if (old) { gl.deleteTexture(old.disp); gl.deleteTexture(old.slope); }
                const mk = (fmt) => {
                    const t = gl.createTexture();
                    gl.bindTexture(gl.TEXTURE_2D, t);
                    gl.texStorage2D(gl.TEXTURE_2D, e.mips, fmt, e.n, e.n);
                    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR_MIPMAP_NEAREST);
                    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
                    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.REPEAT);
                    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.REPEAT);
                    return t;
                };
                this.cas[c] = { key, patch: e.patchM, n: e.n, sigma: e.patchM / e.n, mips: e.mips, disp: mk(gl.RGBA16F), slope: mk(gl.RGBA16F), texels: 0 };
            }
            this.cas[c].fades = e.fades;
        }
        for (let c = nc; c < this.cas.length; c++) { gl.deleteTexture(this.cas[c].disp); gl.deleteTexture(this.cas[c].slope); }
        this.cas.length = nc;
        gl.pixelStorei(gl.UNPACK_ALIGNMENT, 4);
        let written = 0;
        for (const b of blocks) {
            const C = this.cas[b.cascade];
            if (!C || b.mip >= C.mips) continue;
            const side = C.n >> b.mip;
            if (b.x < 0 || b.y < 0 || b.x + b.w > side || b.y + b.h > side) continue;
            gl.bindTexture(gl.TEXTURE_2D, C.disp);
            gl.texSubImage2D(gl.TEXTURE_2D, b.mip, b.x, b.y, b.w, b.h, gl.RGBA, gl.FLOAT, b.disp);
            gl.bindTexture(gl.TEXTURE_2D, C.slope);
            gl.texSubImage2D(gl.TEXTURE_2D, b.mip, b.x, b.y, b.w, b.h, gl.RGBA, gl.FLOAT, b.slope);
            C.texels += b.w * b.h;
            written++;
        }
        this.block = block;
        if (placement) this.placement = { meshId: placement.meshId, origin: placement.origin.slice() };
        return written;
    }

    /* Uniforms of CASCADE_GLSL for program u, eye in world double. */
    cascadeUniforms(u, eye) {
        const gl = this.gl, b = this.block, nc = this.cas.length;
        const cas = new Float32Array(4 * MAX_CASCADES), ce = new Float32Array(2 * MAX_CASCADES);
        const casQ = new Float32Array(MAX_CASCADES);
        const tab = new Float32Array(4 * MIP_ENTRIES * MAX_CASCADES);
        const held = new Float32Array(4 * Math.ceil(MIP_ENTRIES * MAX_CASCADES / 4)).fill(1);
        for (let c = 0; c < nc; c++) {
            const C = this.cas[c], e = b.cascade[c];
            cas.set([C.patch, C.sigma, C.mips, C.fades], 4 * c);
            casQ[c] = e.spacingPerM;
            /* eye modulo the patch, in double, as texture coordinates */
            const m = (v) => { const r = v % C.patch; return (r < 0 ? r + C.patch : r) / C.patch; };
            ce[2 * c] = m(eye[0]);
            ce[2 * c + 1] = m(eye[2]);
            tab.set(e.mip, 4 * MIP_ENTRIES * c);
            /* the shading reads mip 0 by Keys (keys0), the rest bilinear */
            for (let k = 0; k < C.mips; k++) {
                const h = e.held ? e.held[READ.KERNELS * k + (k === 0 ? READ.KEYS : READ.BILINEAR)] : 0;
                held[MIP_ENTRIES * c + k] = h ? h / 32768 : 1;
            }
        }
        gl.uniform1i(u.u_nCas, nc);
        gl.uniform4fv(u.u_cas, cas);
        gl.uniform1fv(u.u_casQ, casQ);
        gl.uniform2fv(u.u_casEye, ce);
        gl.uniform4fv(u.u_mipTab, tab);
        gl.uniform4fv(u.u_mipHeld, held);
        gl.uniform3f(u.u_blk, b.spacingPerM, b.minSpacingM, b.camera[1]);
        gl.uniform2f(u.u_blkCam, b.camera[0] - eye[0], b.camera[2] - eye[2]);
        gl.uniform3fv(u.u_tailMss, b.tailMss);
        gl.uniform1f(u.u_roughScale, this.roughScale);
        gl.uniform1f(u.u_foamScale, this.foamScale);
        const ft = new Float32Array(3 * FOAM_ROWS);
        b.foam.forEach((r, i) => ft.set([r.sigma, r.a, r.omega], 3 * i));
        gl.uniform3fv(u.u_foamTab, ft);
        gl.uniform1i(u.u_foamRows, b.foam.length);
        const W = this.wake;
        gl.activeTexture(gl.TEXTURE12);
        gl.bindTexture(gl.TEXTURE_2D, W ? this.wakeTex : this.dummyTex);
        if (u.u_wakeTex) gl.uniform1i(u.u_wakeTex, 12);
        gl.uniform4f(u.u_wake, W ? W.x0 - eye[0] : 0, W ? W.z0 - eye[2] : 0, W ? W.dx : 1, W ? W.n : 0);
        for (let c = 0; c < MAX_CASCADES; c++) {
            gl.activeTexture(gl.TEXTURE4 + c);
            gl.bindTexture(gl.TEXTURE_2D, c < nc ? this.cas[c].disp : this.dummyTex);
            if (u[`u_cd${c}`]) gl.uniform1i(u[`u_cd${c}`], 4 + c);
            gl.activeTexture(gl.TEXTURE8 + c);
            gl.bindTexture(gl.TEXTURE_2D, c < nc ? this.cas[c].slope : this.dummyTex);
            if (u[`u_cs${c}`]) gl.uniform1i(u[`u_cs${c}`], 8 + c);
        }
    }

    allocTextures(w, h, l) {
        const gl = this.gl;
        for (const t of [this.dispTex, this.nrmTex]) {
            gl.bindTexture(gl.TEXTURE_2D_ARRAY, t);
            gl.texImage3D(gl.TEXTURE_2D_ARRAY, 0, gl.RGBA16F, w, h, l, 0, gl.RGBA, gl.FLOAT, null);
            gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
            gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
            gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
            gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
        }
        this.texW = w; this.texH = h; this.texL = l;
    }

    /* MESH_TOPOLOGY: indices, morph and level arrays; with FLAT (layout 1)
     * the flat positions and level zones, displaced in the vertex shader. */
    setTopology(t) {
        const gl = this.gl;
        if (t.flags & 1) {
            gl.bindVertexArray(this.vao1);
            gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.idx1Buf);
            gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, t.indices, gl.STATIC_DRAW);
            gl.bindBuffer(gl.ARRAY_BUFFER, this.flatBuf);
            gl.bufferData(gl.ARRAY_BUFFER, t.flat, gl.STATIC_DRAW);
            gl.enableVertexAttribArray(0);
            gl.vertexAttribPointer(0, 2, gl.FLOAT, false, 0, 0);
            gl.bindBuffer(gl.ARRAY_BUFFER, this.level1Buf);
            gl.bufferData(gl.ARRAY_BUFFER, t.level, gl.STATIC_DRAW);
            gl.enableVertexAttribArray(1);
            gl.vertexAttribPointer(1, 1, gl.UNSIGNED_BYTE, false, 0, 0);
            gl.bindVertexArray(null);
            const zones = new Float32Array(4 * MAX_LEVELS);
            zones.set(t.zones.subarray(0, 4 * Math.min(t.lodLevels, MAX_LEVELS)));
            let extent = 0;
            for (let i = 0; i < t.flat.length; i++) extent = Math.max(extent, Math.abs(t.flat[i]));
            this.topology1 = { meshId: t.meshId, vertexCount: t.vertexCount, lodLevels: Math.min(t.lodLevels, MAX_LEVELS), zones, extent };
            this.indexCount1 = t.indices.length;
            return;
        }
        gl.bindVertexArray(this.vao);
        gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, this.idxBuf);
        gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, t.indices, gl.STATIC_DRAW);
        gl.bindBuffer(gl.ARRAY_BUFFER, this.posBuf);
        gl.bufferData(gl.ARRAY_BUFFER, t.vertexCount * 12, gl.DYNAMIC_DRAW);
        gl.enableVertexAttribArray(0);
        gl.vertexAttribPointer(0, 3, gl.FLOAT, false, 0, 0);
        gl.bindBuffer(gl.ARRAY_BUFFER, this.morphBuf);
        gl.bufferData(gl.ARRAY_BUFFER, t.morph, gl.STATIC_DRAW);
        gl.enableVertexAttribArray(1);
        gl.vertexAttribPointer(1, 1, gl.FLOAT, false, 0, 0);
        gl.bindBuffer(gl.ARRAY_BUFFER, this.spacingBuf);
        gl.bufferData(gl.ARRAY_BUFFER, t.vertexCount * 4, gl.STATIC_DRAW);
        gl.enableVertexAttribArray(2);
        gl.vertexAttribPointer(2, 1, gl.FLOAT, false, 0, 0);
        gl.bindBuffer(gl.ARRAY_BUFFER, this.levelBuf);
        gl.bufferData(gl.ARRAY_BUFFER, t.level, gl.STATIC_DRAW);
        gl.enableVertexAttribArray(3);
        gl.vertexAttribPointer(3, 1, gl.UNSIGNED_BYTE, false, 0, 0);
        gl.bindVertexArray(null);
        this.topology = { meshId: t.meshId, vertexCount: t.vertexCount, indices: t.indices };
        this.indexCount = t.indices.length;
        this.vertexCount = t.vertexCount;
        this.mesh = null;
        this.needSpacing = true;
    }

    /* MESH_VERTICES (inside a FRAME or alone).  Ignored until the matching
     * topology arrived. */
    setVertices(v) {
        const t = this.topology;
        if (!t || v.meshId !== t.meshId || v.positions.length !== 3 * t.vertexCount) return false;
        const gl = this.gl;
        gl.bindBuffer(gl.ARRAY_BUFFER, this.posBuf);
        gl.bufferSubData(gl.ARRAY_BUFFER, 0, v.positions);
        if (this.needSpacing) {
            /* per-vertex mesh spacing (longest incident edge in xz): the
             * vertex shader's anti-aliasing footprint.  The topology is
             * fixed while the mesh slides, so this runs once per topology. */
            const sp = new Float32Array(t.vertexCount);
            const p = v.positions, ix = t.indices;
            for (let i = 0; i < ix.length; i += 3) {
                for (let e = 0; e < 3; e++) {
                    const a = ix[i + e], b = ix[i + (e + 1) % 3];
                    const d = Math.hypot(p[3 * a] - p[3 * b], p[3 * a + 2] - p[3 * b + 2]);
                    if (d > sp[a]) sp[a] = d;
                    if (d > sp[b]) sp[b] = d;
                }
            }
            gl.bindBuffer(gl.ARRAY_BUFFER, this.spacingBuf);
            gl.bufferData(gl.ARRAY_BUFFER, sp, gl.STATIC_DRAW);
            this.needSpacing = false;
        }
        /* oceand sends displaced positions (height, choppy x/z, near
         * field); a flat mesh (all y = 0) is displaced here from the tiles */
        let displaced = false;
        for (let i = 1; i < v.positions.length; i += 3) if (v.positions[i] !== 0) { displaced = true; break; }
        this.meshDisplaced = displaced;
        this.mesh = { meshId: v.meshId, origin: v.origin.slice() };
        return true;
    }

    /* Tile levels of one frame, as assembled by the worker. */
    setLevels(levels) {
        const gl = this.gl;
        const n = Math.min(levels.length, MAX_LEVELS);
        let w = this.texW, h = this.texH, l = this.texL;
        const needW = Math.max(2, ...levels.slice(0, n).map((x) => x.width));
        const needH = Math.max(2, ...levels.slice(0, n).map((x) => x.height));
        if (needW > w || needH > h || n > l) {
            this.allocTextures(Math.max(w, needW), Math.max(h, needH), Math.max(l, n, 1));
        }
        gl.pixelStorei(gl.UNPACK_ALIGNMENT, 4);
        for (let i = 0; i < n; i++) {
            const L = levels[i];
            gl.bindTexture(gl.TEXTURE_2D_ARRAY, this.dispTex);
            gl.texSubImage3D(gl.TEXTURE_2D_ARRAY, 0, 0, 0, i, L.width, L.height, 1, gl.RGBA, gl.FLOAT, L.disp);
            gl.bindTexture(gl.TEXTURE_2D_ARRAY, this.nrmTex);
            gl.texSubImage3D(gl.TEXTURE_2D_ARRAY, 0, 0, 0, i, L.width, L.height, 1, gl.RGBA, gl.FLOAT, L.nrm);
        }
        this.levels = levels.slice(0, n).map((L) => ({
            originX: L.originX, originZ: L.originZ, spacing: L.spacing, width: L.width, height: L.height,
        }));
    }

    initSkyCube() {
        const gl = this.gl;
        /* HDR cube map where float rendering is available, else RGBA8 holding radiance / 2 */
        const half = !!gl.getExtension('EXT_color_buffer_float');
        this.skyScale = half ? 1 : 2;
        this.skyCube = gl.createTexture();
        gl.bindTexture(gl.TEXTURE_CUBE_MAP, this.skyCube);
        /* mips: rough water reflects a blurred sky (textureLod by slope spread) */
        gl.texStorage2D(gl.TEXTURE_CUBE_MAP, Math.log2(SKY_CUBE) + 1, half ? gl.RGBA16F : gl.RGBA8, SKY_CUBE, SKY_CUBE);
        gl.texParameteri(gl.TEXTURE_CUBE_MAP, gl.TEXTURE_MIN_FILTER, gl.LINEAR_MIPMAP_LINEAR);
        gl.texParameteri(gl.TEXTURE_CUBE_MAP, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
        gl.texParameteri(gl.TEXTURE_CUBE_MAP, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
        gl.texParameteri(gl.TEXTURE_CUBE_MAP, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
        this.skyFbo = gl.createFramebuffer();
        this.skyStamp = -1e9;
        this.skyFace = 0;
        this.skyReady = false;
    }

    /* Sets the uniforms every pass shares. */
    common(u, eye, time) {
        const gl = this.gl;
        gl.uniform3fv(u.u_sunDir, this.sunDir);
        gl.uniform3fv(u.u_sunColor, this.sunColor);
        gl.uniform1f(u.u_time, time % 100000);
        /* texture offsets of the eye, reduced in double so float precision
         * holds however far from the origin (clouds drift with the wind) */
        const drift = 0.004 * time;
        const cu = CLOUD_SCALE / CLOUD_UV, gu = GRAIN_SCALE / CLOUD_UV;
        gl.uniform2f(u.u_cloudOff, frac(eye[0] * cu + this.wind[0] * drift / CLOUD_UV), frac(eye[2] * cu + this.wind[1] * drift / CLOUD_UV));
        /* the foam grain lives in the wind's frame, stretched 4 : 1 along
         * it (foamBreakUp), drifting downwind at 0.6 m/s */
        const [wx, wz] = this.wind, along = eye[0] * wx + eye[2] * wz, across = -eye[0] * wz + eye[2] * wx;
        gl.uniform2f(u.u_grainOff, frac((0.25 * along + 0.6 * 0.25 * time) * gu), frac(across * gu));
        gl.uniform1f(u.u_eyeY, eye[1]);
        gl.uniform2fv(u.u_wind, this.wind);
        gl.uniform1f(u.u_skyScale, this.skyScale);
        gl.activeTexture(gl.TEXTURE2);
        gl.bindTexture(gl.TEXTURE_2D, this.cloudTex);
        gl.uniform1i(u.u_cloudTex, 2);
        gl.activeTexture(gl.TEXTURE3);
        gl.bindTexture(gl.TEXTURE_CUBE_MAP, this.skyCube);
        gl.uniform1i(u.u_skyCube, 3);
    }

    /* Re-renders the sky cube map: all faces at first and whenever the sun
     * or the wind changed (the HELLO's sea usually arrives after the first
     * draw: faces of the default sky beside faces of the real one, changing
     * for a second and a half, would show as a sky that moves by itself),
     * then one face every so often (clouds drift slowly). */
    updateSkyCube(eye, time) {
        const gl = this.gl;
        const now = performance.now();
        const key = `${this.sunDir} ${this.sunColor} ${this.wind}`;
        if (key !== this.skyKey) this.skyReady = false;
        const faces = !this.skyReady ? [0, 1, 2, 3, 4, 5] : now - this.skyStamp > 250 ? [this.skyFace] : [];
        if (!faces.length) return;
        this.skyKey = key;
        gl.bindFramebuffer(gl.FRAMEBUFFER, this.skyFbo);
        gl.viewport(0, 0, SKY_CUBE, SKY_CUBE);
        gl.disable(gl.DEPTH_TEST);
        gl.useProgram(this.skygen.p);
        gl.activeTexture(gl.TEXTURE3);
        gl.bindTexture(gl.TEXTURE_CUBE_MAP, null);   /* not sampled while rendered to */
        const u = this.skygen.u;
        gl.uniform3fv(u.u_sunDir, this.sunDir);
        gl.uniform3fv(u.u_sunColor, this.sunColor);
        const drift = 0.004 * time, cu = CLOUD_SCALE / CLOUD_UV;
        gl.uniform2f(u.u_cloudOff, frac(eye[0] * cu + this.wind[0] * drift / CLOUD_UV), frac(eye[2] * cu + this.wind[1] * drift / CLOUD_UV));
        gl.uniform1f(u.u_eyeY, eye[1]);
        gl.uniform1f(u.u_skyScale, this.skyScale);
        gl.uniform1f(u.u_size, SKY_CUBE);
        gl.activeTexture(gl.TEXTURE2);
        gl.bindTexture(gl.TEXTURE_2D, this.cloudTex);
        gl.uniform1i(u.u_cloudTex, 2);
        gl.bindVertexArray(this.emptyVao);
        for (const f of faces) {
            gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_CUBE_MAP_POSITIVE_X + f, this.skyCube, 0);
            gl.uniform1i(u.u_face, f);
            gl.drawArrays(gl.TRIANGLES, 0, 3);
        }
        gl.bindFramebuffer(gl.FRAMEBUFFER, null);
        gl.bindTexture(gl.TEXTURE_CUBE_MAP, this.skyCube);
        gl.generateMipmap(gl.TEXTURE_CUBE_MAP);
        this.skyFace = (this.skyFace + 1) % 6;
        this.skyStamp = now;
        this.skyReady = true;
    }

    resize() {
        const dpr = Math.min(window.devicePixelRatio || 1, 2) * this.scale;
        const c = this.canvas;
        const w = Math.max(1, Math.round(c.clientWidth * dpr)), h = Math.max(1, Math.round(c.clientHeight * dpr));
        if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
        return [w, h];
    }

    /* cam: {pos[3] (world, double), basis {fwd, right, up}, fovYDeg}; time: sim time estimate. */
    draw(cam, time) {
        const gl = this.gl;
        this.updateSkyCube(cam.pos, time);
        const [W, H] = this.resize();
        gl.viewport(0, 0, W, H);
        const aspect = W / H;
        const fov = cam.fovYDeg * Math.PI / 180;
        const tanH = Math.tan(fov / 2);
        const { fwd, right, up } = cam.basis;
        const eye = cam.pos;
        const common = (u) => this.common(u, eye, time);

        const cascaded = this.layout === 1 && !!this.block && this.cas.length > 0;
        const skyPass = (sky, depthTested) => {
            if (depthTested) {
                /* only where the mesh left the far plane: the far sea and
                 * the sky are not shaded twice */
                gl.enable(gl.DEPTH_TEST);
                gl.depthFunc(gl.LEQUAL);
            } else {
                gl.disable(gl.DEPTH_TEST);
            }
            gl.depthMask(false);
            gl.useProgram(sky.p);
            common(sky.u);
            if (sky === this.sky1) {
                this.cascadeUniforms(sky.u, eye);
                gl.uniform1f(sky.u.u_pixAngle, 2 * tanH / H);
            }
            gl.uniform3fv(sky.u.u_right, right);
            gl.uniform3fv(sky.u.u_up, up);
            gl.uniform3fv(sky.u.u_fwd, fwd);
            gl.uniform2f(sky.u.u_tanHalf, tanH * aspect, tanH);
            gl.bindVertexArray(this.emptyVao);
            gl.drawArrays(gl.TRIANGLES, 0, 3);
        };

        if (this.layout === 1) {
            /* layout 1: the mesh first, then sky and far sea (shaded from
             * the cascades like the mesh) where the mesh did not draw */
            gl.depthMask(true);
            gl.clearDepth(1);
            gl.clear(gl.DEPTH_BUFFER_BIT);
            const t1 = this.topology1, pl = this.placement;
            const ok = cascaded && t1 && pl && pl.meshId === t1.meshId && this.drawSea !== false;
            if (ok) {
                const near = Math.max(0.05, Math.min(1.0, Math.abs(eye[1]) * 0.05));
                const vp = mul4(perspective(fov, aspect, near, 400000), new Float32Array([
                    right[0], up[0], -fwd[0], 0, right[1], up[1], -fwd[1], 0, right[2], up[2], -fwd[2], 0, 0, 0, 0, 1,
                ]));
                gl.enable(gl.DEPTH_TEST);
                gl.depthFunc(gl.LEQUAL);
                gl.disable(gl.CULL_FACE);
                const s1 = this.wake ? this.sea1w : this.sea1;
                gl.useProgram(s1.p);
                common(s1.u);
                this.cascadeUniforms(s1.u, eye);
                gl.uniformMatrix4fv(s1.u.u_viewProj, false, vp);
                /* placement origin relative to the eye, in double */
                gl.uniform3f(s1.u.u_meshOff, pl.origin[0] - eye[0], pl.origin[1] - eye[1], pl.origin[2] - eye[2]);
                gl.uniform4fv(s1.u.u_zone, t1.zones);
                gl.uniform1i(s1.u.u_lodLevels, t1.lodLevels);
                gl.uniform1f(s1.u.u_pixAngle, 2 * tanH / H);
                gl.uniform1f(s1.u.u_debug, this.debug ? 1 : 0);
                gl.uniform1f(s1.u.u_hs, this.hs);
                gl.bindVertexArray(this.vao1);
                gl.drawElements(gl.TRIANGLES, this.indexCount1, gl.UNSIGNED_INT, 0);
                gl.bindVertexArray(null);
            }
            skyPass(cascaded ? this.sky1 : this.sky, true);
            return !!ok;
        }

        /* sky and far sea */
        skyPass(this.sky, false);
        if (!this.mesh || !this.indexCount || this.drawSea === false) return false;

        /* the sea mesh */
        const near = Math.max(0.05, Math.min(1.0, Math.abs(eye[1]) * 0.05));
        const far = 400000;
        const proj = perspective(fov, aspect, near, far);
        const view = new Float32Array([
            right[0], up[0], -fwd[0], 0,
            right[1], up[1], -fwd[1], 0,
            right[2], up[2], -fwd[2], 0,
            0, 0, 0, 1,
        ]);
        const vp = mul4(proj, view);
        gl.enable(gl.DEPTH_TEST);
        gl.depthFunc(gl.LEQUAL);
        gl.depthMask(true);
        gl.clear(gl.DEPTH_BUFFER_BIT);
        gl.disable(gl.CULL_FACE);   /* waves fold; draw both faces */
        const s = this.sea;
        gl.useProgram(s.p);
        common(s.u);
        gl.uniformMatrix4fv(s.u.u_viewProj, false, vp);
        const mo = this.mesh.origin;
        gl.uniform3f(s.u.u_meshOff, mo[0] - eye[0], mo[1] - eye[1], mo[2] - eye[2]);
        gl.uniform1f(s.u.u_pixAngle, 2 * tanH / H);
        gl.uniform1f(s.u.u_debug, this.debug ? 1 : 0);
        gl.uniform1f(s.u.u_hs, this.hs);
        gl.uniform1f(s.u.u_applyTiles, this.meshDisplaced ? 0 : this.applyTiles);
        const nl = this.levels.length;
        const A = new Float32Array(4 * MAX_LEVELS), B = new Float32Array(4 * MAX_LEVELS);
        for (let i = 0; i < nl; i++) {
            const L = this.levels[i];
            A.set([L.originX - eye[0], L.originZ - eye[2], L.spacing, i], 4 * i);
            B.set([L.width, L.height, Math.max(2, 0.12 * Math.min(L.width, L.height)), 1], 4 * i);
        }
        gl.uniform1i(s.u.u_nLevels, nl);
        gl.uniform4fv(s.u.u_lvlA, A);
        gl.uniform4fv(s.u.u_lvlB, B);
        gl.uniform2f(s.u.u_texSize, this.texW, this.texH);
        gl.activeTexture(gl.TEXTURE0);
        gl.bindTexture(gl.TEXTURE_2D_ARRAY, this.dispTex);
        gl.uniform1i(s.u.u_disp, 0);
        gl.activeTexture(gl.TEXTURE1);
        gl.bindTexture(gl.TEXTURE_2D_ARRAY, this.nrmTex);
        gl.uniform1i(s.u.u_nrm, 1);
        gl.bindVertexArray(this.vao);
        gl.drawElements(gl.TRIANGLES, this.indexCount, gl.UNSIGNED_INT, 0);
        gl.bindVertexArray(null);
        return true;
    }
}

function frac(a) { return a - Math.floor(a); }

/* Tileable value-noise fbm (period CLOUD_UV lattice units at the base
 * octave), CLOUD_TEX x CLOUD_TEX bytes: clouds, their shadows and the foam
 * grain all read it (an R8 texture with mipmaps), instead of evaluating
 * noise per pixel.  ocean-sim render (sim/cli/render_shade.c) makes the
 * same bytes for its reference images. */
export function cloudTextureBytes() {
    const N = CLOUD_TEX, P = CLOUD_UV;
    const hash = (x, y, o) => {
        let h = (x * 374761393 + y * 668265263 + o * 2147483647) | 0;
        h = Math.imul(h ^ (h >>> 13), 1274126177);
        return ((h ^ (h >>> 16)) >>> 0) / 4294967296;
    };
    const img = new Uint8Array(N * N);
    const octaves = 5;
    for (let y = 0; y < N; y++) {
        for (let x = 0; x < N; x++) {
            let s = 0, a = 0.5, norm = 0;
            for (let o = 0; o < octaves; o++) {
                const per = P << o;                  /* lattice period at this octave */
                const fx = x / N * per, fy = y / N * per;
                const ix = Math.floor(fx), iy = Math.floor(fy);
                const tx = fx - ix, ty = fy - iy;
                const ux = tx * tx * (3 - 2 * tx), uy = ty * ty * (3 - 2 * ty);
                const x0 = ix % per, y0 = iy % per, x1 = (ix + 1) % per, y1 = (iy + 1) % per;
                const v = (hash(x0, y0, o) * (1 - ux) + hash(x1, y0, o) * ux) * (1 - uy) +
                          (hash(x0, y1, o) * (1 - ux) + hash(x1, y1, o) * ux) * uy;
                s += a * v; norm += a; a *= 0.5;
            }
            img[y * N + x] = Math.round(255 * s / norm);
        }
    }
    return img;
}

function makeCloudTexture(gl) {
    const N = CLOUD_TEX, img = cloudTextureBytes();
    const t = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, t);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.R8, N, N, 0, gl.RED, gl.UNSIGNED_BYTE, img);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 4);
    gl.generateMipmap(gl.TEXTURE_2D);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR_MIPMAP_LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.REPEAT);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.REPEAT);
    return t;
}
export function normalize3(v) {
    const l = Math.hypot(v[0], v[1], v[2]) || 1;
    return [v[0] / l, v[1] / l, v[2] / l];
}
