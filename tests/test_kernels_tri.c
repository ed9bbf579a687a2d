/* Triangle kernels of one algorithm (family tri_moller or tri_watertight):
 * tri_packet and tri_packet_any (by position and through an index array),
 * tri_wide, tri_wide_closest and tri_wide_any, on the same ray/triangle
 * pairs for every set, against ref_tri().
 *
 * As for boxes, cases come in blocks of nr rays x nt triangles, starting at
 * multiples of LANES_MAX_W, with garbage between blocks. Block kinds: random
 * triangles (needles, tiny, degenerate ones among them), height-field
 * meshes whose shared edges and vertices are the targets of "probe" rays
 * (a watertight test must report at least one hit for each), stacks of
 * copies at several depths with exact duplicates (ties for the closest hit)
 * and fans around one vertex. */
#include <float.h>
#include <stdlib.h>

#include "test_kernels_common.h"

#define TR_MAXN 72

typedef struct {
    size_t r0, nr, p0, np, pair0;
    bool mesh;   /* the triangles form a mesh without holes over the probes' targets */
    bool shared; /* triangles share edges or are copies: a ray aimed at the boundary
                  * of one is at the boundary of others */
} tr_block;

enum { PF_HARD = 1, PF_TARGETED = 2 };
/* Ray classes: generic; aimed at the boundary of its target triangle; or
 * stressing precision against every triangle of the block (far origins,
 * translated blocks, mesh probes). */
enum { RC_GENERIC = 0, RC_TARGET = 1, RC_STRESS = 2 };

typedef struct {
    ref_ray *raw;
    bool *ray_gap, *probe;
    uint8_t *targeted; /* RC_*: how the ray was built */
    int32_t *target;
    size_t nrays, cap_r;
    float (*v)[3][3]; /* [tri][vertex][axis] */
    bool *tri_gap, *tri_special;
    size_t ntris, cap_t;
    tr_block *blocks;
    size_t nblocks, cap_k;
    size_t npairs;
    /* per pair */
    uint8_t *ref_hit, *flags;
    float *margin, *tscale, *uscale, *vscale;
    double *rt, *ru, *rv;
    int16_t *hand;
} tr_set;

static void *grow_to(void *p, size_t cap, size_t elem)
{
    p = realloc(p, cap * elem);
    if (!p) abort();
    return p;
}
static size_t round_up(size_t x) { return (x + LANES_MAX_W - 1) / LANES_MAX_W * LANES_MAX_W; }
static size_t new_cap(size_t cap, size_t need)
{
    size_t c = cap ? cap : 4096;
    while (c < need) c *= 2;
    return c;
}

static tr_block *tr_new_block(tr_set *s, size_t nr, size_t np)
{
    size_t r0 = round_up(s->nrays), p0 = round_up(s->ntris);
    if (r0 + nr > s->cap_r) {
        s->cap_r = new_cap(s->cap_r, r0 + nr);
        s->raw = grow_to(s->raw, s->cap_r, sizeof *s->raw);
        s->ray_gap = grow_to(s->ray_gap, s->cap_r, sizeof *s->ray_gap);
        s->probe = grow_to(s->probe, s->cap_r, sizeof *s->probe);
        s->targeted = grow_to(s->targeted, s->cap_r, sizeof *s->targeted);
        s->target = grow_to(s->target, s->cap_r, sizeof *s->target);
    }
    for (size_t i = s->nrays; i < r0 + nr; i++) {
        s->ray_gap[i] = i < r0;
        s->probe[i] = false;
        s->targeted[i] = RC_GENERIC;
        s->target[i] = -1;
        memset(&s->raw[i], 0, sizeof s->raw[i]);
        s->raw[i].o[0] = NAN;
    }
    s->nrays = r0 + nr;
    if (p0 + np > s->cap_t) {
        s->cap_t = new_cap(s->cap_t, p0 + np);
        s->v = grow_to(s->v, s->cap_t, sizeof *s->v);
        s->tri_gap = grow_to(s->tri_gap, s->cap_t, sizeof *s->tri_gap);
        s->tri_special = grow_to(s->tri_special, s->cap_t, sizeof *s->tri_special);
    }
    for (size_t i = s->ntris; i < p0 + np; i++) {
        s->tri_gap[i] = i < p0;
        s->tri_special[i] = false;
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 3; a++) s->v[i][k][a] = NAN;
    }
    s->ntris = p0 + np;
    if (s->nblocks + 1 > s->cap_k) {
        s->cap_k = new_cap(s->cap_k, s->nblocks + 1);
        s->blocks = grow_to(s->blocks, s->cap_k, sizeof *s->blocks);
    }
    tr_block *b = &s->blocks[s->nblocks++];
    b->r0 = r0, b->nr = nr, b->p0 = p0, b->np = np, b->pair0 = s->npairs, b->mesh = b->shared = false;
    s->npairs += nr * np;
    return b;
}

/* ---- generation ---- */

typedef struct {
    double S, C[3];
} tr_frame;

static void random_frame(tk_rng *g, tr_frame *f)
{
    /* scales 2^-20 .. 2^20 and offsets to 2^16 sizes: the float range where
     * the products of three coordinates neither underflow nor overflow */
    f->S = tk_chance(g, 0.7) ? 1.0 : exp2(tk_range(g, -20, 20));
    for (int a = 0; a < 3; a++)
        f->C[a] = tk_chance(g, 0.75) ? 0.0 : tk_sign(g) * f->S * exp2(tk_range(g, 0, 16));
}

static void random_tri(tk_rng *g, const tr_frame *f, float v[3][3], bool *special)
{
    double c[3], size = f->S * exp2(tk_range(g, -6, 0));
    for (int a = 0; a < 3; a++) c[a] = f->C[a] + f->S * tk_range(g, -1, 1);
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 3; a++) v[k][a] = (float)(c[a] + size * tk_range(g, -1, 1));
    *special = false;
    double p = tk_unit(g);
    if (p < 0.04) {
        /* degenerate: a repeated vertex, a point, or exactly collinear */
        *special = true;
        switch (tk_below(g, 3)) {
        case 0: memcpy(v[2], v[tk_below(g, 2)], sizeof v[2]); break;
        case 1: memcpy(v[1], v[0], sizeof v[1]), memcpy(v[2], v[0], sizeof v[2]); break;
        default:
            /* v2 = v0 + 2 (v1 - v0) with dyadic coordinates: exact */
            for (int a = 0; a < 3; a++) {
                v[0][a] = (float)ldexp(floor(ldexp(v[0][a], 8)), -8);
                v[1][a] = (float)ldexp(floor(ldexp(v[1][a], 8)), -8);
                v[2][a] = v[0][a] + 2 * (v[1][a] - v[0][a]);
            }
            break;
        }
    } else if (p < 0.10) {
        /* a needle: one vertex very close to the opposite edge, so that
         * every point is close to an edge */
        *special = true;
        double t = tk_unit(g), e = exp2(tk_range(g, -20, -8));
        for (int a = 0; a < 3; a++)
            v[2][a] = (float)(v[0][a] + t * (v[1][a] - (double)v[0][a]) + e * size * tk_range(g, -1, 1));
    } else if (p < 0.16) {
        /* axis-aligned plane: exact in-plane rays are possible */
        int a = (int)tk_below(g, 3);
        v[1][a] = v[2][a] = v[0][a];
    }
}

static void tri_point(const float v[3][3], double b1, double b2, double p[3])
{
    for (int a = 0; a < 3; a++) p[a] = v[0][a] + b1 * (v[1][a] - (double)v[0][a]) + b2 * (v[2][a] - (double)v[0][a]);
}

static void set_dir(tk_rng *g, ref_ray *r, const double d[3])
{
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    double scale = exp2(tk_range(g, -4, 4));
    if (len == 0 || !isfinite(len)) len = 1;
    for (int a = 0; a < 3; a++) r->d[a] = (float)(d[a] / len * scale);
}

static void corrupt_ray(tk_rng *g, ref_ray *r)
{
    float nan = tk_from_bits(0x7fc00000u | tk_below(g, 1u << 22));
    switch (tk_below(g, 6)) {
    case 0: r->o[tk_below(g, 3)] = nan; break;
    case 1: r->d[tk_below(g, 3)] = nan; break;
    case 2: r->o[tk_below(g, 3)] = (float)tk_sign(g) * INFINITY; break;
    case 3: r->d[tk_below(g, 3)] = (float)tk_sign(g) * INFINITY; break;
    case 4: r->tnear = nan; break;
    default:
        for (int a = 0; a < 3; a++) r->d[a] = tk_chance(g, 0.5) ? 0.0f : -0.0f;
        break;
    }
}

/* tnear/tfar: mostly [0, inf); sometimes set on or next to the hit distance */
static bool random_t(tk_rng *g, const tr_frame *f, ref_ray *r, const float v[3][3])
{
    r->tnear = 0.0f, r->tfar = INFINITY;
    double p = tk_unit(g);
    if (p < 0.6) return false;
    if (p < 0.68) {
        r->tnear = tk_chance(g, 0.5) ? -INFINITY : (float)(-f->S * tk_unit(g));
        return false;
    }
    if (p < 0.9) {
        ref_tri_result rr = ref_tri(r, v[0], v[1], v[2]);
        if (!isfinite(rr.t)) return false;
        int k = (int)tk_below(g, 5) - 2;
        float t = tk_ulps((float)rr.t, k);
        switch (tk_below(g, 3)) {
        case 0: r->tfar = t; break;
        case 1: r->tnear = t; break;
        default: r->tnear = r->tfar = t; break;
        }
        return true;
    }
    if (p < 0.95) {
        r->tfar = 0.0f;
        return true;
    }
    double a = tk_range(g, -1, 10) * f->S, b = tk_range(g, -1, 10) * f->S;
    r->tnear = (float)fmin(a, b), r->tfar = (float)fmax(a, b);
    return false;
}

/* A ray aimed at triangle *target of the block (or anywhere); returns its
 * class (RC_*). */
static int random_ray(tk_rng *g, const tr_frame *f, const float (*tris)[3][3], size_t nt,
                       ref_ray *r, size_t *target)
{
    size_t ti = tk_below(g, (uint32_t)nt);
    *target = ti;
    const float(*v)[3] = tris[ti];
    int targeted = RC_GENERIC;
    double aim[3], d[3];
    for (int a = 0; a < 3; a++) r->o[a] = (float)(f->C[a] + f->S * 4 * tk_range(g, -1, 1));
    double p = tk_unit(g);
    if (p < 0.25) {
        double r1 = tk_unit(g), r2 = tk_unit(g), s = sqrt(r1);
        tri_point(v, s * (1 - r2), s * r2, aim);
    } else if (p < 0.45) {
        /* an edge point, perhaps moved by a few floats */
        targeted = RC_TARGET;
        int e = (int)tk_below(g, 3);
        double t = tk_chance(g, 0.2) ? tk_below(g, 9) / 8.0 : tk_unit(g);
        for (int a = 0; a < 3; a++) aim[a] = v[e][a] + t * (v[(e + 1) % 3][a] - (double)v[e][a]);
        if (tk_chance(g, 0.5)) {
            int a = (int)tk_below(g, 3);
            aim[a] = tk_ulps((float)aim[a], (int)tk_below(g, 9) - 4);
        }
    } else if (p < 0.55) {
        /* a vertex */
        targeted = RC_TARGET;
        int k = (int)tk_below(g, 3);
        for (int a = 0; a < 3; a++) aim[a] = tk_ulps(v[k][a], tk_chance(g, 0.5) ? 0 : (int)tk_below(g, 5) - 2);
    } else if (p < 0.65) {
        /* axis-parallel: the direction along one axis, ±0 elsewhere */
        double r1 = tk_unit(g), r2 = tk_unit(g), s = sqrt(r1);
        int mode = (int)tk_below(g, 3);
        if (mode == 0)
            tri_point(v, s * (1 - r2), s * r2, aim);
        else
            for (int a = 0; a < 3; a++) aim[a] = v[mode][a];
        int ax = (int)tk_below(g, 3);
        double dist = f->S * tk_range(g, 0.5, 4) * tk_sign(g);
        for (int a = 0; a < 3; a++) {
            r->o[a] = (float)aim[a];
            r->d[a] = tk_chance(g, 0.5) ? 0.0f : -0.0f;
        }
        r->o[ax] = (float)(aim[ax] - dist);
        r->d[ax] = (float)(dist > 0 ? 1.0 : -1.0) * (float)exp2(tk_range(g, -3, 3));
        if (mode != 0) targeted = RC_TARGET;
        if (random_t(g, f, r, v)) targeted = RC_TARGET;
        return targeted;
    } else if (p < 0.75) {
        /* grazing: nearly in the triangle's plane */
        targeted = RC_TARGET;
        double r1 = tk_unit(g), r2 = tk_unit(g), s = sqrt(r1), q[3];
        tri_point(v, s * (1 - r2), s * r2, q);
        double e1[3], e2[3], n[3];
        for (int a = 0; a < 3; a++) e1[a] = v[1][a] - (double)v[0][a], e2[a] = v[2][a] - (double)v[0][a];
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double ln = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), le = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
        if (ln == 0 || le == 0) {
            for (int a = 0; a < 3; a++) aim[a] = q[a];
        } else {
            double tilt = tk_chance(g, 0.3) ? 0.0 : exp2(tk_range(g, -24, -4)) * tk_sign(g);
            for (int a = 0; a < 3; a++) d[a] = e1[a] / le + tilt * n[a] / ln;
            for (int a = 0; a < 3; a++) r->o[a] = (float)(q[a] - f->S * d[a]);
            set_dir(g, r, d);
            if (random_t(g, f, r, v)) targeted = RC_TARGET;
            return targeted;
        }
    } else if (p < 0.82) {
        /* from a point of the triangle (t = 0) */
        targeted = RC_TARGET;
        double r1 = tk_unit(g), r2 = tk_unit(g), s = sqrt(r1), q[3];
        tri_point(v, s * (1 - r2), s * r2, q);
        for (int a = 0; a < 3; a++) r->o[a] = (float)q[a], aim[a] = q[a] + tk_range(g, -1, 1);
    } else if (p < 0.9) {
        /* from far away: the float error near every edge grows with the
         * distance, so these are precision stress cases */
        targeted = RC_STRESS;
        double r1 = tk_unit(g), r2 = tk_unit(g), s = sqrt(r1);
        tri_point(v, s * (1 - r2), s * r2, aim);
        double dist = f->S * exp2(tk_range(g, 3, 14));
        for (int a = 0; a < 3; a++) r->o[a] = (float)(aim[a] + dist * tk_range(g, -1, 1));
    } else {
        for (int a = 0; a < 3; a++) aim[a] = r->o[a] + tk_range(g, -1, 1);
    }
    for (int a = 0; a < 3; a++) d[a] = aim[a] - r->o[a];
    set_dir(g, r, d);
    if (random_t(g, f, r, v) && targeted == RC_GENERIC) targeted = RC_TARGET;
    return targeted;
}

static size_t block_size(tk_rng *g) { return tk_chance(g, 0.3) ? 1 + tk_below(g, 17) : 1 + tk_below(g, 64); }

/* A block far from the origin works with coordinates much larger than its
 * triangles: its rays are precision stress cases as well. */
static bool translated(const tr_frame *f) { return f->C[0] != 0 || f->C[1] != 0 || f->C[2] != 0; }

static void fill_rays(tk_rng *g, tr_set *s, const tr_block *b, const tr_frame *f)
{
    for (size_t i = 0; i < b->nr; i++) {
        size_t t;
        ref_ray *r = &s->raw[b->r0 + i];
        int cls = random_ray(g, f, (const float(*)[3][3])(s->v + b->p0), b->np, r, &t);
        s->targeted[b->r0 + i] = (uint8_t)(translated(f) ? RC_STRESS : cls);
        s->target[b->r0 + i] = (int32_t)t;
        if (tk_chance(g, 0.02)) corrupt_ray(g, r);
    }
}

static void random_block(tk_rng *g, tr_set *s)
{
    tr_frame f;
    random_frame(g, &f);
    double kind = tk_unit(g);
    if (kind < 0.55) {
        tr_block *b = tr_new_block(s, block_size(g), block_size(g) / 2 + 1);
        for (size_t i = 0; i < b->np; i++) random_tri(g, &f, s->v[b->p0 + i], &s->tri_special[b->p0 + i]);
        fill_rays(g, s, b, &f);
    } else if (kind < 0.8) {
        /* a height field of nx x ny cells, two triangles each, every vertex
         * shared exactly; probes aim at interior vertices and edge points
         * from above */
        int nx = 1 + (int)tk_below(g, 4), ny = 1 + (int)tk_below(g, 4);
        size_t np = (size_t)(2 * nx * ny);
        tr_block *b = tr_new_block(s, block_size(g), np);
        b->mesh = true;
        float P[5][5][3];
        double cell = f.S * exp2(tk_range(g, -3, 0)), rough = tk_chance(g, 0.3) ? 0 : cell * tk_unit(g);
        for (int i = 0; i <= nx; i++)
            for (int j = 0; j <= ny; j++) {
                P[i][j][0] = (float)(f.C[0] + cell * i);
                P[i][j][1] = (float)(f.C[1] + cell * j);
                P[i][j][2] = (float)(f.C[2] + rough * tk_range(g, -1, 1));
            }
        size_t t = b->p0;
        for (int i = 0; i < nx; i++)
            for (int j = 0; j < ny; j++) {
                bool flip = tk_chance(g, 0.5); /* diagonal direction and winding vary */
                const float *a = P[i][j], *bb = P[i + 1][j], *c = P[i + 1][j + 1], *dd = P[i][j + 1];
                const float *q[2][3] = {{a, bb, flip ? dd : c}, {flip ? bb : a, c, dd}};
                for (int h = 0; h < 2; h++, t++) {
                    bool rev = tk_chance(g, 0.5);
                    for (int k = 0; k < 3; k++) memcpy(s->v[t][rev ? (3 - k) % 3 : k], q[h][k], sizeof(float[3]));
                }
            }
        /* the probes */
        for (size_t i = 0; i < b->nr; i++) {
            ref_ray *r = &s->raw[b->r0 + i];
            double aim[3];
            if (tk_chance(g, 0.4) && nx > 1 && ny > 1) {
                int ii = 1 + (int)tk_below(g, (uint32_t)(nx - 1)), jj = 1 + (int)tk_below(g, (uint32_t)(ny - 1));
                for (int a = 0; a < 3; a++) aim[a] = P[ii][jj][a];
            } else {
                /* a point of a random edge inside the grid (or on its border
                 * when the grid is one cell wide: still one triangle there) */
                size_t tt = b->p0 + tk_below(g, (uint32_t)np);
                int e = (int)tk_below(g, 3);
                double u = tk_below(g, 1023) / 1024.0 + 1.0 / 2048;
                for (int a = 0; a < 3; a++)
                    aim[a] = s->v[tt][e][a] + u * (s->v[tt][(e + 1) % 3][a] - (double)s->v[tt][e][a]);
                /* keep it off the border of the grid */
                double lo0 = f.C[0], hi0 = f.C[0] + cell * nx, lo1 = f.C[1], hi1 = f.C[1] + cell * ny;
                double m = cell * 0.25;
                aim[0] = fmin(fmax(aim[0], lo0 + m), hi0 - m);
                aim[1] = fmin(fmax(aim[1], lo1 + m), hi1 - m);
            }
            double d[3] = {tk_range(g, -0.5, 0.5), tk_range(g, -0.5, 0.5), -1};
            if (tk_chance(g, 0.3)) d[0] = d[1] = 0;
            double h = cell * exp2(tk_range(g, 0, 4));
            for (int a = 0; a < 3; a++) r->o[a] = (float)(aim[a] - h * d[a]);
            set_dir(g, r, d);
            r->tnear = 0, r->tfar = INFINITY;
            s->probe[b->r0 + i] = true;
            s->targeted[b->r0 + i] = RC_STRESS;
        }
    } else if (kind < 0.92) {
        /* stacks: copies of a triangle along a direction, with duplicates */
        tr_block *b = tr_new_block(s, block_size(g), 2 + tk_below(g, 30));
        b->shared = true;
        float base[3][3];
        bool sp;
        random_tri(g, &f, base, &sp);
        /* copies and duplicates are coincidences built on purpose: whatever
         * lands near one boundary lands near all the copies' */
        for (size_t i = 0; i < b->np; i++) s->tri_special[b->p0 + i] = true;
        double dir[3] = {tk_range(g, -1, 1), tk_range(g, -1, 1), tk_range(g, -1, 1)};
        for (size_t i = 0; i < b->np; i++) {
            size_t t = b->p0 + i;
            if (i > 0 && tk_chance(g, 0.3)) {
                memcpy(s->v[t], s->v[t - 1 - tk_below(g, (uint32_t)i)], sizeof s->v[t]);
                continue;
            }
            double step = f.S * 0.25 * tk_below(g, 8);
            for (int k = 0; k < 3; k++)
                for (int a = 0; a < 3; a++) s->v[t][k][a] = (float)(base[k][a] + step * dir[a]);
        }
        fill_rays(g, s, b, &f);
    } else {
        /* a fan of six triangles around one vertex */
        tr_block *b = tr_new_block(s, block_size(g), 6);
        b->mesh = true;
        double c[3], ax[3] = {tk_range(g, -1, 1), tk_range(g, -1, 1), tk_range(g, -1, 1)}, by[3];
        for (int a = 0; a < 3; a++) c[a] = f.C[a] + f.S * tk_range(g, -1, 1);
        double pick[3] = {tk_range(g, -1, 1), tk_range(g, -1, 1), tk_range(g, -1, 1)};
        by[0] = ax[1] * pick[2] - ax[2] * pick[1];
        by[1] = ax[2] * pick[0] - ax[0] * pick[2];
        by[2] = ax[0] * pick[1] - ax[1] * pick[0];
        float ring[6][3], centre[3];
        for (int a = 0; a < 3; a++) centre[a] = (float)c[a];
        for (int k = 0; k < 6; k++) {
            double ang = k * 3.14159265358979 / 3, rr = f.S * tk_range(g, 0.5, 1);
            for (int a = 0; a < 3; a++) ring[k][a] = (float)(c[a] + rr * (cos(ang) * ax[a] + sin(ang) * by[a]));
        }
        for (int k = 0; k < 6; k++) {
            float(*t)[3] = s->v[b->p0 + (size_t)k];
            memcpy(t[0], centre, sizeof centre);
            memcpy(t[1], ring[k], sizeof centre);
            memcpy(t[2], ring[(k + 1) % 6], sizeof centre);
        }
        double n[3] = {ax[1] * by[2] - ax[2] * by[1], ax[2] * by[0] - ax[0] * by[2], ax[0] * by[1] - ax[1] * by[0]};
        for (size_t i = 0; i < b->nr; i++) {
            ref_ray *r = &s->raw[b->r0 + i];
            double d[3], aim[3];
            for (int a = 0; a < 3; a++) aim[a] = centre[a];
            if (tk_chance(g, 0.5)) {
                /* or a point on one of the spokes */
                int k = (int)tk_below(g, 6);
                double u = tk_range(g, 0.05, 0.95);
                for (int a = 0; a < 3; a++) aim[a] = centre[a] + u * (ring[k][a] - (double)centre[a]);
            }
            for (int a = 0; a < 3; a++) d[a] = n[a] * tk_sign(g) + 0.5 * tk_range(g, -1, 1) * (ax[a] + by[a]);
            for (int a = 0; a < 3; a++) r->o[a] = (float)(aim[a] - f.S * d[a]);
            set_dir(g, r, d);
            r->tnear = 0, r->tfar = INFINITY;
            s->probe[b->r0 + i] = true;
            s->targeted[b->r0 + i] = RC_STRESS;
        }
    }
}

/* ---- hand-written cases (shared/research/robustness.md §7b) ---- */

typedef struct {
    char name[80];
    ref_ray r;
    float v[3][3];
    int hit;
    double t;  /* expected t when hit (NAN: not stated) */
    int hard;  /* HARD_*: the algorithms that decide it exactly */
} tr_hand;

enum { HARD_MOLLER = 1, HARD_WT = 2, HARD_BOTH = 3 };

#define TH_MAX 64

static int add(tr_hand *h, int n, const char *name, ref_ray r, const float v0[3], const float v1[3],
               const float v2[3], int hit, double t, int hard)
{
    if (n >= TH_MAX) abort();
    snprintf(h[n].name, sizeof h[n].name, "%s", name);
    h[n].r = r;
    memcpy(h[n].v[0], v0, sizeof h[n].v[0]);
    memcpy(h[n].v[1], v1, sizeof h[n].v[1]);
    memcpy(h[n].v[2], v2, sizeof h[n].v[2]);
    h[n].hit = hit, h[n].t = t, h[n].hard = hard;
    return n + 1;
}

static ref_ray mk(float ox, float oy, float oz, float dx, float dy, float dz, float tn, float tf)
{
    ref_ray r = {{ox, oy, oz}, {dx, dy, dz}, tn, tf};
    return r;
}

static int hand_cases(tr_hand *h)
{
    const float A[3] = {0, 0, 0}, B[3] = {1, 0, 0}, C[3] = {0, 1, 0}, D[3] = {1, 1, 0};
    const float inf = INFINITY;
    int n = 0;
    n = add(h, n, "interior", mk(.25f, .25f, -1, 0, 0, 1, 0, inf), A, B, C, 1, 1, HARD_BOTH);
    n = add(h, n, "interior, from behind (two-sided)", mk(.25f, .25f, 1, 0, 0, -1, 0, inf), A, B, C, 1, 1, HARD_BOTH);
    n = add(h, n, "interior, reversed winding", mk(.25f, .25f, -1, 0, 0, 1, 0, inf), A, C, B, 1, 1, HARD_BOTH);
    n = add(h, n, "edge y=0", mk(.5f, 0, -1, 0, 0, 1, 0, inf), A, B, C, 1, 1, HARD_BOTH);
    n = add(h, n, "edge y=0, d=(-0,-0,1)", mk(.5f, 0, -1, -0.0f, -0.0f, 1, 0, inf), A, B, C, 1, 1, HARD_BOTH);
    n = add(h, n, "edge x=0", mk(0, .5f, -1, 0, 0, 1, 0, inf), A, B, C, 1, 1, HARD_BOTH);
    n = add(h, n, "hypotenuse", mk(.5f, .5f, -1, 0, 0, 1, 0, inf), A, B, C, 1, 1, HARD_BOTH);
    n = add(h, n, "vertex v0", mk(0, 0, -1, 0, 0, 1, 0, inf), A, B, C, 1, 1, HARD_BOTH);
    n = add(h, n, "vertex v1", mk(1, 0, -1, 0, 0, 1, 0, inf), A, B, C, 1, 1, HARD_BOTH);
    n = add(h, n, "vertex v2", mk(0, 1, -1, 0, 0, 1, 0, inf), A, B, C, 1, 1, HARD_BOTH);
    n = add(h, n, "just outside edge y=0", mk(.5f, -0x1p-30f, -1, 0, 0, 1, 0, inf), A, B, C, 0, NAN, HARD_BOTH);
    /* Möller–Trumbore sums the rounded u and v: 0.5 + (0.5 + 2^-24) rounds to 1 */
    n = add(h, n, "just outside hypotenuse", mk(.5f, 0x1.000002p-1f, -1, 0, 0, 1, 0, inf), A, B, C, 0, NAN, HARD_WT);
    n = add(h, n, "just outside vertex v1", mk(0x1.000002p0f, 0, -1, 0, 0, 1, 0, inf), A, B, C, 0, NAN, HARD_BOTH);
    n = add(h, n, "T5 in-plane ray", mk(-1, .25f, 0, 1, 0, 0, 0, inf), A, B, C, 0, NAN, HARD_BOTH);
    n = add(h, n, "in-plane ray, -0", mk(-1, .25f, 0, 1, -0.0f, -0.0f, 0, inf), A, B, C, 0, NAN, HARD_BOTH);
    n = add(h, n, "parallel ray above", mk(-1, .25f, 1, 1, 0, 0, 0, inf), A, B, C, 0, NAN, HARD_BOTH);
    n = add(h, n, "T6 grazing", mk(-.75f, .25f, -1e-7f, 1, 0, 1e-7f, 0, inf), A, B, C, 1, NAN, 0);
    /* T7 degenerate */
    n = add(h, n, "T7 repeated vertex", mk(.5f, 0, -1, 0, 0, 1, 0, inf), A, B, B, 0, NAN, HARD_BOTH);
    {
        const float E[3] = {2, 0, 0};
        n = add(h, n, "T7 collinear", mk(.5f, 0, -1, 0, 0, 1, 0, inf), A, B, E, 0, NAN, HARD_BOTH);
        n = add(h, n, "T7 collinear, oblique ray", mk(.5f, -1, -1, 0, 1, 1, 0, inf), A, B, E, 0, NAN, HARD_BOTH);
        n = add(h, n, "T7 point", mk(0, 0, -1, 0, 0, 1, 0, inf), A, A, A, 0, NAN, HARD_BOTH);
        const float P0[3] = {-1113.45459f, -79.049614f, -56.2431908f};
        const float P1[3] = {-1113.45459f, -87.0922699f, -56.2431908f};
        const float P2[3] = {-1113.45459f, -79.2090149f, -56.2431908f};
        n = add(h, n, "T7 pbrt collinear", mk(-1081.47925f, 99.9999542f, 87.7701111f, -32.1072998f, -183.355865f, -144.607635f, 0, inf),
                P0, P1, P2, 0, NAN, HARD_BOTH);
    }
    /* An edge function whose two float products round to one value while
     * the exact difference is 2^-21: the watertight test's double fallback
     * decides it, exactly. The origin is 2^-21 outside edge v1 v2 (miss), or
     * the triangle lies on the other side of that edge (hit). */
    {
        const float c = 0x1.400002p+2f, t3 = 0x1.e00004p+3f; /* t3 = fl(3c) = 3c + 2^-21 */
        const float P1[3] = {1, 3, 0}, P2[3] = {-c, -t3, 0}, Pm[3] = {3, -1, 0}, Ph[3] = {-3, 1, 0};
        n = add(h, n, "edge function rounds to 0, exact sign says miss", mk(0, 0, -1, 0, 0, 1, 0, inf), Pm, P1, P2, 0, NAN, HARD_WT);
        n = add(h, n, "edge function rounds to 0, inside", mk(0, 0, -1, 0, 0, 1, 0, inf), Ph, P1, P2, 1, 1, HARD_WT);
    }
    /* T9 t bounds */
    n = add(h, n, "T9 tfar=t", mk(.25f, .25f, -1, 0, 0, 1, 0, 1), A, B, C, 1, 1, HARD_BOTH);
    n = add(h, n, "T9 tfar=t-ulp", mk(.25f, .25f, -1, 0, 0, 1, 0, 0x1.fffffep-1f), A, B, C, 0, NAN, HARD_BOTH);
    n = add(h, n, "T9 tnear=t", mk(.25f, .25f, -1, 0, 0, 1, 1, inf), A, B, C, 1, 1, HARD_BOTH);
    n = add(h, n, "T9 tnear=t+ulp", mk(.25f, .25f, -1, 0, 0, 1, 0x1.000002p0f, inf), A, B, C, 0, NAN, HARD_BOTH);
    n = add(h, n, "T9 tnear=tfar=t", mk(.25f, .25f, -1, 0, 0, 1, 1, 1), A, B, C, 1, 1, HARD_BOTH);
    n = add(h, n, "T9 origin on the triangle", mk(.25f, .25f, 0, 0, 0, 1, 0, inf), A, B, C, 1, 0, HARD_BOTH);
    n = add(h, n, "T9 origin on the triangle, tnear=-0", mk(.25f, .25f, 0, .5f, .25f, -1, -0.0f, inf), A, B, C, 1, 0, HARD_BOTH);
    n = add(h, n, "tfar=0, triangle ahead", mk(.25f, .25f, -1, 0, 0, 1, 0, 0), A, B, C, 0, NAN, HARD_BOTH);
    n = add(h, n, "tnear=-inf, triangle behind", mk(.25f, .25f, 2, 0, 0, 1, -inf, inf), A, B, C, 1, -2, HARD_BOTH);
    n = add(h, n, "triangle behind", mk(.25f, .25f, 2, 0, 0, 1, 0, inf), A, B, C, 0, NAN, HARD_BOTH);
    n = add(h, n, "second triangle of the quad", mk(.75f, .75f, -1, 0, 0, 1, 0, inf), B, D, C, 1, 1, HARD_BOTH);
    /* invalid rays and primitives */
    n = add(h, n, "NaN origin", mk(NAN, .25f, -1, 0, 0, 1, 0, inf), A, B, C, 0, NAN, HARD_BOTH);
    n = add(h, n, "NaN direction", mk(.25f, .25f, -1, 0, NAN, 1, 0, inf), A, B, C, 0, NAN, HARD_BOTH);
    n = add(h, n, "inf direction", mk(.25f, .25f, -1, 0, 0, inf, 0, inf), A, B, C, 0, NAN, HARD_BOTH);
    n = add(h, n, "NaN tfar", mk(.25f, .25f, -1, 0, 0, 1, 0, NAN), A, B, C, 0, NAN, HARD_BOTH);
    n = add(h, n, "zero direction", mk(.25f, .25f, 0, 0, -0.0f, 0, 0, inf), A, B, C, 0, NAN, HARD_BOTH);
    n = add(h, n, "inactive interval", mk(.25f, .25f, -1, 0, 0, 1, inf, -inf), A, B, C, 0, NAN, HARD_BOTH);
    {
        const float N0[3] = {NAN, 0, 0};
        n = add(h, n, "T11 NaN vertex", mk(.25f, .25f, -1, 0, 0, 1, 0, inf), N0, B, C, 0, NAN, HARD_BOTH);
        const float I0[3] = {-INFINITY, 0, 0}, I1[3] = {INFINITY, -1, 0};
        n = add(h, n, "T11 infinite vertex", mk(.25f, .25f, -1, 0, 0, 1, 0, inf), I0, B, C, 0, NAN, HARD_BOTH);
        n = add(h, n, "T11 infinite vertices", mk(.25f, .25f, -1, 0, 0, 1, 0, inf), I0, I1, C, 0, NAN, HARD_BOTH);
    }
    /* T1 Embree triangle_hit style: rays from (0,0,-1) through interior points */
    {
        static const float uv[4][2] = {{.25f, .25f}, {.1f, .7f}, {.6f, .3f}, {.333f, .333f}};
        for (int k = 0; k < 4; k++) {
            char name[80];
            snprintf(name, sizeof name, "T1 from (0,0,-1) at u=%g v=%g", (double)uv[k][0], (double)uv[k][1]);
            n = add(h, n, name, mk(0, 0, -1, uv[k][0], uv[k][1], 1, 0, inf), A, B, C, 1, 1, 0);
        }
    }
    /* T8 scales: in range (hit, t = s) and out of it (reported below) */
    {
        static const float sc[] = {1e-10f, 1e-5f, 1e5f, 1e10f};
        for (size_t k = 0; k < sizeof sc / sizeof sc[0]; k++) {
            float s = sc[k];
            const float S0[3] = {0, 0, 0}, S1[3] = {s, 0, 0}, S2[3] = {0, s, 0};
            char name[80];
            snprintf(name, sizeof name, "T8 scale %g", (double)s);
            n = add(h, n, name, mk(s / 4, s / 4, -s, 0, 0, 1, 0, inf), S0, S1, S2, 1, s, 0);
        }
    }
    return n;
}

/* Scales outside the float range of the algorithms' products: the
 * reference hits, the kernels may miss, but a hit they report must carry a
 * finite t (shared/research/robustness.md §1: t = +inf above ~1e15). */
static const float extreme_scales[] = {1e-15f, 1e-20f, 1e-23f, 1e13f, 1e15f, 1e19f, 1e20f};

static const size_t hand_layout[][4] = {
    {1, 0, 1, 0}, {3, 2, 5, 4}, {5, 0, 7, 6}, {7, 6, 9, 0}, {9, 8, 3, 1},
    {15, 7, 17, 16}, {17, 16, 15, 14}, {33, 32, 31, 0}, {31, 0, 33, 32},
};
#define N_LAYOUT (sizeof hand_layout / sizeof hand_layout[0])

/* ---- the world ---- */

typedef struct {
    tr_set s;
    tr_hand hand[TH_MAX];
    int nhand;
    size_t hand_blocks, mesh_hand_blocks;
    lanes_rays R;
    lanes_triangles T;
    lanes_triangle *aos;
    uint32_t *idx;
    size_t *idx_at, *idx_n;
    int algo;
} tr_world;

static void add_hand_mesh_blocks(tk_rng *g, tr_set *s)
{
    /* T2: the quad's diagonal, exactly on it and tilted */
    for (int tilt = 0; tilt < 2; tilt++) {
        tr_block *b = tr_new_block(s, 64, 2);
        b->mesh = true;
        const float q[2][3][3] = {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{1, 0, 0}, {0, 1, 0}, {1, 1, 0}}};
        memcpy(s->v[b->p0], q[0], sizeof q[0]);
        memcpy(s->v[b->p0 + 1], q[1], sizeof q[1]);
        for (size_t i = 0; i < b->nr; i++) {
            int k = 1 + (int)tk_below(g, 1023);
            float p[3] = {k / 1024.0f, 1 - k / 1024.0f, 0};
            float d[3] = {tilt ? 1e-3f : 0, tilt ? 2e-3f : 0, 1};
            ref_ray r = {{p[0] - d[0], p[1] - d[1], p[2] - d[2]}, {d[0], d[1], d[2]}, 0, INFINITY};
            s->raw[b->r0 + i] = r;
            s->probe[b->r0 + i] = true;
            s->targeted[b->r0 + i] = RC_STRESS;
        }
    }
    /* T3: a hexagonal fan around the origin, rays at the centre */
    {
        tr_block *b = tr_new_block(s, 64, 6);
        b->mesh = true;
        for (int k = 0; k < 6; k++) {
            double a0 = k * 3.14159265358979 / 3, a1 = (k + 1) * 3.14159265358979 / 3;
            float t[3][3] = {{0, 0, 0}, {(float)cos(a0), (float)sin(a0), 0}, {(float)cos(a1), (float)sin(a1), 0}};
            memcpy(s->v[b->p0 + (size_t)k], t, sizeof t);
        }
        for (size_t i = 0; i < b->nr; i++) {
            ref_ray r = {{0, 0, -1}, {0, 0, 1}, 0, INFINITY};
            if (i > 0)
                for (int a = 0; a < 3; a++) {
                    r.o[a] = (float)tk_range(g, -2, 2);
                    if (a == 2) r.o[a] = (float)(tk_sign(g) * tk_range(g, 0.5, 2));
                    r.d[a] = -r.o[a];
                }
            s->raw[b->r0 + i] = r;
            s->probe[b->r0 + i] = true;
            s->targeted[b->r0 + i] = RC_STRESS;
        }
    }
}

static void build(tk_ctx *c, tr_world *w, int algo)
{
    tk_rng g;
    tk_seed(&g, c->seed ^ 0x7415);
    tr_set *s = &w->s;
    memset(s, 0, sizeof *s);
    w->algo = algo;
    w->nhand = hand_cases(w->hand);
    for (int h = 0; h < w->nhand; h++)
        for (size_t l = 0; l < N_LAYOUT; l++) {
            tr_frame f = {1.0, {0, 0, 0}};
            tr_block *b = tr_new_block(s, hand_layout[l][0], hand_layout[l][2]);
            for (size_t i = 0; i < b->np; i++) random_tri(&g, &f, s->v[b->p0 + i], &s->tri_special[b->p0 + i]);
            memcpy(s->v[b->p0 + hand_layout[l][3]], w->hand[h].v, sizeof w->hand[h].v);
            s->tri_special[b->p0 + hand_layout[l][3]] = false;
            fill_rays(&g, s, b, &f);
            s->raw[b->r0 + hand_layout[l][1]] = w->hand[h].r;
            s->probe[b->r0 + hand_layout[l][1]] = false;
        }
    w->hand_blocks = s->nblocks;
    /* extreme scales, one block each */
    for (size_t k = 0; k < sizeof extreme_scales / sizeof extreme_scales[0]; k++) {
        float sc = extreme_scales[k];
        tr_block *b = tr_new_block(s, 1, 1);
        s->targeted[b->r0] = RC_STRESS;
        const float t[3][3] = {{0, 0, 0}, {sc, 0, 0}, {0, sc, 0}};
        memcpy(s->v[b->p0], t, sizeof t);
        ref_ray r = {{sc / 4, sc / 4, -sc}, {0, 0, 1}, 0, INFINITY};
        s->raw[b->r0] = r;
    }
    add_hand_mesh_blocks(&g, s);
    w->mesh_hand_blocks = s->nblocks;
    size_t hand_pairs = s->npairs;
    while (s->npairs < c->target + hand_pairs) random_block(&g, s);

    /* references */
    s->ref_hit = malloc(s->npairs);
    s->flags = malloc(s->npairs);
    s->margin = malloc(s->npairs * sizeof(float));
    s->tscale = malloc(s->npairs * sizeof(float));
    s->uscale = malloc(s->npairs * sizeof(float));
    s->vscale = malloc(s->npairs * sizeof(float));
    s->rt = malloc(s->npairs * sizeof(double));
    s->ru = malloc(s->npairs * sizeof(double));
    s->rv = malloc(s->npairs * sizeof(double));
    s->hand = malloc(s->npairs * sizeof(int16_t));
    if (!s->ref_hit || !s->flags || !s->margin || !s->tscale || !s->uscale || !s->vscale || !s->rt ||
        !s->ru || !s->rv || !s->hand)
        abort();
    int ra = algo == LANES_TRI_MOLLER ? REF_MOLLER : REF_WATERTIGHT;
    for (size_t k = 0; k < s->nblocks; k++) {
        const tr_block *b = &s->blocks[k];
        for (size_t i = 0; i < b->nr; i++)
            for (size_t j = 0; j < b->np; j++) {
                size_t p = b->pair0 + i * b->np + j;
                const float(*v)[3] = s->v[b->p0 + j];
                ref_ray pr = tk_prepared(&s->raw[b->r0 + i]);
                ref_tri_result rr = ref_tri(&pr, v[0], v[1], v[2]);
                s->ref_hit[p] = rr.hit;
                s->margin[p] = (float)rr.margin[ra];
                s->tscale[p] = (float)rr.tscale[ra];
                s->uscale[p] = (float)rr.uscale[ra];
                s->vscale[p] = (float)rr.vscale[ra];
                s->rt[p] = rr.t, s->ru[p] = rr.u, s->rv[p] = rr.v;
                s->hand[p] = -1;
                uint8_t rc = s->targeted[b->r0 + i];
                bool tg = s->tri_special[b->p0 + j] || rc == RC_STRESS || b->mesh ||
                          (rc == RC_TARGET && (b->shared || s->target[b->r0 + i] == (int32_t)j));
                s->flags[p] = tg ? PF_TARGETED : 0;
            }
    }
    tk_group gr;
    tk_begin(&gr, c, "triangle reference self-check on %d hand-written cases", w->nhand);
    for (int h = 0; h < w->nhand; h++)
        for (size_t l = 0; l < N_LAYOUT; l++) {
            const tr_block *b = &s->blocks[(size_t)h * N_LAYOUT + l];
            size_t p = b->pair0 + hand_layout[l][1] * b->np + hand_layout[l][3];
            s->hand[p] = (int16_t)h;
            int need = algo == LANES_TRI_MOLLER ? HARD_MOLLER : HARD_WT;
            s->flags[p] = PF_TARGETED | ((w->hand[h].hard & need) ? PF_HARD : 0);
            if (l) continue;
            if (s->ref_hit[p] != w->hand[h].hit)
                tk_fail(&gr, "%s: reference says %s", w->hand[h].name, s->ref_hit[p] ? "hit" : "miss");
            else if (w->hand[h].hit && !isnan(w->hand[h].t) && fabs(s->rt[p] - w->hand[h].t) > 1e-12 * fabs(w->hand[h].t))
                tk_fail(&gr, "%s: reference t %a, expected %a", w->hand[h].name, s->rt[p], w->hand[h].t);
        }
    tk_end(&gr, NULL);

    if (!lanes_rays_alloc(&w->R, s->nrays) || !lanes_triangles_alloc(&w->T, s->ntris)) abort();
    for (size_t i = 0; i < s->nrays; i++) {
        if (s->ray_gap[i])
            tk_garbage_ray(&w->R, i, (unsigned)i);
        else
            tk_put_ray(&w->R, i, &s->raw[i]);
    }
    w->aos = malloc(s->ntris * sizeof *w->aos);
    if (!w->aos) abort();
    float *arr[3][3] = {{w->T.v0x, w->T.v0y, w->T.v0z}, {w->T.v1x, w->T.v1y, w->T.v1z}, {w->T.v2x, w->T.v2y, w->T.v2z}};
    for (size_t i = 0; i < s->ntris; i++) {
        if (s->tri_gap[i]) {
            tk_garbage_tri(&w->T, i, (unsigned)i);
            continue;
        }
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 3; a++) arr[k][a][i] = s->v[i][k][a];
        memcpy(w->aos[i].v0, s->v[i][0], sizeof(float[3]));
        memcpy(w->aos[i].v1, s->v[i][1], sizeof(float[3]));
        memcpy(w->aos[i].v2, s->v[i][2], sizeof(float[3]));
    }
    w->idx = malloc(s->nrays * sizeof *w->idx);
    w->idx_at = malloc(s->nblocks * sizeof(size_t));
    w->idx_n = malloc(s->nblocks * sizeof(size_t));
    if (!w->idx || !w->idx_at || !w->idx_n) abort();
    size_t at = 0;
    for (size_t k = 0; k < s->nblocks; k++) {
        const tr_block *b = &s->blocks[k];
        uint32_t *ix = w->idx + at;
        for (size_t i = 0; i < b->nr; i++) ix[i] = (uint32_t)(b->r0 + i);
        for (size_t i = b->nr; i > 1; i--) {
            size_t j = tk_below(&g, (uint32_t)i);
            uint32_t t = ix[i - 1];
            ix[i - 1] = ix[j], ix[j] = t;
        }
        size_t n = b->nr;
        if (k >= w->hand_blocks && n > 2 && tk_chance(&g, 0.25)) n = 1 + tk_below(&g, (uint32_t)(n - 1));
        w->idx_at[k] = at, w->idx_n[k] = n;
        at += b->nr;
    }
    size_t probes = 0;
    for (size_t i = 0; i < s->nrays; i++) probes += s->probe[i];
    printf("  triangle cases: %zu pairs in %zu blocks (%d hand-written cases x %zu lane layouts), "
           "%zu rays (%zu mesh probes), %zu triangles\n",
           s->npairs, s->nblocks, w->nhand, N_LAYOUT, s->nrays, probes, s->ntris);
}

static lanes_rays rays_at(const lanes_rays *R, size_t r0, size_t n)
{
    lanes_rays v = *R;
    float **f[] = {&v.ox, &v.oy, &v.oz, &v.dx, &v.dy, &v.dz, &v.rdx, &v.rdy, &v.rdz, &v.tnear, &v.tfar};
    for (size_t i = 0; i < sizeof f / sizeof f[0]; i++) *f[i] += r0;
    v.count = n, v.capacity = R->capacity - r0;
    return v;
}

static lanes_triangles tris_at(const lanes_triangles *T, size_t p0, size_t n)
{
    lanes_triangles v = *T;
    float **f[] = {&v.v0x, &v.v0y, &v.v0z, &v.v1x, &v.v1y, &v.v1z, &v.v2x, &v.v2y, &v.v2z};
    for (size_t i = 0; i < sizeof f / sizeof f[0]; i++) *f[i] += p0;
    v.count = n, v.capacity = T->capacity - p0;
    return v;
}

static void describe(const tr_world *w, size_t blk, size_t ri, size_t pj, char *buf, size_t size)
{
    const tr_set *s = &w->s;
    const tr_block *b = &s->blocks[blk];
    char rb[200], v0[96], v1[96], v2[96];
    tk_fmt_ray(rb, sizeof rb, &s->raw[b->r0 + ri]);
    tk_fmt3(v0, sizeof v0, s->v[b->p0 + pj][0]);
    tk_fmt3(v1, sizeof v1, s->v[b->p0 + pj][1]);
    tk_fmt3(v2, sizeof v2, s->v[b->p0 + pj][2]);
    size_t p = b->pair0 + ri * b->np + pj;
    snprintf(buf, size, "%s%s%sray %s tri %s %s %s (block %zu ray %zu/%zu tri %zu/%zu)",
             s->hand[p] >= 0 ? "[" : "", s->hand[p] >= 0 ? w->hand[s->hand[p]].name : "",
             s->hand[p] >= 0 ? "] " : "", rb, v0, v1, v2, blk, ri, b->nr, pj, b->np);
}

/* ---- running ---- */

enum { V_PACKET, V_PACKET_IDX, V_PACKET_ANY, V_PACKET_ANY_IDX, V_WIDE, V_CLOSEST, V_ANY, V_COUNT };
static const char *const vname[V_COUNT] = {
    "tri_packet", "tri_packet(idx)", "tri_packet_any", "tri_packet_any(idx)",
    "tri_wide", "tri_wide_closest", "tri_wide_any",
};

typedef struct {
    uint8_t *hit; /* per pair; 0xff: not tested */
    float *t, *u, *v;
    long *closest; /* per ray: index returned by tri_wide_closest */
    float *ct, *cu, *cv;
    uint8_t *any;  /* per ray: tri_wide_any */
} tr_res;

static void res_alloc(tr_res *r, const tr_set *s)
{
    r->hit = malloc(s->npairs);
    r->t = malloc(s->npairs * sizeof(float));
    r->u = malloc(s->npairs * sizeof(float));
    r->v = malloc(s->npairs * sizeof(float));
    r->closest = malloc(s->nrays * sizeof(long));
    r->ct = malloc(s->nrays * sizeof(float));
    r->cu = malloc(s->nrays * sizeof(float));
    r->cv = malloc(s->nrays * sizeof(float));
    r->any = malloc(s->nrays);
    if (!r->hit || !r->t || !r->u || !r->v || !r->closest || !r->ct || !r->cu || !r->cv || !r->any) abort();
}
static void res_free(tr_res *r)
{
    free(r->hit), free(r->t), free(r->u), free(r->v), free(r->closest), free(r->ct), free(r->cu),
        free(r->cv), free(r->any);
}
static void res_copy(tr_res *d, const tr_res *s, const tr_set *set)
{
    memcpy(d->hit, s->hit, set->npairs);
    memcpy(d->t, s->t, set->npairs * sizeof(float));
    memcpy(d->u, s->u, set->npairs * sizeof(float));
    memcpy(d->v, s->v, set->npairs * sizeof(float));
    memcpy(d->closest, s->closest, set->nrays * sizeof(long));
    memcpy(d->ct, s->ct, set->nrays * sizeof(float));
    memcpy(d->cu, s->cu, set->nrays * sizeof(float));
    memcpy(d->cv, s->cv, set->nrays * sizeof(float));
    memcpy(d->any, s->any, set->nrays);
}

static int check_words(tk_group *g, const uint32_t *w, size_t n, uint32_t sent, const char *what)
{
    size_t nw = lanes_mask_words(n);
    int bad = 0;
    for (size_t i = nw; i < nw + 2; i++)
        if (w[i] != sent) tk_fail(g, "%s: hit word %zu past n=%zu written (0x%08x)", what, i, n, w[i]), bad++;
    if (n % 32) {
        uint32_t past = ~((1u << (n % 32)) - 1u);
        if (w[nw - 1] & past & ~sent) tk_fail(g, "%s: hit bits past n=%zu set (word 0x%08x)", what, n, w[nw - 1]), bad++;
    }
    return bad;
}

static size_t popcount_n(const uint32_t *w, size_t n)
{
    size_t c = 0;
    for (size_t i = 0; i < n; i++) c += lanes_mask_get(w, i);
    return c;
}

static bool same_f(float a, float b) { return tk_bits(a) == tk_bits(b); }

static bool same_out(float a[3][TR_MAXN + 40], float b[3][TR_MAXN + 40], size_t n)
{
    for (int q = 0; q < 3; q++)
        if (memcmp(a[q], b[q], n * sizeof(float))) return false;
    return true;
}

/* wide: tri_wide's results of this set, for the expectation of
 * tri_wide_any's lane accounting (it stops at the first vector with a hit). */
static void run_variant(const lanes_kernels *k, tr_world *w, int v, tr_res *res, const tr_res *wide,
                        tk_group *g, tk_group *gs, size_t *cases)
{
    const tr_set *s = &w->s;
    const int W = k->lanes, A = w->algo;
    uint32_t hw[8], hw2[8];
    float tb[3][TR_MAXN + 40], tb2[3][TR_MAXN + 40];
    lanes_tri_hits out = {tb[0], tb[1], tb[2]}, out2 = {tb2[0], tb2[1], tb2[2]};
    bool with_uv = v == V_PACKET || v == V_PACKET_IDX || v == V_WIDE;
    memset(res->hit, 0xff, s->npairs);
    *cases = 0;
    size_t call = 0;
    for (size_t blk = 0; blk < s->nblocks; blk++) {
        const tr_block *b = &s->blocks[blk];
        const uint32_t *ix = w->idx + w->idx_at[blk];
        size_t nix = w->idx_n[blk];
        if (v == V_WIDE || v == V_CLOSEST || v == V_ANY) {
            lanes_triangles Tb = tris_at(&w->T, b->p0, b->np);
            size_t n = b->np;
            for (size_t i = 0; i < b->nr; i++, call++) {
                lanes_ray ray;
                tk_get_ray(&w->R, b->r0 + i, &ray);
                lanes_lane_stats st = {0, 0, 0};
                size_t ray_id = b->r0 + i;
                *cases += n;
                if (v == V_CLOSEST) {
                    float t = tk_from_bits(TK_SENTINEL_F), u = t, vv = t, t2 = t, u2 = t, v2 = t;
                    long r1 = k->tri_wide_closest[A](&ray, &Tb, n, &t, &u, &vv, NULL);
                    long r2 = k->tri_wide_closest[A](&ray, &Tb, n, &t2, &u2, &v2, &st);
                    if (r1 != r2 || !same_f(t, t2) || !same_f(u, u2) || !same_f(vv, v2))
                        tk_fail(gs, "tri_wide_closest: results with stats differ (block %zu ray %zu)", blk, i);
                    if (!tk_stats_ok(&st, n, W))
                        tk_fail(gs, "tri_wide_closest n=%zu: stats ops=%llu slots=%llu active=%llu", n,
                                (unsigned long long)st.vector_ops, (unsigned long long)st.lane_slots,
                                (unsigned long long)st.active_lanes);
                    if (r1 < -1 || r1 >= (long)n) tk_fail(g, "tri_wide_closest returned %ld for n=%zu", r1, n);
                    if (r1 < 0 && (!tk_is_sentinel(t) || !tk_is_sentinel(u) || !tk_is_sentinel(vv)))
                        tk_fail(g, "tri_wide_closest: t/u/v written without a hit (block %zu ray %zu)", blk, i);
                    res->closest[ray_id] = r1;
                    res->ct[ray_id] = t, res->cu[ray_id] = u, res->cv[ray_id] = vv;
                    continue;
                }
                if (v == V_ANY) {
                    bool a1 = k->tri_wide_any[A](&ray, &Tb, n, NULL);
                    bool a2 = k->tri_wide_any[A](&ray, &Tb, n, &st);
                    if (a1 != a2) tk_fail(gs, "tri_wide_any: results with stats differ (block %zu ray %zu)", blk, i);
                    res->any[ray_id] = a1;
                    size_t first = n;
                    for (size_t j = 0; j < n; j++)
                        if (wide->hit[b->pair0 + i * b->np + j] == 1) {
                            first = j;
                            break;
                        }
                    size_t upto = first < n ? (first / (size_t)W + 1) * (size_t)W : n;
                    if (upto > n) upto = n;
                    if (!tk_stats_ok(&st, upto, W))
                        tk_fail(gs, "tri_wide_any n=%zu first hit %zu: stats ops=%llu slots=%llu active=%llu",
                                n, first, (unsigned long long)st.vector_ops,
                                (unsigned long long)st.lane_slots, (unsigned long long)st.active_lanes);
                    continue;
                }
                uint32_t sent = tk_word_sentinel(call);
                for (int q = 0; q < 8; q++) hw[q] = hw2[q] = sent;
                for (int q = 0; q < 3; q++) tk_fill_sentinel(tb[q], n + 40), tk_fill_sentinel(tb2[q], n + 40);
                size_t h1 = k->tri_wide[A](&ray, &Tb, n, hw, &out, NULL);
                size_t h2 = k->tri_wide[A](&ray, &Tb, n, hw2, &out2, &st);
                check_words(g, hw, n, sent, "tri_wide");
                if (h1 != popcount_n(hw, n)) tk_fail(g, "tri_wide returned %zu, %zu bits set", h1, popcount_n(hw, n));
                if (h1 != h2 || memcmp(hw, hw2, sizeof hw) || !same_out(tb, tb2, n + 40))
                    tk_fail(gs, "tri_wide: results with stats differ (block %zu ray %zu)", blk, i);
                if (!tk_stats_ok(&st, n, W))
                    tk_fail(gs, "tri_wide n=%zu: stats ops=%llu slots=%llu active=%llu", n,
                            (unsigned long long)st.vector_ops, (unsigned long long)st.lane_slots,
                            (unsigned long long)st.active_lanes);
                for (size_t j = 0; j < n + 40; j++) {
                    bool h = j < n && lanes_mask_get(hw, j);
                    if (!h && (!tk_is_sentinel(tb[0][j]) || !tk_is_sentinel(tb[1][j]) || !tk_is_sentinel(tb[2][j]))) {
                        tk_fail(g, "tri_wide: t/u/v[%zu] written for a %s (n=%zu)", j, j < n ? "miss" : "lane past n", n);
                        break;
                    }
                    if (j < n) {
                        size_t p = b->pair0 + i * b->np + j;
                        res->hit[p] = h;
                        res->t[p] = tb[0][j], res->u[p] = tb[1][j], res->v[p] = tb[2][j];
                    }
                }
            }
            continue;
        }
        lanes_rays Rb = rays_at(&w->R, b->r0, b->nr);
        bool use_idx = v == V_PACKET_IDX || v == V_PACKET_ANY_IDX;
        const uint32_t *idx = use_idx ? ix : NULL;
        const lanes_rays *rr = use_idx ? &w->R : &Rb;
        size_t n = use_idx ? nix : b->nr;
        for (size_t pj = 0; pj < b->np; pj++, call++) {
            const lanes_triangle *tri = &w->aos[b->p0 + pj];
            uint32_t sent = tk_word_sentinel(call);
            lanes_lane_stats st = {0, 0, 0};
            for (int q = 0; q < 8; q++) hw[q] = hw2[q] = sent;
            size_t h1, h2;
            if (with_uv) {
                for (int q = 0; q < 3; q++) tk_fill_sentinel(tb[q], n + 40), tk_fill_sentinel(tb2[q], n + 40);
                h1 = k->tri_packet[A](rr, idx, n, tri, hw, &out, NULL);
                h2 = k->tri_packet[A](rr, idx, n, tri, hw2, &out2, &st);
            } else {
                h1 = k->tri_packet_any[A](rr, idx, n, tri, hw, NULL);
                h2 = k->tri_packet_any[A](rr, idx, n, tri, hw2, &st);
            }
            check_words(g, hw, n, sent, vname[v]);
            if (h1 != popcount_n(hw, n)) tk_fail(g, "%s returned %zu, %zu bits set", vname[v], h1, popcount_n(hw, n));
            if (h1 != h2 || memcmp(hw, hw2, sizeof hw) || (with_uv && !same_out(tb, tb2, n + 40)))
                tk_fail(gs, "%s: results with stats differ (block %zu tri %zu)", vname[v], blk, pj);
            if (!tk_stats_ok(&st, n, W))
                tk_fail(gs, "%s n=%zu: stats ops=%llu slots=%llu active=%llu", vname[v], n,
                        (unsigned long long)st.vector_ops, (unsigned long long)st.lane_slots,
                        (unsigned long long)st.active_lanes);
            for (size_t j = 0; j < n + (with_uv ? 40 : 0); j++) {
                bool h = j < n && lanes_mask_get(hw, j);
                if (with_uv && !h && (!tk_is_sentinel(tb[0][j]) || !tk_is_sentinel(tb[1][j]) || !tk_is_sentinel(tb[2][j]))) {
                    tk_fail(g, "%s: t/u/v[%zu] written for a %s (n=%zu)", vname[v], j, j < n ? "miss" : "lane past n", n);
                    break;
                }
                if (j < n) {
                    size_t ri = idx ? idx[j] - b->r0 : j;
                    size_t p = b->pair0 + ri * b->np + pj;
                    res->hit[p] = h;
                    if (with_uv) res->t[p] = tb[0][j], res->u[p] = tb[1][j], res->v[p] = tb[2][j];
                }
            }
            *cases += n;
        }
    }
}

/* Möller–Trumbore between the FMA and the non-FMA sets: t in ulps, u and v
 * in units of 2^-24 (absolute: they live in [0, 1]). The bound applies to
 * cases outside the tolerance band, scaled by the case's conditioning
 * (tscale, uscale: the forward-error scale of ref_tri) so that a grazing ray,
 * whose t is ill-conditioned, gets its due. Measured (see the summary
 * line): at most a few units of conditioning; the bound leaves room. */
#define FMA_ULP_PER_COND 8.0
/* Raw ulps of t between the groups where t is well conditioned (its error
 * scale below 16 |t|): measured at most a handful. */
#define FMA_T_ULP_WELL 32u

static double err_ratio(double err, double scale) { return scale > 0 ? err / scale : (err > 0 ? INFINITY : 0); }

void tk_family_tri(tk_ctx *c, int algo)
{
    if (c->n_isa == 0) return;
    tr_world w;
    memset(&w, 0, sizeof w);
    build(c, &w, algo);
    const tr_set *s = &w.s;
    const char *an = algo == LANES_TRI_MOLLER ? "moller" : "watertight";
    tr_res res, packet, wide, rep[V_COUNT][2];
    res_alloc(&res, s);
    res_alloc(&packet, s);
    res_alloc(&wide, s);
    const char *rep_name[V_COUNT][2] = {{0}};
    for (int v = 0; v < V_COUNT; v++) rep[v][0].hit = rep[v][1].hit = NULL;
    tk_hist hist_t, hist_u, hist_v;
    memset(&hist_t, 0, sizeof hist_t);
    memset(&hist_u, 0, sizeof hist_u);
    memset(&hist_v, 0, sizeof hist_v);
    double fma_worst = 0;
    size_t fma_cmp = 0;
    tk_hist hist_tw;
    memset(&hist_tw, 0, sizeof hist_tw);
    tk_tally fma_tally;
    memset(&fma_tally, 0, sizeof fma_tally);
    bool have_cross = false;

    for (int i = 0; i < c->n_isa; i++) {
        const lanes_kernels *k = c->isa[i];
        /* Möller's rounding differs between the FMA and non-FMA sets; the
         * watertight test uses no FMA and must be identical everywhere */
        int grp = algo == LANES_TRI_MOLLER ? tk_fma_group(k->isa) : 0;
        tk_group gs;
        tk_begin(&gs, c, "%s %s kernels: lane stats and stats-independence", k->name, an);
        for (int v = 0; v < V_COUNT; v++) {
            tk_group g;
            tk_begin(&g, c, "%s %s[%s] vs reference", k->name, vname[v], an);
            size_t cases;
            run_variant(k, &w, v, &res, &wide, &g, &gs, &cases);
            tk_tally tally;
            memset(&tally, 0, sizeof tally);
            if (v == V_CLOSEST || v == V_ANY) tally.query_factor = TK_QUERY_FACTOR;
            double worst_t = 0, worst_u = 0;
            size_t acc_checked = 0, hand_checked = 0, probes = 0, leaks = 0;
            char buf[800];
            if (v == V_CLOSEST || v == V_ANY) {
                for (size_t blk = 0; blk < s->nblocks; blk++) {
                    const tr_block *b = &s->blocks[blk];
                    for (size_t ri = 0; ri < b->nr; ri++) {
                        size_t ray_id = b->r0 + ri;
                        /* the reference: nearest hit, ties to the lowest index */
                        long best = -1;
                        bool any = false, any_robust_hit = false, all_miss_robust = true;
                        for (size_t pj = 0; pj < b->np; pj++) {
                            size_t p = b->pair0 + ri * b->np + pj;
                            bool robust = (s->flags[p] & PF_HARD) || s->margin[p] >= REF_BAND;
                            if (s->ref_hit[p]) {
                                any = true;
                                any_robust_hit = any_robust_hit || robust;
                                if (best < 0 || s->rt[p] < s->rt[b->pair0 + ri * b->np + (size_t)best]) best = (long)pj;
                            }
                            if (!robust) all_miss_robust = false;
                        }
                        bool targeted = false;
                        for (size_t pj = 0; pj < b->np; pj++)
                            targeted = targeted || (s->flags[b->pair0 + ri * b->np + pj] & PF_TARGETED);
                        if (v == V_ANY) {
                            bool got = res.any[ray_id];
                            /* consistency with tri_wide in the same set: exact */
                            bool wide_any = false;
                            for (size_t pj = 0; pj < b->np; pj++) wide_any = wide_any || wide.hit[b->pair0 + ri * b->np + pj] == 1;
                            if (got != wide_any)
                                tk_fail(&g, "block %zu ray %zu: tri_wide_any %d, tri_wide found %s", blk, ri, got,
                                        wide_any ? "hits" : "none");
                            /* against the reference: robust when a robust hit
                             * exists or every pair is robust */
                            double margin = (any ? any_robust_hit : all_miss_robust) ? INFINITY : 0.0;
                            if (tk_tally_weighted(&tally, targeted, margin, any, got, b->np)) {
                                describe(&w, blk, ri, 0, buf, sizeof buf);
                                tk_fail(&g, "%s: any-hit expected %d, got %d", buf, any, got);
                            }
                            continue;
                        }
                        long got = res.closest[ray_id];
                        /* consistency with tri_wide: the lowest index of the smallest t */
                        long wbest = -1;
                        for (size_t pj = 0; pj < b->np; pj++) {
                            size_t p = b->pair0 + ri * b->np + pj;
                            if (wide.hit[p] == 1 && (wbest < 0 || wide.t[p] < wide.t[b->pair0 + ri * b->np + (size_t)wbest]))
                                wbest = (long)pj;
                        }
                        if (got != wbest) {
                            tk_fail(&g, "block %zu ray %zu: tri_wide_closest returned %ld, tri_wide's nearest is %ld",
                                    blk, ri, got, wbest);
                        } else if (got >= 0) {
                            size_t p = b->pair0 + ri * b->np + (size_t)got;
                            if (!same_f(res.ct[ray_id], wide.t[p]) || !same_f(res.cu[ray_id], wide.u[p]) ||
                                !same_f(res.cv[ray_id], wide.v[p]))
                                tk_fail(&g, "block %zu ray %zu: closest t/u/v %a %a %a differ from tri_wide's %a %a %a",
                                        blk, ri, (double)res.ct[ray_id], (double)res.cu[ray_id],
                                        (double)res.cv[ray_id], (double)wide.t[p], (double)wide.u[p], (double)wide.v[p]);
                        }
                        /* against the reference: the same primitive, unless the
                         * two are at (nearly) the same distance or a decision
                         * involved is in the band. The query counts as in the
                         * band when any of its decisions is, or when its two
                         * nearest reference hits nearly tie. */
                        bool agree = got == best;
                        bool uncertain = false;
                        for (size_t pj = 0; pj < b->np; pj++) {
                            size_t p = b->pair0 + ri * b->np + pj;
                            if (!(s->flags[p] & PF_HARD) && s->margin[p] < REF_BAND) uncertain = true;
                            if (best >= 0 && (long)pj != best && s->ref_hit[p]) {
                                size_t pr = b->pair0 + ri * b->np + (size_t)best;
                                double tol = fmax(REF_BAND * fmax(fabs(s->rt[p]), fabs(s->rt[pr])),
                                                  FMA_ULP_PER_COND * 0x1p-24 * (s->tscale[p] + s->tscale[pr]));
                                if (fabs(s->rt[p] - s->rt[pr]) <= tol) uncertain = true;
                            }
                        }
                        double margin = uncertain ? 0.0 : INFINITY;
                        if (!agree && uncertain) {
                            size_t pk = got >= 0 ? b->pair0 + ri * b->np + (size_t)got : 0;
                            size_t pr = best >= 0 ? b->pair0 + ri * b->np + (size_t)best : 0;
                            bool band_k = got >= 0 && !(s->flags[pk] & PF_HARD) && s->margin[pk] < REF_BAND;
                            bool band_r = best >= 0 && !(s->flags[pr] & PF_HARD) && s->margin[pr] < REF_BAND;
                            bool tie = false;
                            if (got >= 0 && best >= 0) {
                                double tk = s->rt[pk], tr = s->rt[pr];
                                double tol = fmax(REF_BAND * fmax(fabs(tk), fabs(tr)),
                                                  FMA_ULP_PER_COND * 0x1p-24 * (s->tscale[pk] + s->tscale[pr]));
                                tie = fabs(tk - tr) <= tol;
                            }
                            /* explained only by the two primitives involved */
                            if (!(band_k || band_r || tie)) margin = INFINITY;
                        }
                        if (tk_tally_weighted(&tally, targeted, margin, true, agree, b->np)) {
                            describe(&w, blk, ri, got >= 0 ? (size_t)got : 0, buf, sizeof buf);
                            tk_fail(&g, "%s: closest is %ld (t=%a), reference %ld (t=%a)", buf, got,
                                    got >= 0 ? s->rt[b->pair0 + ri * b->np + (size_t)got] : NAN, best,
                                    best >= 0 ? s->rt[b->pair0 + ri * b->np + (size_t)best] : NAN);
                        }
                    }
                }
            } else {
                for (size_t blk = 0; blk < s->nblocks; blk++) {
                    const tr_block *b = &s->blocks[blk];
                    for (size_t ri = 0; ri < b->nr; ri++) {
                        size_t ray_id = b->r0 + ri;
                        bool tested = false;
                        size_t kernel_hits = 0;
                        bool ref_any = false;
                        for (size_t pj = 0; pj < b->np; pj++) {
                            size_t p = b->pair0 + ri * b->np + pj;
                            if (res.hit[p] == 0xff) continue;
                            tested = true;
                            bool hard = s->flags[p] & PF_HARD;
                            double margin = hard ? INFINITY : s->margin[p];
                            hand_checked += s->hand[p] >= 0;
                            bool want = s->ref_hit[p], got = res.hit[p];
                            kernel_hits += got;
                            ref_any = ref_any || want;
                            size_t before = tally.dis;
                            if (tk_tally_case(&tally, s->flags[p] & PF_TARGETED, margin, want, got)) {
                                describe(&w, blk, ri, pj, buf, sizeof buf);
                                tk_fail(&g, "%s: expected %s, got %s (margin %.3g, ref t=%.9g)", buf,
                                        want ? "hit" : "miss", got ? "hit" : "miss", margin, s->rt[p]);
                                continue;
                            }
                            if (tally.dis != before && c->show_band &&
                                ((s->flags[p] & PF_TARGETED) ? tally.dis_targeted <= 10 : tally.dis - tally.dis_targeted <= 30)) {
                                describe(&w, blk, ri, pj, buf, sizeof buf);
                                tk_band(&g, "%s %s: expected %s (margin %.3g)",
                                        (s->flags[p] & PF_TARGETED) ? "[boundary-built]" : "[generic]", buf,
                                        want ? "hit" : "miss", margin);
                            }
                            if (!got || v == V_PACKET_ANY || v == V_PACKET_ANY_IDX) continue;
                            /* whatever the band, a reported hit carries a finite t,
                             * and one of the right sign when the true t is well above
                             * its rounding scale: an overflow to inf or an underflow
                             * to 0 is not rounding */
                            double rtp = s->rt[p];
                            bool resolved = fabs(rtp) > fmax(REF_TINY, 64 * 0x1p-24 * s->tscale[p]);
                            bool gross = isfinite(rtp) && (!isfinite(res.t[p]) || (resolved && !(res.t[p] * rtp > 0)));
                            if (gross) {
                                describe(&w, blk, ri, pj, buf, sizeof buf);
                                tk_fail(&g, "%s: hit with t=%a (reference t=%.9g)", buf, (double)res.t[p], s->rt[p]);
                                continue;
                            }
                            if (!want || margin < REF_BAND || !isfinite(s->tscale[p])) continue;
                            /* accuracy, scaled by the case's conditioning */
                            acc_checked++;
                            double u24 = 0x1p-24;
                            double et = err_ratio(fabs(res.t[p] - s->rt[p]), u24 * s->tscale[p] + REF_TINY);
                            double eu = err_ratio(fabs(res.u[p] - s->ru[p]), u24 * s->uscale[p] + REF_TINY);
                            double ev = err_ratio(fabs(res.v[p] - s->rv[p]), u24 * s->vscale[p] + REF_TINY);
                            worst_t = fmax(worst_t, et);
                            worst_u = fmax(worst_u, fmax(eu, ev));
                            if (et > 16 || eu > 16 || ev > 16) {
                                describe(&w, blk, ri, pj, buf, sizeof buf);
                                tk_fail(&g, "%s: t,u,v = %.9g %.9g %.9g, reference %.9g %.9g %.9g (errors %.3g %.3g %.3g "
                                            "units of the conditioned roundoff, bound 16)",
                                        buf, (double)res.t[p], (double)res.u[p], (double)res.v[p], s->rt[p],
                                        s->ru[p], s->rv[p], et, eu, ev);
                            }
                        }
                        /* watertightness: a probe aimed at a shared edge or
                         * vertex of a mesh hits at least one of its triangles */
                        if (tested && b->mesh && s->probe[ray_id] && ref_any && (v == V_PACKET || v == V_WIDE)) {
                            probes++;
                            if (kernel_hits == 0) {
                                leaks++;
                                if (algo == LANES_TRI_WATERTIGHT) {
                                    char rb[200];
                                    tk_fmt_ray(rb, sizeof rb, &s->raw[ray_id]);
                                    tk_fail(&g, "leak: probe %s hits none of the %zu mesh triangles (block %zu)",
                                            rb, b->np, blk);
                                }
                            }
                        }
                    }
                }
            }
            char summary[700];
            tk_tally_close(&g, &tally, summary, sizeof summary);
            if (!c->quick && cases < 1000000) tk_fail(&g, "only %zu cases (at least 10^6 wanted)", cases);
            if (v == V_PACKET || v == V_WIDE)
                tk_end(&g, "%s; %zu hand; accuracy over %zu hits: t %.3g, u/v %.3g units of conditioned "
                           "roundoff (bound 16); mesh probes %zu, leaks %zu%s",
                       summary, hand_checked, acc_checked, worst_t, worst_u, probes, leaks,
                       algo == LANES_TRI_MOLLER ? " (allowed for Möller)" : "");
            else if (v == V_CLOSEST || v == V_ANY)
                tk_end(&g, "%s; a query counts as its ray/triangle pairs, in the band as one", summary);
            else
                tk_end(&g, "%s", summary);

            /* within a set: the forms agree bit for bit */
            if (v == V_PACKET) res_copy(&packet, &res, s);
            if (v == V_WIDE) res_copy(&wide, &res, s);
            if (v == V_PACKET_IDX || v == V_PACKET_ANY || v == V_PACKET_ANY_IDX || v == V_WIDE) {
                tk_group gx;
                tk_begin(&gx, c, "%s %s[%s] == tri_packet", k->name, vname[v], an);
                bool uv = v == V_PACKET_IDX || v == V_WIDE;
                for (size_t p = 0; p < s->npairs; p++) {
                    if (res.hit[p] == 0xff || packet.hit[p] == 0xff) continue;
                    if (res.hit[p] != packet.hit[p] ||
                        (uv && res.hit[p] && (!same_f(res.t[p], packet.t[p]) || !same_f(res.u[p], packet.u[p]) ||
                                              !same_f(res.v[p], packet.v[p]))))
                        tk_fail(&gx, "pair %zu: hit %d t %a u %a v %a vs %d %a %a %a", p, res.hit[p],
                                (double)res.t[p], (double)res.u[p], (double)res.v[p], packet.hit[p],
                                (double)packet.t[p], (double)packet.u[p], (double)packet.v[p]);
                }
                tk_end(&gx, NULL);
            }

            /* across sets */
            if (!rep[v][grp].hit) {
                res_alloc(&rep[v][grp], s);
                res_copy(&rep[v][grp], &res, s);
                rep_name[v][grp] = k->name;
            } else {
                tk_group gx;
                tk_begin(&gx, c, "%s %s[%s] == %s bitwise", k->name, vname[v], an, rep_name[v][grp]);
                const tr_res *r = &rep[v][grp];
                if (v == V_CLOSEST) {
                    for (size_t q = 0; q < s->nrays; q++) {
                        if (s->ray_gap[q]) continue;
                        if (r->closest[q] != res.closest[q] ||
                            (res.closest[q] >= 0 && (!same_f(r->ct[q], res.ct[q]) || !same_f(r->cu[q], res.cu[q]) ||
                                                     !same_f(r->cv[q], res.cv[q]))))
                            tk_fail(&gx, "ray %zu: closest %ld t %a vs %ld %a", q, res.closest[q],
                                    (double)res.ct[q], r->closest[q], (double)r->ct[q]);
                    }
                } else if (v == V_ANY) {
                    for (size_t q = 0; q < s->nrays; q++)
                        if (!s->ray_gap[q] && r->any[q] != res.any[q])
                            tk_fail(&gx, "ray %zu: any %d vs %d", q, res.any[q], r->any[q]);
                } else {
                    bool uv = v == V_PACKET || v == V_PACKET_IDX || v == V_WIDE;
                    for (size_t p = 0; p < s->npairs; p++) {
                        if (res.hit[p] == 0xff) continue;
                        if (res.hit[p] != r->hit[p] ||
                            (uv && res.hit[p] && (!same_f(res.t[p], r->t[p]) || !same_f(res.u[p], r->u[p]) ||
                                                  !same_f(res.v[p], r->v[p]))))
                            tk_fail(&gx, "pair %zu: hit %d t %a u %a v %a vs %d %a %a %a", p, res.hit[p],
                                    (double)res.t[p], (double)res.u[p], (double)res.v[p], r->hit[p],
                                    (double)r->t[p], (double)r->u[p], (double)r->v[p]);
                    }
                }
                tk_end(&gx, NULL);
            }
            /* Möller: FMA against non-FMA, on tri_packet */
            if (algo == LANES_TRI_MOLLER && v == V_PACKET && rep[v][0].hit && rep[v][1].hit && !have_cross) {
                have_cross = true;
                const tr_res *a = &rep[v][0], *bq = &rep[v][1];
                tk_group gx;
                tk_begin(&gx, c, "tri_packet[moller] %s (no FMA) vs %s (FMA)", rep_name[v][0], rep_name[v][1]);
                for (size_t blk = 0; blk < s->nblocks; blk++) {
                    const tr_block *b = &s->blocks[blk];
                    for (size_t ri = 0; ri < b->nr; ri++)
                        for (size_t pj = 0; pj < b->np; pj++) {
                            size_t p = b->pair0 + ri * b->np + pj;
                            bool hard = s->flags[p] & PF_HARD;
                            bool band = !hard && s->margin[p] < REF_BAND;
                            if (tk_tally_case(&fma_tally, s->flags[p] & PF_TARGETED, hard ? INFINITY : s->margin[p],
                                              a->hit[p], bq->hit[p])) {
                                describe(&w, blk, ri, pj, buf, sizeof buf);
                                tk_fail(&gx, "%s: hit %d without FMA, %d with FMA (margin %.3g)", buf, a->hit[p],
                                        bq->hit[p], (double)s->margin[p]);
                            }
                            if (a->hit[p] != bq->hit[p]) continue;
                            if (!a->hit[p] || band || !isfinite(s->tscale[p])) continue;
                            fma_cmp++;
                            uint32_t dt = ref_ulp_distance(a->t[p], bq->t[p]);
                            uint32_t du = (uint32_t)fmin(fabs((double)a->u[p] - bq->u[p]) / 0x1p-24, 4e9);
                            uint32_t dv = (uint32_t)fmin(fabs((double)a->v[p] - bq->v[p]) / 0x1p-24, 4e9);
                            tk_hist_add(&hist_t, dt);
                            bool well = s->tscale[p] <= 16 * fabs(s->rt[p]);
                            if (well) tk_hist_add(&hist_tw, dt);
                            if (well && dt > FMA_T_ULP_WELL) {
                                describe(&w, blk, ri, pj, buf, sizeof buf);
                                tk_fail(&gx, "%s: well-conditioned t %a/%a differs by %u ulp (bound %u)", buf,
                                        (double)a->t[p], (double)bq->t[p], dt, FMA_T_ULP_WELL);
                            }
                            tk_hist_add(&hist_u, du);
                            tk_hist_add(&hist_v, dv);
                            /* in units of the conditioned roundoff u * scale */
                            double rt = fabs((double)a->t[p] - bq->t[p]) / (0x1p-24 * s->tscale[p] + REF_TINY);
                            double ru = du / fmax(s->uscale[p], 1e-30), rv = dv / fmax(s->vscale[p], 1e-30);
                            double worst = fmax(rt, fmax(ru, rv));
                            fma_worst = fmax(fma_worst, worst);
                            if (worst > FMA_ULP_PER_COND) {
                                describe(&w, blk, ri, pj, buf, sizeof buf);
                                tk_fail(&gx, "%s: t %a/%a (%u ulp), u %a/%a, v %a/%a: %.3g x conditioning (bound %.0f)",
                                        buf, (double)a->t[p], (double)bq->t[p], dt, (double)a->u[p], (double)bq->u[p],
                                        (double)a->v[p], (double)bq->v[p], worst, FMA_ULP_PER_COND);
                            }
                        }
                }
                char summary[700];
                tk_tally_close(&gx, &fma_tally, summary, sizeof summary);
                tk_hist_print(&hist_t, "t difference, ulps");
                tk_hist_print(&hist_tw, "t difference where t is well conditioned, ulps");
                tk_hist_print(&hist_u, "u difference, units of 2^-24");
                tk_hist_print(&hist_v, "v difference, units of 2^-24");
                tk_end(&gx, "%zu common hits outside the band compared: t/u/v differ by at most %.3g units of "
                            "u x their error scale (bound %.0f); raw max t %u ulp (well-conditioned t: %u, "
                            "bound %u), u %u, v %u (units of 2^-24); hit bits: %s",
                       fma_cmp, fma_worst, FMA_ULP_PER_COND, hist_t.max, hist_tw.max, FMA_T_ULP_WELL,
                       hist_u.max, hist_v.max, summary);
            }
        }
        tk_end(&gs, NULL);
    }
    for (int v = 0; v < V_COUNT; v++)
        for (int q = 0; q < 2; q++)
            if (rep[v][q].hit) res_free(&rep[v][q]);
    res_free(&res), res_free(&packet), res_free(&wide);
    lanes_rays_free(&w.R);
    lanes_triangles_free(&w.T);
    free(w.aos), free(w.idx), free(w.idx_at), free(w.idx_n);
    tr_set *ss = &w.s;
    free(ss->raw), free(ss->ray_gap), free(ss->probe), free(ss->targeted), free(ss->target);
    free(ss->v), free(ss->tri_gap), free(ss->tri_special), free(ss->blocks);
    free(ss->ref_hit), free(ss->flags), free(ss->margin), free(ss->tscale), free(ss->uscale), free(ss->vscale);
    free(ss->rt), free(ss->ru), free(ss->rv), free(ss->hand);
}
