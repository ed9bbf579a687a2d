/* Frustum kernels: frustum_build over coherent packets of many kinds, then
 * frustum_boxes and frustum_tris with every cull method against many
 * primitives. The one rule with no tolerance at all: a primitive that the
 * double reference says some active ray of the packet hits is never culled.
 * And so that a kernel culling nothing cannot pass: primitives far to the
 * side of a coherent primary packet must be culled by every method. */
#include <float.h>
#include <stdlib.h>

#include "test_kernels_common.h"

#define FR_MAXN 64
/* Far-side primitives (60 to 120 degrees off the axis of a cone of at most
 * 10 degrees) that every method must cull. Measured: boxes 100% by every
 * method, triangles 100% by PLANES and ~98% by INTERVAL (interval
 * arithmetic on the edge functions overestimates for big triangles). */
#define FR_MIN_SIDE_CULL 0.95

enum {
    K_PRIMARY,  /* common origin, narrow cone in one octant */
    K_WIDE,     /* common origin, wide cone (mixed signs on some axes) */
    K_ORTHO,    /* parallel rays from a grid of origins, ±0 components */
    K_SHADOW,   /* distinct origins to one light, tfar = 1 */
    K_REFLECT,  /* distinct origins on a patch, a cone of directions */
    K_ZEROS,    /* ±0 and tiny components mixed in */
    K_INACTIVE, /* some rays invalid or with tnear > tfar */
    K_BEHIND,   /* tnear < 0 */
    K_HUGE,     /* an origin beyond 1e18: no culling at all */
    K_EMPTY,    /* no active ray: everything culled */
    K_COUNT
};
static const char *const kname[K_COUNT] = {"primary", "wide cone", "orthographic", "shadow",
                                           "reflection", "±0/tiny comps", "inactive rays",
                                           "tnear<0", "huge origin", "empty"};

enum { C_NEAR, C_MISS, C_SIDE, C_BEHIND, C_RANDOM, C_SPECIAL, C_COUNT };
static const char *const cname[C_COUNT] = {"near rays", "just missing", "far side", "behind",
                                           "random", "special"};

typedef struct {
    size_t r0, nr, b0, nb, t0, nt;
    int kind;
    size_t idx_at, nidx; /* a shuffled index array over the packet's rays */
} fr_block;

typedef struct {
    ref_ray *raw;
    size_t nrays, cap_r;
    float (*lo)[3], (*hi)[3];
    uint8_t *bcat;
    size_t nboxes, cap_b;
    float (*v)[3][3];
    uint8_t *tcat;
    size_t ntris, cap_t;
    fr_block *blocks;
    size_t nblocks, cap_k;
    uint8_t *box_hit, *tri_hit; /* reference: some active ray hits */
    uint32_t *idx;
    size_t nidx, cap_i;
} fr_set;

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

static fr_block *new_block(fr_set *s, size_t nr, size_t nb, size_t nt)
{
    size_t r0 = round_up(s->nrays), b0 = round_up(s->nboxes), t0 = round_up(s->ntris);
    if (r0 + nr > s->cap_r) {
        s->cap_r = new_cap(s->cap_r, r0 + nr);
        s->raw = grow_to(s->raw, s->cap_r, sizeof *s->raw);
    }
    for (size_t i = s->nrays; i < r0 + nr; i++) {
        memset(&s->raw[i], 0, sizeof s->raw[i]);
        s->raw[i].o[0] = NAN;
    }
    s->nrays = r0 + nr;
    if (b0 + nb > s->cap_b) {
        s->cap_b = new_cap(s->cap_b, b0 + nb);
        s->lo = grow_to(s->lo, s->cap_b, sizeof *s->lo);
        s->hi = grow_to(s->hi, s->cap_b, sizeof *s->hi);
        s->bcat = grow_to(s->bcat, s->cap_b, 1);
    }
    for (size_t i = s->nboxes; i < b0 + nb; i++) s->bcat[i] = 0xff;
    s->nboxes = b0 + nb;
    if (t0 + nt > s->cap_t) {
        s->cap_t = new_cap(s->cap_t, t0 + nt);
        s->v = grow_to(s->v, s->cap_t, sizeof *s->v);
        s->tcat = grow_to(s->tcat, s->cap_t, 1);
    }
    for (size_t i = s->ntris; i < t0 + nt; i++) s->tcat[i] = 0xff;
    s->ntris = t0 + nt;
    if (s->nidx + nr > s->cap_i) {
        s->cap_i = new_cap(s->cap_i, s->nidx + nr);
        s->idx = grow_to(s->idx, s->cap_i, sizeof *s->idx);
    }
    if (s->nblocks + 1 > s->cap_k) {
        s->cap_k = new_cap(s->cap_k, s->nblocks + 1);
        s->blocks = grow_to(s->blocks, s->cap_k, sizeof *s->blocks);
    }
    fr_block *b = &s->blocks[s->nblocks++];
    b->r0 = r0, b->nr = nr, b->b0 = b0, b->nb = nb, b->t0 = t0, b->nt = nt;
    b->idx_at = s->nidx, b->nidx = nr;
    s->nidx += nr;
    return b;
}

/* ---- vectors in double ---- */
static void normalize(double v[3])
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int a = 0; a < 3; a++) v[a] /= l;
}
static void basis(const double d[3], double u[3], double w[3])
{
    double t[3] = {1, 0, 0};
    if (fabs(d[0]) > 0.7) t[0] = 0, t[1] = 1;
    u[0] = d[1] * t[2] - d[2] * t[1], u[1] = d[2] * t[0] - d[0] * t[2], u[2] = d[0] * t[1] - d[1] * t[0];
    normalize(u);
    w[0] = d[1] * u[2] - d[2] * u[1], w[1] = d[2] * u[0] - d[0] * u[2], w[2] = d[0] * u[1] - d[1] * u[0];
}

typedef struct {
    double O[3], D[3], U[3], V[3]; /* the packet's centre origin, axis and basis */
    double spread;                /* half-width of the origins */
    double cone;                  /* tan of the cone's half-angle */
    double T;                     /* a typical distance to the primitives */
} fr_geom;

static void set_ray(ref_ray *r, const double o[3], const double d[3], float tn, float tf)
{
    for (int a = 0; a < 3; a++) r->o[a] = (float)o[a], r->d[a] = (float)d[a];
    r->tnear = tn, r->tfar = tf;
}

static void gen_packet(tk_rng *g, fr_set *s, fr_block *b, fr_geom *G)
{
    double scale = tk_chance(g, 0.7) ? 1.0 : exp2(tk_range(g, -10, 10));
    for (int a = 0; a < 3; a++) G->O[a] = scale * tk_range(g, -4, 4);
    G->T = scale * tk_range(g, 2, 20);
    G->spread = 0, G->cone = tan(tk_range(g, 0.01, 0.17));
    /* a principal direction with no small component: one octant */
    do {
        for (int a = 0; a < 3; a++) G->D[a] = tk_range(g, -1, 1);
        normalize(G->D);
    } while (fabs(G->D[0]) < 0.3 || fabs(G->D[1]) < 0.3 || fabs(G->D[2]) < 0.3);
    basis(G->D, G->U, G->V);
    int k = b->kind;
    for (size_t i = 0; i < b->nr; i++) {
        ref_ray *r = &s->raw[b->r0 + i];
        double o[3], d[3], x = tk_range(g, -1, 1), y = tk_range(g, -1, 1);
        for (int a = 0; a < 3; a++) o[a] = G->O[a], d[a] = G->D[a] + G->cone * (x * G->U[a] + y * G->V[a]);
        float tn = 0, tf = INFINITY;
        switch (k) {
        case K_WIDE:
            for (int a = 0; a < 3; a++) d[a] = G->D[a] + 1.5 * (x * G->U[a] + y * G->V[a]);
            break;
        case K_ORTHO: {
            int ax = (int)(tk_next(g) % 3);
            G->spread = scale;
            for (int a = 0; a < 3; a++) {
                d[a] = 0;
                o[a] = G->O[a] + scale * (a == ax ? -2.0 : tk_range(g, -1, 1));
            }
            d[ax] = 1;
            set_ray(r, o, d, tn, tf);
            for (int a = 0; a < 3; a++)
                if (a != ax) r->d[a] = (b->r0 & 16) ? -0.0f : 0.0f;
            if (tk_chance(g, 0.5)) r->d[(ax + 1) % 3] = -r->d[(ax + 1) % 3];
            continue;
        }
        case K_SHADOW: {
            double L[3];
            for (int a = 0; a < 3; a++) L[a] = G->O[a] + G->T * G->D[a];
            G->spread = scale;
            for (int a = 0; a < 3; a++) o[a] = G->O[a] + scale * (x * G->U[a] + y * G->V[a] + tk_range(g, -0.3, 0.3) * G->D[a]);
            for (int a = 0; a < 3; a++) d[a] = L[a] - o[a];
            tf = 1;
            break;
        }
        case K_REFLECT:
            G->spread = scale * 0.5;
            for (int a = 0; a < 3; a++) o[a] = G->O[a] + G->spread * (x * G->U[a] + y * G->V[a]);
            break;
        case K_ZEROS:
            if (tk_chance(g, 0.5)) {
                int ax = (int)(tk_next(g) % 3);
                d[ax] = tk_chance(g, 0.5) ? 0.0 : -0.0;
                if (tk_chance(g, 0.3)) d[ax] = tk_sign(g) * (tk_chance(g, 0.5) ? 1e-30 : 1e-42);
            }
            break;
        case K_BEHIND:
            tn = (float)(-G->T * tk_unit(g));
            break;
        default:
            break;
        }
        set_ray(r, o, d, tn, tf);
        if (tk_chance(g, 0.2)) r->tfar = (float)(G->T * tk_range(g, 0.5, 3));
        if (k == K_INACTIVE && tk_chance(g, 0.4)) {
            switch (tk_below(g, 4)) {
            case 0: r->o[0] = NAN; break;
            case 1: r->d[0] = r->d[1] = r->d[2] = 0; break;
            case 2: r->tnear = 5, r->tfar = 1; break;
            default: r->d[1] = INFINITY; break;
            }
        }
        if (k == K_EMPTY) r->tnear = INFINITY, r->tfar = -INFINITY;
    }
    if (k == K_HUGE && b->nr) s->raw[b->r0].o[0] = tk_chance(g, 0.5) ? 3e18f : -1e20f;
}

/* A point of an active ray of the packet at a random distance. */
static bool point_on_ray(tk_rng *g, const fr_set *s, const fr_block *b, const fr_geom *G, double p[3])
{
    for (int tries = 0; tries < 8 && b->nr; tries++) {
        const ref_ray *r = &s->raw[b->r0 + tk_below(g, (uint32_t)b->nr)];
        if (!ref_ray_valid(r) || !(r->tnear <= r->tfar)) continue;
        double lo = fmax(r->tnear, 0), hi = fmin(r->tfar, lo + 2 * G->T / (fabs(r->d[0]) + fabs(r->d[1]) + fabs(r->d[2]) + 1e-30));
        if (!(hi >= lo) || !isfinite(hi)) continue;
        double t = tk_range(g, lo, hi);
        for (int a = 0; a < 3; a++) p[a] = r->o[a] + t * (double)r->d[a];
        return true;
    }
    for (int a = 0; a < 3; a++) p[a] = G->O[a] + G->T * G->D[a];
    return false;
}

static void gen_box(tk_rng *g, fr_set *s, const fr_block *b, const fr_geom *G, size_t at, bool side_ok)
{
    double c[3], h = G->T * exp2(tk_range(g, -8, -2));
    double p = tk_unit(g);
    int cat;
    if (p < 0.35) {
        cat = C_NEAR;
        point_on_ray(g, s, b, G, c);
    } else if (p < 0.5) {
        cat = C_MISS;
        point_on_ray(g, s, b, G, c);
        double off = G->T * (G->cone + 0.05) * tk_range(g, 1, 2) + G->spread;
        for (int a = 0; a < 3; a++) c[a] += off * (tk_sign(g) * G->U[a] + tk_range(g, -1, 1) * G->V[a]);
    } else if (p < 0.75 && side_ok) {
        /* 60 to 120 degrees off the axis: clearly outside a narrow cone */
        cat = C_SIDE;
        double phi = tk_range(g, 1.05, 2.1), psi = tk_range(g, 0, 6.283), dist = G->T * tk_range(g, 0.5, 2);
        for (int a = 0; a < 3; a++)
            c[a] = G->O[a] + dist * (cos(phi) * G->D[a] + sin(phi) * (cos(psi) * G->U[a] + sin(psi) * G->V[a]));
        h = fmin(h, dist * 0.2);
    } else if (p < 0.82) {
        cat = C_BEHIND;
        for (int a = 0; a < 3; a++) c[a] = G->O[a] - G->T * tk_range(g, 0.3, 2) * G->D[a] + G->T * tk_range(g, -0.2, 0.2);
    } else if (p < 0.94) {
        cat = C_RANDOM;
        for (int a = 0; a < 3; a++) c[a] = G->O[a] + 2 * G->T * tk_range(g, -1, 1);
        h = G->T * exp2(tk_range(g, -6, 0));
    } else {
        cat = C_SPECIAL;
        point_on_ray(g, s, b, G, c);
        float *lo = s->lo[at], *hi = s->hi[at];
        switch (tk_below(g, 5)) {
        case 0: /* containing every origin */
            for (int a = 0; a < 3; a++) lo[a] = (float)(G->O[a] - 4 * G->T), hi[a] = (float)(G->O[a] + 4 * G->T);
            break;
        case 1: /* unbounded */
            for (int a = 0; a < 3; a++) lo[a] = -INFINITY, hi[a] = INFINITY;
            lo[tk_below(g, 3)] = (float)c[0];
            break;
        case 2: /* empty */
            for (int a = 0; a < 3; a++) lo[a] = (float)(c[a] + h), hi[a] = (float)(c[a] - h);
            break;
        case 3: /* flat */
            for (int a = 0; a < 3; a++) lo[a] = (float)(c[a] - h), hi[a] = (float)(c[a] + h);
            {
                int a = (int)tk_below(g, 3);
                hi[a] = lo[a];
            }
            break;
        default: /* a box around a ray's origin */
            if (b->nr) {
                const ref_ray *r = &s->raw[b->r0 + tk_below(g, (uint32_t)b->nr)];
                for (int a = 0; a < 3; a++) lo[a] = r->o[a] - (float)h, hi[a] = r->o[a] + (float)h;
            }
            break;
        }
        s->bcat[at] = (uint8_t)cat;
        return;
    }
    for (int a = 0; a < 3; a++) {
        double ha = h * tk_range(g, 0.2, 1);
        s->lo[at][a] = (float)(c[a] - ha), s->hi[at][a] = (float)(c[a] + ha);
    }
    s->bcat[at] = (uint8_t)cat;
}

static void gen_tri(tk_rng *g, fr_set *s, const fr_block *b, const fr_geom *G, size_t at, bool side_ok)
{
    double c[3], h = G->T * exp2(tk_range(g, -7, -2));
    double p = tk_unit(g);
    int cat;
    if (p < 0.4) {
        cat = C_NEAR;
        point_on_ray(g, s, b, G, c);
    } else if (p < 0.55) {
        cat = C_MISS;
        point_on_ray(g, s, b, G, c);
        double off = G->T * (G->cone + 0.05) * tk_range(g, 1, 2) + G->spread;
        for (int a = 0; a < 3; a++) c[a] += off * (tk_sign(g) * G->U[a] + tk_range(g, -1, 1) * G->V[a]);
    } else if (p < 0.8 && side_ok) {
        cat = C_SIDE;
        double phi = tk_range(g, 1.05, 2.1), psi = tk_range(g, 0, 6.283), dist = G->T * tk_range(g, 0.5, 2);
        for (int a = 0; a < 3; a++)
            c[a] = G->O[a] + dist * (cos(phi) * G->D[a] + sin(phi) * (cos(psi) * G->U[a] + sin(psi) * G->V[a]));
        h = fmin(h, dist * 0.2);
    } else if (p < 0.87) {
        cat = C_BEHIND;
        for (int a = 0; a < 3; a++) c[a] = G->O[a] - G->T * tk_range(g, 0.3, 2) * G->D[a];
    } else if (p < 0.95) {
        cat = C_RANDOM;
        for (int a = 0; a < 3; a++) c[a] = G->O[a] + 2 * G->T * tk_range(g, -1, 1);
        h = G->T * exp2(tk_range(g, -5, 0));
    } else {
        cat = C_SPECIAL;
        point_on_ray(g, s, b, G, c);
        h = G->T * 4; /* a big one through the bundle, or degenerate */
    }
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 3; a++) s->v[at][k][a] = (float)(c[a] + h * tk_range(g, -1, 1));
    if (cat == C_SPECIAL && tk_chance(g, 0.3)) memcpy(s->v[at][2], s->v[at][1], sizeof s->v[at][2]);
    s->tcat[at] = (uint8_t)cat;
}

/* Hand-written packets (shared/research/robustness.md §5, §7c). */
static void hand_packets(tk_rng *g, fr_set *s)
{
    /* the mixed-sign counterexample: d0 hits the box, an octant-assuming
     * test culls it */
    {
        fr_block *b = new_block(s, 2, 1, 1);
        b->kind = K_WIDE;
        ref_ray r0 = {{0, 0, 0}, {1, .25f, 1}, 0, INFINITY}, r1 = {{0, 0, 0}, {-1, .25f, 1}, 0, INFINITY};
        s->raw[b->r0] = r0, s->raw[b->r0 + 1] = r1;
        const float lo[3] = {1, -1, 1}, hi[3] = {2, 1, 2};
        memcpy(s->lo[b->b0], lo, sizeof lo), memcpy(s->hi[b->b0], hi, sizeof hi);
        const float t[3][3] = {{1, 0, 1.5f}, {2, 0.5f, 1.5f}, {2, -0.5f, 1.5f}};
        memcpy(s->v[b->t0], t, sizeof t);
        s->bcat[b->b0] = s->tcat[b->t0] = C_SPECIAL;
    }
    /* orthographic packet with ±0, boxes beside some rays and hit by others */
    for (int neg = 0; neg < 2; neg++) {
        fr_block *b = new_block(s, 16, 4, 2);
        b->kind = K_ORTHO;
        for (int i = 0; i < 16; i++) {
            ref_ray r = {{(float)(i % 4), (float)(i / 4), -10}, {neg ? -0.0f : 0.0f, (i & 1) ? -0.0f : 0.0f, 1}, 0, INFINITY};
            s->raw[b->r0 + (size_t)i] = r;
        }
        const float box[4][2][3] = {{{3, 3, 0}, {4, 4, 1}},    /* touches the corner ray (3,3) */
                                    {{3, 0, 0}, {3, 0, 1}},    /* flat, on the ray (3,0) */
                                    {{3.5f, 0, 0}, {5, 1, 1}}, /* beside: missed */
                                    {{-1, -1, -20}, {0, 0, -11}}}; /* behind: missed */
        for (int q = 0; q < 4; q++) {
            memcpy(s->lo[b->b0 + (size_t)q], box[q][0], sizeof box[q][0]);
            memcpy(s->hi[b->b0 + (size_t)q], box[q][1], sizeof box[q][1]);
            s->bcat[b->b0 + (size_t)q] = C_SPECIAL;
        }
        const float t0[3][3] = {{3, 3, 5}, {4, 3, 5}, {3, 4, 5}}, t1[3][3] = {{3.5f, 3.5f, 5}, {4, 3.5f, 5}, {3.5f, 4, 5}};
        memcpy(s->v[b->t0], t0, sizeof t0), memcpy(s->v[b->t0 + 1], t1, sizeof t1);
        s->tcat[b->t0] = s->tcat[b->t0 + 1] = C_SPECIAL;
    }
    /* a triangle whose plane separates the origins (P5) */
    {
        fr_block *b = new_block(s, 8, 1, 1);
        b->kind = K_REFLECT;
        for (int i = 0; i < 8; i++) {
            ref_ray r = {{(float)tk_range(g, -.5, .5), (float)tk_range(g, -.5, .5), (i & 1) ? -1.0f : 1.0f},
                         {(float)tk_range(g, -.1, .1), (float)tk_range(g, -.1, .1), 1}, 0, INFINITY};
            s->raw[b->r0 + (size_t)i] = r;
        }
        const float t[3][3] = {{-2, -2, 0}, {2, -2, 0}, {0, 2, 0}};
        memcpy(s->v[b->t0], t, sizeof t);
        const float lo[3] = {-1, -1, -0.5f}, hi[3] = {1, 1, 0};
        memcpy(s->lo[b->b0], lo, sizeof lo), memcpy(s->hi[b->b0], hi, sizeof hi);
        s->bcat[b->b0] = s->tcat[b->t0] = C_SPECIAL;
    }
    /* a dominant-axis component so small that d[a] / d[k] overflows: the ray
     * starting on the near plane must still bound the planes */
    for (int variant = 0; variant < 2; variant++) {
        fr_block *b = new_block(s, 2, 1, 1);
        b->kind = K_ZEROS;
        float tiny = variant ? 1e-40f : 1e-30f;
        float big = variant ? 1.0f : 1e10f;
        ref_ray r0 = {{0, 0, 0}, {1, 0, 1}, 0, INFINITY}, r1 = {{10, 0, 0}, {-big, 0, tiny}, 0, INFINITY};
        s->raw[b->r0] = r0, s->raw[b->r0 + 1] = r1;
        const float lo[3] = {9, -1, 0}, hi[3] = {11, 1, 0.5f};
        memcpy(s->lo[b->b0], lo, sizeof lo), memcpy(s->hi[b->b0], hi, sizeof hi);
        const float t[3][3] = {{9.5f, -1, 0}, {9.5f, 1, 0}, {9.5f, 0, 0.5f}};
        memcpy(s->v[b->t0], t, sizeof t);
        s->bcat[b->b0] = s->tcat[b->t0] = C_SPECIAL;
    }
    /* boxes unbounded along the dominant axis, for a packet whose other
     * components are all ±0 (slopes 0, so 0 * inf comes up) */
    {
        fr_block *b = new_block(s, 1, 2, 0);
        b->kind = K_ORTHO;
        ref_ray r0 = {{0, 0, 0}, {1, 0, -0.0f}, 0, INFINITY};
        s->raw[b->r0] = r0;
        const float lo0[3] = {1, -1, -1}, hi0[3] = {INFINITY, 1, 1};
        const float lo1[3] = {-INFINITY, -1, -1}, hi1[3] = {INFINITY, 1, 1};
        memcpy(s->lo[b->b0], lo0, sizeof lo0), memcpy(s->hi[b->b0], hi0, sizeof hi0);
        memcpy(s->lo[b->b0 + 1], lo1, sizeof lo1), memcpy(s->hi[b->b0 + 1], hi1, sizeof hi1);
        s->bcat[b->b0] = s->bcat[b->b0 + 1] = C_SPECIAL;
    }
    /* a box whose far face lies exactly on the near plane */
    {
        fr_block *b = new_block(s, 2, 1, 0);
        b->kind = K_ZEROS;
        ref_ray r0 = {{0, 0, 0}, {1, 0, 1}, 0, INFINITY}, r1 = {{10, 0, 0}, {-1, 0, 1e-40f}, 0, INFINITY};
        s->raw[b->r0] = r0, s->raw[b->r0 + 1] = r1;
        const float lo[3] = {9, -1, -1}, hi[3] = {11, 1, 0};
        memcpy(s->lo[b->b0], lo, sizeof lo), memcpy(s->hi[b->b0], hi, sizeof hi);
        s->bcat[b->b0] = C_SPECIAL;
    }
    /* a huge triangle crossing a coherent packet */
    {
        fr_block *b = new_block(s, 8, 0, 2);
        b->kind = K_PRIMARY;
        for (int i = 0; i < 8; i++) {
            ref_ray r = {{0, 0, 0}, {(float)tk_range(g, -.1, .1), (float)tk_range(g, -.1, .1), 1}, 0, INFINITY};
            s->raw[b->r0 + (size_t)i] = r;
        }
        const float t0[3][3] = {{-1e20f, -1e20f, 5}, {1e20f, -1e20f, 5}, {0, 1e20f, 5}};
        const float t1[3][3] = {{-1e6f, -1e6f, 5}, {1e6f, -1e6f, 5}, {0, 1e6f, 5}};
        memcpy(s->v[b->t0], t0, sizeof t0), memcpy(s->v[b->t0 + 1], t1, sizeof t1);
        s->tcat[b->t0] = s->tcat[b->t0 + 1] = C_SPECIAL;
    }
    /* an empty packet (n = 0) and a packet with n = 1 */
    {
        fr_block *b = new_block(s, 0, 3, 3);
        b->kind = K_EMPTY;
        for (size_t q = 0; q < 3; q++) {
            for (int a = 0; a < 3; a++) s->lo[b->b0 + q][a] = -1, s->hi[b->b0 + q][a] = 1;
            const float t[3][3] = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
            memcpy(s->v[b->t0 + q], t, sizeof t);
            s->bcat[b->b0 + q] = s->tcat[b->t0 + q] = C_SPECIAL;
        }
    }
}

/* ---- the family ---- */

typedef struct {
    bool valid, empty;
    float tnear, tfar, omin[3], omax[3], dmin[3], dmax[3];
} fr_expect;

static void expect_frustum(const fr_set *s, const uint32_t *rays, size_t n, fr_expect *e)
{
    e->empty = true;
    e->valid = true;
    e->tnear = INFINITY, e->tfar = -INFINITY;
    for (int a = 0; a < 3; a++) e->omin[a] = e->dmin[a] = INFINITY, e->omax[a] = e->dmax[a] = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        ref_ray pr = tk_prepared(&s->raw[rays[i]]);
        const ref_ray *r = &pr;
        if (!ref_ray_valid(r) || !(r->tnear <= r->tfar)) continue;
        e->empty = false;
        e->tnear = fminf(e->tnear, r->tnear), e->tfar = fmaxf(e->tfar, r->tfar);
        for (int a = 0; a < 3; a++) {
            e->omin[a] = fminf(e->omin[a], r->o[a]), e->omax[a] = fmaxf(e->omax[a], r->o[a]);
            e->dmin[a] = fminf(e->dmin[a], r->d[a]), e->dmax[a] = fmaxf(e->dmax[a], r->d[a]);
            if (fabsf(r->o[a]) >= 1e18f) e->valid = false;
        }
    }
}

static bool frustum_equal(const lanes_frustum *a, const lanes_frustum *b)
{
    if (a->valid != b->valid || a->empty != b->empty) return false;
    if (a->empty || !a->valid) return true;
    bool eq = a->tnear == b->tnear && a->tfar == b->tfar && a->has_planes == b->has_planes;
    for (int i = 0; i < 3; i++)
        eq = eq && a->omin[i] == b->omin[i] && a->omax[i] == b->omax[i] && a->dmin[i] == b->dmin[i] &&
             a->dmax[i] == b->dmax[i] && a->rmin[i] == b->rmin[i] && a->rmax[i] == b->rmax[i] &&
             a->ia_axis_ok[i] == b->ia_axis_ok[i];
    if (eq && a->has_planes) {
        eq = a->k == b->k && a->ksign == b->ksign && a->near == b->near;
        for (int i = 0; i < 3; i++)
            if (i != a->k)
                eq = eq && a->lo0[i] == b->lo0[i] && a->hi0[i] == b->hi0[i] && a->lo_slope[i] == b->lo_slope[i] &&
                     a->hi_slope[i] == b->hi_slope[i];
    }
    return eq;
}

static lanes_rays rays_at(const lanes_rays *R, size_t r0, size_t n)
{
    lanes_rays v = *R;
    float **f[] = {&v.ox, &v.oy, &v.oz, &v.dx, &v.dy, &v.dz, &v.rdx, &v.rdy, &v.rdz, &v.tnear, &v.tfar};
    for (size_t i = 0; i < sizeof f / sizeof f[0]; i++) *f[i] += r0;
    v.count = n, v.capacity = R->capacity - r0;
    return v;
}
static lanes_boxes boxes_at(const lanes_boxes *B, size_t p0, size_t n)
{
    lanes_boxes v = *B;
    float **f[] = {&v.minx, &v.miny, &v.minz, &v.maxx, &v.maxy, &v.maxz};
    for (size_t i = 0; i < sizeof f / sizeof f[0]; i++) *f[i] += p0;
    v.count = n, v.capacity = B->capacity - p0;
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

static void describe_packet(const fr_set *s, const fr_block *b, char *buf, size_t size)
{
    int at = snprintf(buf, size, "%s packet of %zu rays:", kname[b->kind], b->nr);
    for (size_t i = 0; i < b->nr && i < 4 && at > 0 && (size_t)at < size; i++) {
        char rb[200];
        tk_fmt_ray(rb, sizeof rb, &s->raw[b->r0 + i]);
        at += snprintf(buf + at, size - (size_t)at, " [%s]", rb);
    }
    if (b->nr > 4 && at > 0 && (size_t)at < size) snprintf(buf + at, size - (size_t)at, " ...");
}

void tk_family_frustum(tk_ctx *c, int arg)
{
    (void)arg;
    if (c->n_isa == 0) return;
    tk_rng g;
    tk_seed(&g, c->seed ^ 0xf2057);
    fr_set S;
    memset(&S, 0, sizeof S);
    fr_set *s = &S;
    hand_packets(&g, s);
    size_t n_hand = s->nblocks;
    size_t cases_b = 0, cases_t = 0;
    while (cases_b < c->target || cases_t < c->target) {
        int kind = (int)tk_below(&g, K_COUNT);
        if (tk_chance(&g, 0.3)) kind = K_PRIMARY;
        size_t nr = kind == K_EMPTY && tk_chance(&g, 0.3) ? 0 : 1 + tk_below(&g, FR_MAXN);
        size_t nb = 1 + tk_below(&g, FR_MAXN), nt = 1 + tk_below(&g, FR_MAXN);
        fr_block *b = new_block(s, nr, nb, nt);
        b->kind = kind;
        fr_geom G;
        gen_packet(&g, s, b, &G);
        bool side_ok = kind == K_PRIMARY;
        for (size_t i = 0; i < nb; i++) gen_box(&g, s, b, &G, b->b0 + i, side_ok);
        for (size_t i = 0; i < nt; i++) gen_tri(&g, s, b, &G, b->t0 + i, side_ok);
        cases_b += nb, cases_t += nt;
    }
    /* index arrays: shuffles of the packets' rays */
    for (size_t k = 0; k < s->nblocks; k++) {
        fr_block *b = &s->blocks[k];
        uint32_t *ix = s->idx + b->idx_at;
        for (size_t i = 0; i < b->nr; i++) ix[i] = (uint32_t)(b->r0 + i);
        for (size_t i = b->nr; i > 1; i--) {
            size_t j = tk_below(&g, (uint32_t)i);
            uint32_t t = ix[i - 1];
            ix[i - 1] = ix[j], ix[j] = t;
        }
    }
    /* references: does some active ray of the packet hit the primitive? */
    s->box_hit = malloc(s->nboxes);
    s->tri_hit = malloc(s->ntris);
    if (!s->box_hit || !s->tri_hit) abort();
    memset(s->box_hit, 0, s->nboxes);
    memset(s->tri_hit, 0, s->ntris);
    size_t nbox = 0, ntri = 0;
    for (size_t k = 0; k < s->nblocks; k++) {
        const fr_block *b = &s->blocks[k];
        nbox += b->nb, ntri += b->nt;
        for (size_t j = 0; j < b->nb; j++)
            for (size_t i = 0; i < b->nr && !s->box_hit[b->b0 + j]; i++) {
                ref_ray pr = tk_prepared(&s->raw[b->r0 + i]);
                s->box_hit[b->b0 + j] = ref_box_hit(&pr, s->lo[b->b0 + j], s->hi[b->b0 + j]);
            }
        for (size_t j = 0; j < b->nt; j++)
            for (size_t i = 0; i < b->nr && !s->tri_hit[b->t0 + j]; i++) {
                const float(*v)[3] = s->v[b->t0 + j];
                ref_ray pr = tk_prepared(&s->raw[b->r0 + i]);
                s->tri_hit[b->t0 + j] = ref_tri_hit(&pr, v[0], v[1], v[2]);
            }
    }
    printf("  frustum cases: %zu packets (%zu hand-written), %zu (packet, box) and %zu (packet, triangle) pairs\n",
           s->nblocks, n_hand, nbox, ntri);

    lanes_rays R;
    lanes_boxes B;
    lanes_triangles T;
    if (!lanes_rays_alloc(&R, s->nrays) || !lanes_boxes_alloc(&B, s->nboxes) || !lanes_triangles_alloc(&T, s->ntris))
        abort();
    for (size_t i = 0; i < s->nrays; i++) tk_put_ray(&R, i, &s->raw[i]);
    /* the lanes between packets: garbage that must not reach the frustum */
    for (size_t k = 0, prev = 0; k <= s->nblocks; k++) {
        size_t start = k < s->nblocks ? s->blocks[k].r0 : s->nrays;
        for (size_t i = prev; i < start; i++) tk_garbage_ray(&R, i, (unsigned)i);
        if (k < s->nblocks) prev = s->blocks[k].r0 + s->blocks[k].nr;
    }
    float *bx[6] = {B.minx, B.miny, B.minz, B.maxx, B.maxy, B.maxz};
    for (size_t i = 0; i < s->nboxes; i++) {
        if (s->bcat[i] == 0xff) {
            tk_garbage_box(&B, i, (unsigned)i);
            continue;
        }
        for (int a = 0; a < 3; a++) bx[a][i] = s->lo[i][a], bx[3 + a][i] = s->hi[i][a];
    }
    float *tv[3][3] = {{T.v0x, T.v0y, T.v0z}, {T.v1x, T.v1y, T.v1z}, {T.v2x, T.v2y, T.v2z}};
    for (size_t i = 0; i < s->ntris; i++) {
        if (s->tcat[i] == 0xff) {
            tk_garbage_tri(&T, i, (unsigned)i);
            continue;
        }
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 3; a++) tv[k][a][i] = s->v[i][k][a];
    }

    /* per set: keep bits of every (method, primitive type), for the
     * cross-set comparison */
    size_t words_b = 0, words_t = 0;
    for (size_t k = 0; k < s->nblocks; k++)
        words_b += lanes_mask_words(s->blocks[k].nb), words_t += lanes_mask_words(s->blocks[k].nt);
    uint32_t *keep_rep[2][3], *keep_cur[2][3];
    for (int q = 0; q < 2; q++)
        for (int m = 0; m < 3; m++) {
            size_t nw = q ? words_t : words_b;
            keep_rep[q][m] = malloc((nw + 1) * sizeof(uint32_t));
            keep_cur[q][m] = malloc((nw + 1) * sizeof(uint32_t));
            if (!keep_rep[q][m] || !keep_cur[q][m]) abort();
        }
    lanes_frustum *f_rep = malloc(s->nblocks * sizeof *f_rep), *f_cur = malloc(s->nblocks * sizeof *f_cur);
    if (!f_rep || !f_cur) abort();
    const char *rep_name = NULL;
    static const lanes_cull_method methods[3] = {LANES_CULL_INTERVAL, LANES_CULL_PLANES, LANES_CULL_BOTH};
    static const char *const mname[3] = {"INTERVAL", "PLANES", "BOTH"};

    for (int i = 0; i < c->n_isa; i++) {
        const lanes_kernels *k = c->isa[i];
        const int W = k->lanes;
        tk_group gb, gc[2], gs;
        tk_begin(&gb, c, "%s frustum_build: fields, idx == positions", k->name);
        tk_begin(&gc[0], c, "%s frustum_boxes: no cull of a box some active ray hits", k->name);
        tk_begin(&gc[1], c, "%s frustum_tris: no cull of a triangle some active ray hits", k->name);
        tk_begin(&gs, c, "%s frustum kernels: lane stats, stats-independence, sentinels", k->name);
        /* culled counts: [prim][method][packet kind][category] */
        static size_t culled[2][3][K_COUNT][C_COUNT], total[2][K_COUNT][C_COUNT];
        memset(culled, 0, sizeof culled);
        memset(total, 0, sizeof total);
        size_t off[2] = {0, 0};
        for (size_t blk = 0; blk < s->nblocks; blk++) {
            const fr_block *b = &s->blocks[blk];
            lanes_rays Rb = rays_at(&R, b->r0, b->nr);
            lanes_frustum f, fi;
            memset(&f, 0x5a, sizeof f);
            k->frustum_build(&Rb, NULL, b->nr, &f);
            k->frustum_build(&R, s->idx + b->idx_at, b->nidx, &fi);
            f_cur[blk] = f;
            char pb[1200];
            if (!frustum_equal(&f, &fi)) {
                describe_packet(s, b, pb, sizeof pb);
                tk_fail(&gb, "block %zu: frustum through idx differs from the one by position; %s", blk, pb);
            }
            uint32_t rays[FR_MAXN];
            for (size_t q = 0; q < b->nr; q++) rays[q] = (uint32_t)(b->r0 + q);
            fr_expect e;
            expect_frustum(s, rays, b->nr, &e);
            bool ok = f.empty == e.empty && (e.empty || f.valid == e.valid);
            if (ok && !e.empty && e.valid) {
                ok = f.tnear == e.tnear && f.tfar == e.tfar;
                for (int a = 0; a < 3; a++)
                    ok = ok && f.omin[a] == e.omin[a] && f.omax[a] == e.omax[a] && f.dmin[a] == e.dmin[a] &&
                         f.dmax[a] == e.dmax[a];
            }
            if (!ok) {
                describe_packet(s, b, pb, sizeof pb);
                tk_fail(&gb, "block %zu: frustum valid=%d empty=%d tnear=%a tfar=%a omin.x=%a dmin.x=%a, "
                             "expected valid=%d empty=%d tnear=%a tfar=%a omin.x=%a dmin.x=%a; %s",
                        blk, f.valid, f.empty, (double)f.tnear, (double)f.tfar, (double)f.omin[0],
                        (double)f.dmin[0], e.valid, e.empty, (double)e.tnear, (double)e.tfar,
                        (double)e.omin[0], (double)e.dmin[0], pb);
            }
            for (int q = 0; q < 2; q++) {
                size_t n = q ? b->nt : b->nb;
                size_t nw = lanes_mask_words(n);
                const uint8_t *cat = q ? s->tcat + b->t0 : s->bcat + b->b0;
                const uint8_t *hit = q ? s->tri_hit + b->t0 : s->box_hit + b->b0;
                lanes_boxes Bb = boxes_at(&B, b->b0, b->nb);
                lanes_triangles Tb = tris_at(&T, b->t0, b->nt);
                uint32_t kw[3][4];
                for (int m = 0; m < 3; m++) {
                    uint32_t w1[4], w2[4], sent = tk_word_sentinel(blk + (size_t)m);
                    for (int x = 0; x < 4; x++) w1[x] = w2[x] = sent;
                    lanes_lane_stats st = {0, 0, 0};
                    size_t kept, kept2;
                    if (q) {
                        kept = k->frustum_tris(&f, &Tb, n, methods[m], w1, NULL);
                        kept2 = k->frustum_tris(&f, &Tb, n, methods[m], w2, &st);
                    } else {
                        kept = k->frustum_boxes(&f, &Bb, n, methods[m], w1, NULL);
                        kept2 = k->frustum_boxes(&f, &Bb, n, methods[m], w2, &st);
                    }
                    if (kept != kept2 || memcmp(w1, w2, sizeof w1))
                        tk_fail(&gs, "block %zu %s %s: results with stats differ", blk, q ? "tris" : "boxes", mname[m]);
                    if (!tk_stats_ok(&st, n, W))
                        tk_fail(&gs, "block %zu %s n=%zu: stats ops=%llu slots=%llu active=%llu", blk,
                                q ? "tris" : "boxes", n, (unsigned long long)st.vector_ops,
                                (unsigned long long)st.lane_slots, (unsigned long long)st.active_lanes);
                    for (size_t x = nw; x < nw + 2 && x < 4; x++)
                        if (w1[x] != sent) tk_fail(&gs, "block %zu: keep word %zu past n=%zu written", blk, x, n);
                    if (n % 32 && (w1[nw - 1] & ~((1u << (n % 32)) - 1u) & ~sent))
                        tk_fail(&gs, "block %zu: keep bits past n=%zu set", blk, n);
                    size_t pc = 0;
                    for (size_t j = 0; j < n; j++) pc += lanes_mask_get(w1, j);
                    if (pc != kept) tk_fail(&gs, "block %zu: returned %zu, %zu bits set", blk, kept, pc);
                    memcpy(kw[m], w1, sizeof kw[m]);
                    for (size_t j = 0; j < n; j++) {
                        bool kp = lanes_mask_get(w1, j);
                        if (m == 0) total[q][b->kind][cat[j]]++;
                        if (!kp) culled[q][m][b->kind][cat[j]]++;
                        if (!kp && hit[j]) {
                            describe_packet(s, b, pb, sizeof pb);
                            char pr[300];
                            if (q) {
                                char v0[96], v1[96], v2[96];
                                tk_fmt3(v0, sizeof v0, s->v[b->t0 + j][0]);
                                tk_fmt3(v1, sizeof v1, s->v[b->t0 + j][1]);
                                tk_fmt3(v2, sizeof v2, s->v[b->t0 + j][2]);
                                snprintf(pr, sizeof pr, "triangle %s %s %s", v0, v1, v2);
                            } else {
                                char lo[96], hi[96];
                                tk_fmt3(lo, sizeof lo, s->lo[b->b0 + j]);
                                tk_fmt3(hi, sizeof hi, s->hi[b->b0 + j]);
                                snprintf(pr, sizeof pr, "box lo=%s hi=%s", lo, hi);
                            }
                            tk_fail(&gc[q], "%s culled %s (%s, block %zu #%zu) that a ray hits; %s", mname[m], pr,
                                    cname[cat[j]], blk, j, pb);
                        }
                        /* an empty frustum culls everything, an invalid one nothing */
                        if (f.empty && kp) tk_fail(&gc[q], "block %zu: empty frustum kept #%zu", blk, j);
                        if (!f.empty && !f.valid && !kp) tk_fail(&gc[q], "block %zu: invalid frustum culled #%zu", blk, j);
                    }
                    for (size_t x = 0; x < nw; x++) keep_cur[q][m][off[q] + x] = w1[x];
                }
                for (size_t x = 0; x < nw; x++)
                    if (kw[2][x] != (kw[0][x] & kw[1][x]))
                        tk_fail(&gs, "block %zu %s: BOTH keeps 0x%08x, INTERVAL & PLANES 0x%08x", blk,
                                q ? "tris" : "boxes", kw[2][x], kw[0][x] & kw[1][x]);
                off[q] += nw;
            }
        }
        tk_end(&gb, "%zu packets", s->nblocks);
        /* culling must not be vacuous: the far-side primitives of coherent
         * primary packets are culled by every method */
        for (int q = 0; q < 2; q++) {
            size_t tot = 0, hits = 0;
            for (int kk = 0; kk < K_COUNT; kk++)
                for (int cc = 0; cc < C_COUNT; cc++) tot += total[q][kk][cc];
            for (size_t j = 0; j < (q ? s->ntris : s->nboxes); j++)
                if (q ? s->tcat[j] != 0xff && s->tri_hit[j] : s->bcat[j] != 0xff && s->box_hit[j]) hits++;
            for (int m = 0; m < 3; m++) {
                size_t side = total[q][K_PRIMARY][C_SIDE], cs = culled[q][m][K_PRIMARY][C_SIDE];
                if (side == 0 || (double)cs < FR_MIN_SIDE_CULL * (double)side)
                    tk_fail(&gc[q], "%s culls %zu of %zu far-side %s of primary packets (at least %.0f%% wanted)",
                            mname[m], cs, side, q ? "triangles" : "boxes", 100 * FR_MIN_SIDE_CULL);
            }
            size_t cul[3] = {0, 0, 0};
            for (int m = 0; m < 3; m++)
                for (int kk = 0; kk < K_COUNT; kk++)
                    for (int cc = 0; cc < C_COUNT; cc++) cul[m] += culled[q][m][kk][cc];
            tk_end(&gc[q], "%zu pairs, %zu hit by some ray; culled: INTERVAL %.1f%%, PLANES %.1f%%, BOTH %.1f%%", tot,
                   hits, 100.0 * (double)cul[0] / (double)tot, 100.0 * (double)cul[1] / (double)tot,
                   100.0 * (double)cul[2] / (double)tot);
            if (i == 0) {
                printf("  %s culled, per packet kind and category (INTERVAL/PLANES/BOTH %% of count):\n",
                       q ? "triangles" : "boxes");
                for (int kk = 0; kk < K_COUNT; kk++) {
                    printf("    %-14s", kname[kk]);
                    for (int cc = 0; cc < C_COUNT; cc++) {
                        size_t t = total[q][kk][cc];
                        if (!t) continue;
                        printf(" %s: %.0f/%.0f/%.0f of %zu;", cname[cc], 100.0 * (double)culled[q][0][kk][cc] / (double)t,
                               100.0 * (double)culled[q][1][kk][cc] / (double)t,
                               100.0 * (double)culled[q][2][kk][cc] / (double)t, t);
                    }
                    printf("\n");
                }
            }
        }
        tk_end(&gs, NULL);
        /* frustum building uses no FMA: every set agrees */
        if (!rep_name) {
            rep_name = k->name;
            memcpy(f_rep, f_cur, s->nblocks * sizeof *f_rep);
            for (int q = 0; q < 2; q++)
                for (int m = 0; m < 3; m++)
                    memcpy(keep_rep[q][m], keep_cur[q][m], (q ? words_t : words_b) * sizeof(uint32_t));
        } else {
            tk_group gx;
            tk_begin(&gx, c, "%s frustum build and culls == %s", k->name, rep_name);
            for (size_t blk = 0; blk < s->nblocks; blk++)
                if (!frustum_equal(&f_cur[blk], &f_rep[blk])) tk_fail(&gx, "block %zu: frusta differ", blk);
            for (int q = 0; q < 2; q++)
                for (int m = 0; m < 3; m++)
                    for (size_t x = 0; x < (q ? words_t : words_b); x++)
                        if (keep_cur[q][m][x] != keep_rep[q][m][x]) {
                            tk_fail(&gx, "%s %s keep word %zu: 0x%08x vs 0x%08x", q ? "tris" : "boxes", mname[m], x,
                                    keep_cur[q][m][x], keep_rep[q][m][x]);
                        }
            tk_end(&gx, NULL);
        }
    }
    for (int q = 0; q < 2; q++)
        for (int m = 0; m < 3; m++) free(keep_rep[q][m]), free(keep_cur[q][m]);
    free(f_rep), free(f_cur);
    lanes_rays_free(&R);
    lanes_boxes_free(&B);
    lanes_triangles_free(&T);
    free(s->raw), free(s->lo), free(s->hi), free(s->bcat), free(s->v), free(s->tcat), free(s->blocks);
    free(s->box_hit), free(s->tri_hit), free(s->idx);
}
