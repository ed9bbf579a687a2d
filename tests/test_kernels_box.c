/* Box kernels: box_packet (by position and through an index array),
 * box_partition (out of place, in place, without idx) and box_wide, on the
 * same ray/box pairs for every set, against ref_box().
 *
 * Cases come in blocks of nr rays x nb boxes; every pair of a block is a
 * case, seen by the packet forms (one box, nr rays) and by the wide form
 * (one ray, nb boxes). Blocks start at multiples of LANES_MAX_W so that the
 * position form can be handed a lanes_rays whose arrays start at the block;
 * the lanes between blocks hold garbage that hits everything (or is NaN) if
 * a kernel forgets to mask them. */
#include <float.h>
#include <stdlib.h>

#include "test_kernels_common.h"

#define BX_MAXN 72 /* rays or boxes per block */

typedef struct {
    size_t r0, nr, p0, np, pair0;
} bx_block;

typedef struct {
    ref_ray *raw;
    bool *ray_gap;
    int32_t *target; /* per ray: the block-local box it was aimed at, -1 if none */
    bool *targeted;  /* per ray: aimed at that box's boundary on purpose */
    size_t nrays, cap_r;
    float (*lo)[3], (*hi)[3];
    bool *box_gap;
    bool *box_special; /* flat, or empty by one float: every pair is near a tie */
    size_t nboxes, cap_b;
    bx_block *blocks;
    size_t nblocks, cap_k;
    size_t npairs;
    uint8_t *ref_hit;
    float *margin;
    double *ref_te;
    int16_t *hand;
    uint8_t *flags; /* PF_* */
} bx_set;

enum { PF_HARD = 1, PF_TARGETED = 2 };

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

static bx_block *bx_new_block(bx_set *s, size_t nr, size_t np)
{
    size_t r0 = round_up(s->nrays), p0 = round_up(s->nboxes);
    if (r0 + nr > s->cap_r) {
        s->cap_r = new_cap(s->cap_r, r0 + nr);
        s->raw = grow_to(s->raw, s->cap_r, sizeof *s->raw);
        s->ray_gap = grow_to(s->ray_gap, s->cap_r, sizeof *s->ray_gap);
        s->target = grow_to(s->target, s->cap_r, sizeof *s->target);
        s->targeted = grow_to(s->targeted, s->cap_r, sizeof *s->targeted);
    }
    for (size_t i = s->nrays; i < r0 + nr; i++) s->target[i] = -1, s->targeted[i] = false;
    for (size_t i = s->nrays; i < r0; i++) {
        s->ray_gap[i] = true;
        memset(&s->raw[i], 0, sizeof s->raw[i]);
        s->raw[i].o[0] = NAN;
    }
    for (size_t i = r0; i < r0 + nr; i++) s->ray_gap[i] = false;
    s->nrays = r0 + nr;

    if (p0 + np > s->cap_b) {
        s->cap_b = new_cap(s->cap_b, p0 + np);
        s->lo = grow_to(s->lo, s->cap_b, sizeof *s->lo);
        s->hi = grow_to(s->hi, s->cap_b, sizeof *s->hi);
        s->box_gap = grow_to(s->box_gap, s->cap_b, sizeof *s->box_gap);
        s->box_special = grow_to(s->box_special, s->cap_b, sizeof *s->box_special);
    }
    for (size_t i = s->nboxes; i < p0; i++) {
        s->box_gap[i] = true;
        for (int a = 0; a < 3; a++) s->lo[i][a] = s->hi[i][a] = NAN;
    }
    for (size_t i = s->nboxes; i < p0 + np; i++) s->box_special[i] = false;
    for (size_t i = p0; i < p0 + np; i++) s->box_gap[i] = false;
    s->nboxes = p0 + np;

    if (s->nblocks + 1 > s->cap_k) {
        s->cap_k = new_cap(s->cap_k, s->nblocks + 1);
        s->blocks = grow_to(s->blocks, s->cap_k, sizeof *s->blocks);
    }
    bx_block *b = &s->blocks[s->nblocks++];
    b->r0 = r0, b->nr = nr, b->p0 = p0, b->np = np, b->pair0 = s->npairs;
    s->npairs += nr * np;
    return b;
}

/* ---- random boxes and rays ---- */

typedef struct {
    double S;    /* scale of the block */
    double C[3]; /* its centre */
} bx_frame;

static bool random_box(tk_rng *g, const bx_frame *f, float lo[3], float hi[3])
{
    for (int a = 0; a < 3; a++) {
        double c = f->C[a] + f->S * tk_range(g, -1, 1);
        double h = f->S * exp2(tk_range(g, -8, 0));
        lo[a] = (float)(c - h), hi[a] = (float)(c + h);
    }
    double p = tk_unit(g);
    if (p < 0.06) {
        int a = (int)tk_below(g, 3);
        hi[a] = lo[a]; /* flat */
        if (p < 0.02) hi[(a + 1) % 3] = lo[(a + 1) % 3];
        return true;
    }
    if (p < 0.09) {
        int a = (int)tk_below(g, 3); /* empty: inverted, by far or by one float */
        if (tk_chance(g, 0.5)) {
            float t = lo[a];
            lo[a] = hi[a], hi[a] = t;
        } else {
            lo[a] = tk_ulps(hi[a], 1);
            return true;
        }
    }
    return false;
}

/* A point of the box: inside, or with `nb` coordinates on its bounds. */
static void box_point(tk_rng *g, const float lo[3], const float hi[3], int nb, double p[3])
{
    int first = (int)tk_below(g, 3);
    for (int a = 0; a < 3; a++) {
        int k = (a - first + 3) % 3;
        if (k < nb)
            p[a] = tk_chance(g, 0.5) ? lo[a] : hi[a];
        else
            p[a] = lo[a] + (hi[a] - (double)lo[a]) * tk_unit(g);
    }
}

static void set_dir(tk_rng *g, ref_ray *r, const double d[3])
{
    double scale = exp2(tk_range(g, -6, 6));
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (len == 0) len = 1;
    for (int a = 0; a < 3; a++) r->d[a] = (float)(d[a] / len * scale);
}

static void random_origin(tk_rng *g, const bx_frame *f, double spread, float o[3])
{
    for (int a = 0; a < 3; a++) o[a] = (float)(f->C[a] + f->S * spread * tk_range(g, -1, 1));
}

/* Slab entry and exit of a ray against a box, in double, ignoring tnear and
 * tfar: used only to place tnear/tfar near the boundary. */
static void slab_range(const ref_ray *r, const float lo[3], const float hi[3], double *tin, double *tout)
{
    *tin = -INFINITY, *tout = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (r->d[a] == 0) continue;
        double t0 = (lo[a] - (double)r->o[a]) / r->d[a], t1 = (hi[a] - (double)r->o[a]) / r->d[a];
        if (t0 > t1) {
            double t = t0;
            t0 = t1, t1 = t;
        }
        *tin = fmax(*tin, t0), *tout = fmin(*tout, t1);
    }
}

static void corrupt_ray(tk_rng *g, ref_ray *r)
{
    float nan = tk_from_bits(0x7fc00000u | tk_below(g, 1u << 22));
    switch (tk_below(g, 7)) {
    case 0: r->o[tk_below(g, 3)] = nan; break;
    case 1: r->d[tk_below(g, 3)] = tk_chance(g, 0.5) ? nan : -nan; break;
    case 2: r->o[tk_below(g, 3)] = (float)tk_sign(g) * INFINITY; break;
    case 3: r->d[tk_below(g, 3)] = (float)tk_sign(g) * INFINITY; break;
    case 4: r->tnear = nan; break;
    case 5: r->tfar = nan; break;
    default:
        for (int a = 0; a < 3; a++) r->d[a] = tk_chance(g, 0.5) ? 0.0f : -0.0f;
        break;
    }
}

static bool random_t_range(tk_rng *g, const bx_frame *f, ref_ray *r, const float lo[3], const float hi[3])
{
    double p = tk_unit(g);
    r->tnear = 0.0f, r->tfar = INFINITY;
    if (p < 0.55) return false;
    if (p < 0.63) {
        r->tnear = tk_chance(g, 0.5) ? -INFINITY : (float)(-f->S * tk_unit(g));
        if (tk_chance(g, 0.3)) r->tnear = -0.0f;
        return false;
    }
    if (p < 0.88) {
        /* bounds placed on (or a few floats from) the entry or exit */
        double tin, tout;
        slab_range(r, lo, hi, &tin, &tout);
        if (!isfinite(tin) || !isfinite(tout)) return false;
        int k = (int)tk_below(g, 5) - 2;
        switch (tk_below(g, 4)) {
        case 0: r->tfar = tk_ulps((float)tin, k); break;
        case 1: r->tnear = tk_ulps((float)tout, k); break;
        case 2: r->tnear = r->tfar = tk_ulps((float)tin, k); break;
        default: r->tnear = r->tfar = tk_ulps((float)tout, k); break;
        }
        if (r->tnear > r->tfar && tk_chance(g, 0.5)) r->tnear = r->tfar;
        return true;
    }
    if (p < 0.94) {
        r->tfar = 0.0f;
        if (tk_chance(g, 0.3)) r->tnear = tk_chance(g, 0.5) ? 0.0f : -0.0f;
        return true;
    }
    double a = tk_range(g, -1, 10) * f->S, b = tk_range(g, -1, 10) * f->S;
    r->tnear = (float)fmin(a, b), r->tfar = (float)fmax(a, b);
    return false;
}

/* Returns whether the ray was aimed at the boundary of box *target on purpose. */
static bool random_ray(tk_rng *g, const bx_frame *f, const float (*lo)[3], const float (*hi)[3],
                       size_t nb, ref_ray *r, size_t *target)
{
    size_t tb = tk_below(g, (uint32_t)nb);
    bool targeted = false;
    *target = tb;
    const float *L = lo[tb], *H = hi[tb];
    double p = tk_unit(g), aim[3], d[3];
    random_origin(g, f, 4.0, r->o);
    if (p < 0.22) {
        box_point(g, L, H, 0, aim);
    } else if (p < 0.42) {
        targeted = true;
        box_point(g, L, H, 1 + (int)tk_below(g, 3), aim);
        if (tk_chance(g, 0.6)) {
            int a = (int)tk_below(g, 3);
            aim[a] = tk_ulps((float)aim[a], (int)tk_below(g, 9) - 4);
        }
    } else if (p < 0.50) {
        for (int a = 0; a < 3; a++) aim[a] = r->o[a] + tk_range(g, -1, 1);
    } else if (p < 0.66) {
        /* axis-parallel: one or two components ±0, the origin on those axes
         * on a bound, just outside or inside, or anywhere */
        targeted = true;
        box_point(g, L, H, (int)tk_below(g, 2), aim);
        for (int a = 0; a < 3; a++) d[a] = aim[a] - r->o[a];
        set_dir(g, r, d);
        int nz = 1 + (int)tk_below(g, 2), first = (int)tk_below(g, 3);
        for (int k = 0; k < nz; k++) {
            int a = (first + k) % 3;
            r->d[a] = tk_chance(g, 0.5) ? 0.0f : -0.0f;
            switch (tk_below(g, 7)) {
            case 0: r->o[a] = L[a]; break;
            case 1: r->o[a] = H[a]; break;
            case 2: r->o[a] = tk_ulps(L[a], -1); break;
            case 3: r->o[a] = tk_ulps(H[a], 1); break;
            case 4: r->o[a] = tk_ulps(L[a], 1); break;
            case 5: r->o[a] = (float)aim[a]; break;
            default: break;
            }
        }
        goto t_range;
    } else if (p < 0.78) {
        /* origin on a face (or edge), going anywhere */
        double q[3];
        targeted = true;
        box_point(g, L, H, 1 + (int)tk_below(g, 2), q);
        for (int a = 0; a < 3; a++) r->o[a] = (float)q[a];
        if (tk_chance(g, 0.5))
            box_point(g, L, H, 0, aim);
        else
            for (int a = 0; a < 3; a++) aim[a] = r->o[a] + tk_range(g, -1, 1);
        if (tk_chance(g, 0.3)) {
            /* and lying in the face's plane */
            for (int a = 0; a < 3; a++) d[a] = aim[a] - r->o[a];
            set_dir(g, r, d);
            for (int a = 0; a < 3; a++)
                if (r->o[a] == L[a] || r->o[a] == H[a]) {
                    r->d[a] = tk_chance(g, 0.5) ? 0.0f : -0.0f;
                    break;
                }
            goto t_range;
        }
    } else if (p < 0.86) {
        /* from inside */
        double q[3];
        box_point(g, L, H, 0, q);
        for (int a = 0; a < 3; a++) r->o[a] = (float)q[a], aim[a] = q[a] + tk_range(g, -1, 1);
    } else if (p < 0.93) {
        /* from far away, at a point inside or on the boundary */
        targeted = true;
        box_point(g, L, H, (int)tk_below(g, 2), aim);
        double dist = f->S * exp2(tk_range(g, 4, 20));
        for (int a = 0; a < 3; a++) r->o[a] = (float)(aim[a] + dist * tk_range(g, -1, 1));
    } else {
        /* a face pair at exactly equal distance: ties between slabs */
        targeted = true;
        box_point(g, L, H, 2, aim);
        for (int a = 0; a < 3; a++) r->o[a] = (float)(aim[a] - tk_sign(g) * f->S);
    }
    for (int a = 0; a < 3; a++) d[a] = aim[a] - r->o[a];
    set_dir(g, r, d);
t_range:
    targeted = random_t_range(g, f, r, L, H) || targeted;
    if (tk_chance(g, 0.02)) corrupt_ray(g, r);
    return targeted;
}

static void random_frame(tk_rng *g, bx_frame *f)
{
    f->S = tk_chance(g, 0.7) ? 1.0 : exp2(tk_range(g, -30, 30));
    for (int a = 0; a < 3; a++)
        f->C[a] = tk_chance(g, 0.7) ? 0.0 : tk_sign(g) * f->S * exp2(tk_range(g, 0, 20));
}

static size_t block_size(tk_rng *g)
{
    return tk_chance(g, 0.3) ? 1 + tk_below(g, 17) : 1 + tk_below(g, 64);
}

static void fill_block(tk_rng *g, bx_set *s, const bx_block *b, const bx_frame *f)
{
    for (size_t i = 0; i < b->np; i++)
        s->box_special[b->p0 + i] = random_box(g, f, s->lo[b->p0 + i], s->hi[b->p0 + i]);
    for (size_t i = 0; i < b->nr; i++) {
        size_t t;
        s->targeted[b->r0 + i] = random_ray(g, f, (const float(*)[3])(s->lo + b->p0),
                                            (const float(*)[3])(s->hi + b->p0), b->np,
                                            &s->raw[b->r0 + i], &t);
        s->target[b->r0 + i] = (int32_t)t;
    }
}

/* ---- hand-written cases (shared/research/robustness.md §7a) ---- */

typedef struct {
    char name[80];
    ref_ray r;
    float lo[3], hi[3];
    int hit;      /* expected */
    double te;    /* expected tentry when hit, NAN if not stated */
    bool hard;    /* no tolerance: float code decides this exactly */
} bx_hand;

#define NH_MAX 96

static int add_hand(bx_hand *h, int n, const char *name, ref_ray r, const float lo[3],
                    const float hi[3], int hit, double te, bool hard)
{
    if (n >= NH_MAX) abort();
    snprintf(h[n].name, sizeof h[n].name, "%s", name);
    h[n].r = r;
    memcpy(h[n].lo, lo, sizeof h[n].lo);
    memcpy(h[n].hi, hi, sizeof h[n].hi);
    h[n].hit = hit, h[n].te = te, h[n].hard = hard;
    return n + 1;
}

static ref_ray mkray(float ox, float oy, float oz, float dx, float dy, float dz, float tn, float tf)
{
    ref_ray r = {{ox, oy, oz}, {dx, dy, dz}, tn, tf};
    return r;
}

static int hand_cases(bx_hand *h)
{
    const float U0[3] = {0, 0, 0}, U1[3] = {1, 1, 1};
    const float inf = INFINITY, nan = NAN;
    int n = 0;
    char name[80];
    /* A1 */
    n = add_hand(h, n, "A1 d=(+0,+0,1)", mkray(.5f, .5f, -1, 0.0f, 0.0f, 1, 0, inf), U0, U1, 1, 1, true);
    n = add_hand(h, n, "A1 d=(-0,-0,1)", mkray(.5f, .5f, -1, -0.0f, -0.0f, 1, 0, inf), U0, U1, 1, 1, true);
    n = add_hand(h, n, "A1 d=(+0,-0,-1)", mkray(.5f, .5f, 2, 0.0f, -0.0f, -1, 0, inf), U0, U1, 1, 1, true);
    /* A2: origin in the plane of a face, the direction ±0 on that axis */
    for (int a = 0; a < 3; a++)
        for (int face = 0; face < 2; face++)
            for (int neg = 0; neg < 2; neg++)
                for (int k = 1; k <= 2; k++) {
                    int b = (a + k) % 3;
                    ref_ray r = mkray(.5f, .5f, .5f, 0, 0, 0, 0, inf);
                    r.o[a] = (float)face;
                    r.d[a] = neg ? -0.0f : 0.0f;
                    r.o[b] = -1;
                    r.d[b] = 1;
                    snprintf(name, sizeof name, "A2 o[%d]=%d d[%d]=%s0 travel %d", a, face, a,
                             neg ? "-" : "+", b);
                    n = add_hand(h, n, name, r, U0, U1, 1, 1, true);
                }
    /* A3 edges and corners */
    n = add_hand(h, n, "A3 edge", mkray(0, 0, -1, 0, 0, 1, 0, inf), U0, U1, 1, 1, true);
    n = add_hand(h, n, "A3 corner -0", mkray(1, 1, -1, -0.0f, -0.0f, 1, 0, inf), U0, U1, 1, 1, true);
    /* A4 just outside, denormal outside, just inside */
    n = add_hand(h, n, "A4 o.x=-1e-7", mkray(-1e-7f, .5f, -1, 0, 0, 1, 0, inf), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "A4 o.x=-denormal", mkray(-0x1p-149f, .5f, -1, 0, 0, 1, 0, inf), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "A4 o.x=1+ulp", mkray(0x1.000002p0f, .5f, -1, -0.0f, 0, 1, 0, inf), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "A4 o.x=+denormal", mkray(0x1p-149f, .5f, -1, 0, 0, 1, 0, inf), U0, U1, 1, 1, true);
    /* A5, A6 flat boxes */
    {
        const float lo[3] = {0, 0, .5f}, hi[3] = {1, 1, .5f};
        n = add_hand(h, n, "A5 flat box crossed", mkray(.5f, .5f, -1, 0, 0, 1, 0, inf), lo, hi, 1, 1.5, true);
        n = add_hand(h, n, "A5 flat box crossed, tilted", mkray(.25f, .25f, -1, .125f, .25f, 1, 0, inf), lo, hi, 1, 1.5, true);
        n = add_hand(h, n, "A6 flat box, ray in its plane", mkray(-1, .5f, .5f, 1, 0, 0, 0, inf), lo, hi, 1, 1, true);
        n = add_hand(h, n, "A6 flat box, ray in its plane, -0", mkray(-1, .5f, .5f, 1, -0.0f, -0.0f, 0, inf), lo, hi, 1, 1, true);
        n = add_hand(h, n, "flat box, parallel ray 1 ulp off", mkray(-1, .5f, 0x1.000002p-1f, 1, 0, 0, 0, inf), lo, hi, 0, NAN, true);
        const float lo2[3] = {0, .5f, .5f}, hi2[3] = {1, .5f, .5f};
        n = add_hand(h, n, "segment box, ray along it", mkray(-1, .5f, .5f, 1, 0, 0, 0, inf), lo2, hi2, 1, 1, true);
        n = add_hand(h, n, "segment box, ray across", mkray(.5f, -1, .5f, 0, 1, 0, 0, inf), lo2, hi2, 1, 1.5, true);
        const float pt[3] = {.5f, .5f, .5f};
        n = add_hand(h, n, "point box, ray through", mkray(.5f, .5f, -1, 0, 0, 1, 0, inf), pt, pt, 1, 1.5, true);
    }
    /* A7 empty boxes */
    {
        const float elo[3] = {inf, inf, inf}, ehi[3] = {-inf, -inf, -inf};
        n = add_hand(h, n, "A7 empty slot +inf/-inf", mkray(.5f, .5f, -1, 0, 0, 1, 0, inf), elo, ehi, 0, NAN, true);
        n = add_hand(h, n, "A7 empty slot, oblique ray", mkray(-1, -2, -3, 1, 2, 3, -inf, inf), elo, ehi, 0, NAN, true);
        n = add_hand(h, n, "A7 inverted box", mkray(.5f, .5f, -1, 0, 0, 1, 0, inf), U1, U0, 0, NAN, true);
        n = add_hand(h, n, "A7 inverted box, oblique ray", mkray(-1, -1, -1, 1, 1, 1, 0, inf), U1, U0, 0, NAN, true);
        const float lo[3] = {0, 0, 1}, hi[3] = {1, 1, 0x1.fffffep-1f};
        n = add_hand(h, n, "A7 empty by one float", mkray(.5f, .5f, -1, 0, 0, 1, 0, inf), lo, hi, 0, NAN, true);
        /* slab distances of an inverted axis that round to one value */
        const float lo3[3] = {1, 0, 0}, hi3[3] = {.5f, 1, 1};
        n = add_hand(h, n, "A7 inverted x slab, far origin (o.x=-1e8)", mkray(-1e8f, .5f, .5f, 1, 0, 0, 0, inf), lo3, hi3, 0, NAN, true);
        n = add_hand(h, n, "A7 inverted x slab, far origin (o.x=1e30)", mkray(1e30f, .5f, .5f, -1, 0, 0, 0, inf), lo3, hi3, 0, NAN, true);
    }
    {
        /* a NaN bound makes no box: never hit */
        const float lo[3] = {0, NAN, 0}, hi[3] = {1, 1, 1};
        n = add_hand(h, n, "box with a NaN bound", mkray(.5f, .5f, -1, 0, 0, 1, 0, inf), lo, hi, 0, NAN, true);
        n = add_hand(h, n, "box with a NaN bound, oblique ray", mkray(-1, -1, -1, 1, 1, 1, 0, inf), lo, hi, 0, NAN, true);
    }
    /* A8 invalid rays */
    n = add_hand(h, n, "A8 NaN o", mkray(nan, .5f, -1, 0, 0, 1, 0, inf), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "A8 NaN d", mkray(.5f, .5f, -1, nan, 0, 1, 0, inf), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "A8 NaN tnear", mkray(.5f, .5f, -1, 0, 0, 1, nan, inf), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "A8 NaN tfar", mkray(.5f, .5f, -1, 0, 0, 1, 0, nan), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "A8 inf o", mkray(-inf, .5f, .5f, 1, 0, 0, 0, inf), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "A8 inf d", mkray(.5f, .5f, -1, 0, 0, inf, 0, inf), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "A8 d=0, origin inside", mkray(.5f, .5f, .5f, 0, -0.0f, 0, 0, inf), U0, U1, 0, NAN, true);
    /* A9 - A11 t bounds */
    n = add_hand(h, n, "A9 tnear=tfar=1.5", mkray(.5f, .5f, -1, 0, 0, 1, 1.5f, 1.5f), U0, U1, 1, 1.5, true);
    n = add_hand(h, n, "A9 tnear=tfar=entry", mkray(.5f, .5f, -1, 0, 0, 1, 1, 1), U0, U1, 1, 1, true);
    n = add_hand(h, n, "A9 tnear=tfar=exit", mkray(.5f, .5f, -1, 0, 0, 1, 2, 2), U0, U1, 1, 2, true);
    n = add_hand(h, n, "A9 tfar=entry-ulp", mkray(.5f, .5f, -1, 0, 0, 1, 0, 0x1.fffffep-1f), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "A9 tnear=exit+ulp", mkray(.5f, .5f, -1, 0, 0, 1, 0x1.000002p1f, inf), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "A10 tfar=0, box ahead", mkray(.5f, .5f, -1, 0, 0, 1, 0, 0), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "A10 tfar=0, origin inside", mkray(.5f, .5f, .5f, 0, 0, 1, 0, 0), U0, U1, 1, 0, true);
    n = add_hand(h, n, "A11 inactive interval", mkray(.5f, .5f, .5f, 0, 0, 1, inf, -inf), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "A11 tnear=-0", mkray(.5f, .5f, -1, 0, 0, 1, -0.0f, inf), U0, U1, 1, 1, true);
    n = add_hand(h, n, "A11 tnear=-inf, origin behind", mkray(.5f, .5f, 3, 0, 0, 1, -inf, inf), U0, U1, 1, -3, true);
    /* origin on a face */
    n = add_hand(h, n, "origin on face, outward: touch at 0", mkray(1, .5f, .5f, 1, 0, 0, 0, inf), U0, U1, 1, 0, true);
    n = add_hand(h, n, "origin on face, inward", mkray(1, .5f, .5f, -1, .25f, 0, 0, inf), U0, U1, 1, 0, true);
    n = add_hand(h, n, "origin on face, outward, tnear=.5", mkray(1, .5f, .5f, 1, 0, 0, .5f, inf), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "origin on edge, outward oblique", mkray(1, 1, .5f, 1, 1, 0, 0, inf), U0, U1, 1, 0, true);
    /* grazing a face plane */
    n = add_hand(h, n, "in face plane y=1", mkray(-1, 1, .5f, 1, 0, 0, 0, inf), U0, U1, 1, 1, true);
    n = add_hand(h, n, "leaving face plane y=1 upward", mkray(-1, 1, .5f, 1, 1e-8f, 0, 0, inf), U0, U1, 0, NAN, true);
    n = add_hand(h, n, "entering through edge", mkray(-1, 2, .5f, 1, -1, 0, 0, inf), U0, U1, 1, 1, true);
    /* unbounded boxes */
    {
        /* the y slab is [0, 1] and the origin below it with d.y = -0:
         * both y distances are -inf, and with tnear = -inf and x unbounded
         * nothing else raises the entry above them */
        const float rlo[3] = {-inf, 0, 0}, rhi[3] = {inf, 1, 1};
        n = add_hand(h, n, "tnear=-inf, d.y=-0, origin below the y slab, x unbounded",
                     mkray(0, -1, .5f, 1, -0.0f, 0, -inf, inf), rlo, rhi, 0, NAN, true);
        n = add_hand(h, n, "tnear=-inf, d.y=+0, origin below the y slab, x unbounded",
                     mkray(0, -1, .5f, 1, 0.0f, 0, -inf, inf), rlo, rhi, 0, NAN, true);
        /* with +0 the y distances are both +inf: an "entry at infinity" */
        n = add_hand(h, n, "d.y=+0, origin below the y slab, x unbounded",
                     mkray(0, -1, .5f, 1, 0.0f, 0, 0, inf), rlo, rhi, 0, NAN, true);
        const float lo[3] = {-inf, -inf, -inf}, hi[3] = {inf, inf, inf};
        n = add_hand(h, n, "infinite box", mkray(3, -4, 5, .3f, .2f, -1, 0, inf), lo, hi, 1, 0, true);
        n = add_hand(h, n, "infinite box, axis ray", mkray(3, -4, 5, 0, 0, -1, 2, 7), lo, hi, 1, 2, true);
        const float lo2[3] = {0, 0, 0}, hi2[3] = {inf, inf, inf};
        n = add_hand(h, n, "octant box, ray away", mkray(-1, 1, 1, -1, 0, 0, 0, inf), lo2, hi2, 0, NAN, true);
        n = add_hand(h, n, "octant box, ray in", mkray(-1, 1, 1, 1, 0, 0, 0, inf), lo2, hi2, 1, 1, true);
    }
    /* A12 large translations: rays through interior points */
    {
        static const float T[3] = {1e3f, 1e5f, 1e7f};
        for (int i = 0; i < 3; i++) {
            const float lo[3] = {T[i], T[i], T[i]};
            const float hi[3] = {T[i] + 1, T[i] + 1, T[i] + 1};
            float p[3] = {T[i] + .25f, T[i] + .5f, T[i] + .75f}, d[3] = {.3f, -.5f, .8f};
            ref_ray r = mkray(p[0] - 100 * d[0], p[1] - 100 * d[1], p[2] - 100 * d[2], d[0], d[1], d[2], 0, inf);
            snprintf(name, sizeof name, "A12 box at %g", (double)T[i]);
            n = add_hand(h, n, name, r, lo, hi, 1, NAN, false);
        }
    }
    /* A13 huge origin */
    {
        n = add_hand(h, n, "A13 o.x=1e20", mkray(1e20f, .5f, .5f, -1, 0, 0, 0, inf), U0, U1, 1, NAN, false);
    }
    /* A14 tiny boxes and tiny direction components */
    {
        const float lo[3] = {0, 0, 0}, hi[3] = {1e-20f, 1e-20f, 1e-20f};
        n = add_hand(h, n, "A14 tiny box", mkray(5e-21f, 5e-21f, -1, 0, 0, 1, 0, inf), lo, hi, 1, 1, true);
        n = add_hand(h, n, "A14 d.x=1e-30", mkray(5e-21f, 5e-21f, -1, 1e-30f, 0, 1, 0, inf), lo, hi, 1, 1, false);
        n = add_hand(h, n, "A14 d.x=1e-40 (denormal)", mkray(5e-21f, 5e-21f, -1, 1e-40f, 0, 1, 0, inf), lo, hi, 1, 1, false);
    }
    return n;
}

/* Lane layouts a hand case is placed in: (rays, position of the hand ray,
 * boxes, position of the hand box). Sizes are n mod W in {1, W-1} for
 * W = 4, 8, 16 and the single-element case. */
static const size_t hand_layout[][4] = {
    {1, 0, 1, 0}, {3, 2, 5, 4}, {5, 0, 7, 6}, {7, 6, 9, 0}, {9, 8, 3, 1},
    {15, 7, 17, 16}, {17, 16, 15, 14}, {33, 32, 31, 0}, {31, 0, 33, 32},
};

/* ---- the family ---- */

enum {
    V_PACKET,      /* box_packet, rays by position */
    V_PACKET_IDX,  /* box_packet through an index array */
    V_PART,        /* box_partition, out != idx */
    V_PART_INPL,   /* box_partition, out == idx */
    V_PART_NOIDX,  /* box_partition, rays by position */
    V_WIDE,        /* box_wide */
    V_PACKET_FAST, /* box_packet on rays prepared with fast reciprocals */
    V_COUNT
};
static const char *const vname[V_COUNT] = {
    "box_packet", "box_packet(idx)", "box_partition(idx)", "box_partition(in place)",
    "box_partition(no idx)", "box_wide", "box_packet(fast 1/d)",
};

typedef struct {
    bx_set s;
    bx_hand hand[NH_MAX];
    int nhand;
    lanes_rays R, Rfast;
    lanes_boxes B;
    lanes_box *aos;
    uint32_t *idx; /* per block, an index array over its rays (global indices) */
    size_t *idx_at, *idx_n;
} bx_world;

static void build(tk_ctx *c, bx_world *w)
{
    tk_rng g;
    tk_seed(&g, c->seed ^ 0xb0c5);
    bx_set *s = &w->s;
    memset(s, 0, sizeof *s);
    w->nhand = hand_cases(w->hand);
    size_t n_hand_blocks = 0;
    for (int h = 0; h < w->nhand; h++) {
        for (size_t l = 0; l < sizeof hand_layout / sizeof hand_layout[0]; l++) {
            bx_frame f = {1.0, {0, 0, 0}};
            bx_block *b = bx_new_block(s, hand_layout[l][0], hand_layout[l][2]);
            fill_block(&g, s, b, &f);
            s->raw[b->r0 + hand_layout[l][1]] = w->hand[h].r;
            memcpy(s->lo[b->p0 + hand_layout[l][3]], w->hand[h].lo, sizeof(float[3]));
            memcpy(s->hi[b->p0 + hand_layout[l][3]], w->hand[h].hi, sizeof(float[3]));
            n_hand_blocks++;
        }
    }
    size_t hand_pairs = s->npairs;
    while (s->npairs < c->target + hand_pairs) {
        bx_frame f;
        random_frame(&g, &f);
        bx_block *b = bx_new_block(s, block_size(&g), block_size(&g) / 2 + 1);
        fill_block(&g, s, b, &f);
    }

    /* the references */
    s->ref_hit = malloc(s->npairs);
    s->margin = malloc(s->npairs * sizeof(float));
    s->ref_te = malloc(s->npairs * sizeof(double));
    s->hand = malloc(s->npairs * sizeof(int16_t));
    s->flags = malloc(s->npairs);
    if (!s->ref_hit || !s->margin || !s->ref_te || !s->hand || !s->flags) abort();
    for (size_t k = 0; k < s->nblocks; k++) {
        const bx_block *b = &s->blocks[k];
        for (size_t i = 0; i < b->nr; i++)
            for (size_t j = 0; j < b->np; j++) {
                size_t p = b->pair0 + i * b->np + j;
                ref_ray pr = tk_prepared(&s->raw[b->r0 + i]);
                ref_box_result rr = ref_box(&pr, s->lo[b->p0 + j], s->hi[b->p0 + j]);
                s->ref_hit[p] = rr.hit;
                s->margin[p] = (float)rr.margin;
                s->ref_te[p] = rr.tentry;
                s->hand[p] = -1;
                bool tg = s->box_special[b->p0 + j] ||
                          (s->targeted[b->r0 + i] && s->target[b->r0 + i] == (int32_t)j);
                s->flags[p] = tg ? PF_TARGETED : 0;
            }
    }
    /* hand pairs: the reference must say what the case says */
    tk_group g_ref;
    tk_begin(&g_ref, c, "box reference self-check on %d hand-written cases", w->nhand);
    size_t nl = sizeof hand_layout / sizeof hand_layout[0];
    for (int h = 0; h < w->nhand; h++) {
        for (size_t l = 0; l < nl; l++) {
            const bx_block *b = &s->blocks[(size_t)h * nl + l];
            size_t p = b->pair0 + hand_layout[l][1] * b->np + hand_layout[l][3];
            s->hand[p] = (int16_t)h;
            s->flags[p] = PF_TARGETED | (w->hand[h].hard ? PF_HARD : 0);
            if (l) continue;
            if (s->ref_hit[p] != w->hand[h].hit)
                tk_fail(&g_ref, "%s: reference says %s", w->hand[h].name, s->ref_hit[p] ? "hit" : "miss");
            else if (w->hand[h].hit && !isnan(w->hand[h].te) && s->ref_te[p] != w->hand[h].te)
                tk_fail(&g_ref, "%s: reference tentry %a, expected %a", w->hand[h].name,
                        s->ref_te[p], w->hand[h].te);
        }
    }
    tk_end(&g_ref, NULL);

    /* SoA arrays, prepared; the lanes between blocks get garbage after set-up */
    if (!lanes_rays_alloc(&w->R, s->nrays) || !lanes_rays_alloc(&w->Rfast, s->nrays) ||
        !lanes_boxes_alloc(&w->B, s->nboxes))
        abort();
    for (size_t i = 0; i < s->nrays; i++) tk_put_ray(&w->R, i, &s->raw[i]);
    /* fast reciprocals from one set, so that every set gets the same input */
    const lanes_kernels *k0 = c->isa[0];
    for (size_t i = 0; i < s->nrays; i++) {
        const ref_ray *r = &s->raw[i];
        w->Rfast.ox[i] = r->o[0], w->Rfast.oy[i] = r->o[1], w->Rfast.oz[i] = r->o[2];
        w->Rfast.dx[i] = r->d[0], w->Rfast.dy[i] = r->d[1], w->Rfast.dz[i] = r->d[2];
        w->Rfast.tnear[i] = r->tnear, w->Rfast.tfar[i] = r->tfar;
    }
    k0->rays_prepare(&w->Rfast, LANES_RCP_FAST);
    for (size_t i = 0; i < s->nrays; i++)
        if (s->ray_gap[i]) tk_garbage_ray(&w->R, i, (unsigned)i), tk_garbage_ray(&w->Rfast, i, (unsigned)i);
    w->aos = malloc(s->nboxes * sizeof *w->aos);
    if (!w->aos) abort();
    for (size_t i = 0; i < s->nboxes; i++) {
        if (s->box_gap[i]) {
            tk_garbage_box(&w->B, i, (unsigned)i);
            continue;
        }
        w->B.minx[i] = s->lo[i][0], w->B.miny[i] = s->lo[i][1], w->B.minz[i] = s->lo[i][2];
        w->B.maxx[i] = s->hi[i][0], w->B.maxy[i] = s->hi[i][1], w->B.maxz[i] = s->hi[i][2];
        memcpy(w->aos[i].min, s->lo[i], sizeof(float[3]));
        memcpy(w->aos[i].max, s->hi[i], sizeof(float[3]));
    }
    /* index arrays: a shuffle of the block's rays, for a quarter of the
     * blocks a shuffled strict subset */
    w->idx = malloc(s->nrays * sizeof *w->idx);
    w->idx_at = malloc(s->nblocks * sizeof(size_t));
    w->idx_n = malloc(s->nblocks * sizeof(size_t));
    if (!w->idx || !w->idx_at || !w->idx_n) abort();
    size_t at = 0;
    for (size_t k = 0; k < s->nblocks; k++) {
        const bx_block *b = &s->blocks[k];
        uint32_t *ix = w->idx + at;
        for (size_t i = 0; i < b->nr; i++) ix[i] = (uint32_t)(b->r0 + i);
        for (size_t i = b->nr; i > 1; i--) {
            size_t j = tk_below(&g, (uint32_t)i);
            uint32_t t = ix[i - 1];
            ix[i - 1] = ix[j], ix[j] = t;
        }
        size_t n = b->nr;
        if (k >= n_hand_blocks && n > 2 && tk_chance(&g, 0.25)) n = 1 + tk_below(&g, (uint32_t)(n - 1));
        w->idx_at[k] = at, w->idx_n[k] = n;
        at += b->nr;
    }
    printf("  box cases: %zu pairs in %zu blocks (%d hand-written cases x %zu lane layouts), "
           "%zu rays, %zu boxes\n", s->npairs, s->nblocks, w->nhand, nl, s->nrays, s->nboxes);
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

/* Per-call checks of what a kernel wrote: hit words past n, entries for
 * misses and past n. Returns the number of problems (and reports them). */
static int check_words(tk_group *g, const uint32_t *w, size_t n, uint32_t sent, const char *what)
{
    size_t nw = lanes_mask_words(n);
    int bad = 0;
    for (size_t i = nw; i < nw + 2; i++)
        if (w[i] != sent) tk_fail(g, "%s: hit word %zu past n=%zu written (0x%08x)", what, i, n, w[i]), bad++;
    if (n % 32) {
        uint32_t past = ~((1u << (n % 32)) - 1u);
        if (w[nw - 1] & past & ~sent)
            tk_fail(g, "%s: hit bits past n=%zu set (word 0x%08x)", what, n, w[nw - 1]), bad++;
    }
    return bad;
}

static size_t popcount_n(const uint32_t *w, size_t n)
{
    size_t c = 0;
    for (size_t i = 0; i < n; i++) c += lanes_mask_get(w, i);
    return c;
}

typedef struct {
    uint8_t *hit; /* per pair: 0, 1, or 0xff when the variant did not test it */
    float *te;
} bx_res;

static void res_alloc(bx_res *r, size_t n)
{
    r->hit = malloc(n);
    r->te = malloc(n * sizeof(float));
    if (!r->hit || !r->te) abort();
}

static void describe(const bx_world *w, size_t blk, size_t ri, size_t pj, char *buf, size_t size)
{
    const bx_set *s = &w->s;
    const bx_block *b = &s->blocks[blk];
    char rb[200], lo[96], hi[96];
    tk_fmt_ray(rb, sizeof rb, &s->raw[b->r0 + ri]);
    tk_fmt3(lo, sizeof lo, s->lo[b->p0 + pj]);
    tk_fmt3(hi, sizeof hi, s->hi[b->p0 + pj]);
    size_t p = b->pair0 + ri * b->np + pj;
    snprintf(buf, size, "%s%s%sray %s box lo=%s hi=%s (block %zu ray %zu/%zu box %zu/%zu)",
             s->hand[p] >= 0 ? "[" : "", s->hand[p] >= 0 ? w->hand[s->hand[p]].name : "",
             s->hand[p] >= 0 ? "] " : "", rb, lo, hi, blk, ri, b->nr, pj, b->np);
}

/* Runs one variant over every block; fills res and checks the per-call
 * properties (sentinels, return values, stats and stats-independence). */
static void run_variant(const lanes_kernels *k, bx_world *w, int v, bx_res *res,
                        tk_group *g, tk_group *gs, size_t *cases)
{
    const bx_set *s = &w->s;
    const int W = k->lanes;
    uint32_t hw[8], hw2[8], out[BX_MAXN + 40], out2[BX_MAXN + 40];
    float te[BX_MAXN + 40], te2[BX_MAXN + 40];
    memset(res->hit, 0xff, s->npairs);
    *cases = 0;
    size_t call = 0;
    const lanes_rays *RR = v == V_PACKET_FAST ? &w->Rfast : &w->R;
    for (size_t blk = 0; blk < s->nblocks; blk++) {
        const bx_block *b = &s->blocks[blk];
        const uint32_t *ix = w->idx + w->idx_at[blk];
        size_t nix = w->idx_n[blk];
        if (v == V_WIDE) {
            lanes_boxes Bb = boxes_at(&w->B, b->p0, b->np);
            for (size_t i = 0; i < b->nr; i++, call++) {
                lanes_ray ray;
                tk_get_ray(&w->R, b->r0 + i, &ray);
                size_t n = b->np;
                bool want_te = call % 4 != 3;
                uint32_t sent = tk_word_sentinel(call);
                for (int q = 0; q < 8; q++) hw[q] = hw2[q] = sent;
                tk_fill_sentinel(te, n + 40);
                tk_fill_sentinel(te2, n + 40);
                size_t hits = k->box_wide(&ray, &Bb, n, hw, want_te ? te : NULL, NULL);
                lanes_lane_stats st = {0, 0, 0};
                size_t hits2 = k->box_wide(&ray, &Bb, n, hw2, want_te ? te2 : NULL, &st);
                check_words(g, hw, n, sent, "box_wide");
                if (hits != popcount_n(hw, n)) tk_fail(g, "box_wide returned %zu, %zu bits set", hits, popcount_n(hw, n));
                if (hits2 != hits || memcmp(hw, hw2, sizeof hw) || memcmp(te, te2, (n + 40) * sizeof(float)))
                    tk_fail(gs, "box_wide: results with stats differ from stats=NULL (block %zu ray %zu)", blk, i);
                if (!tk_stats_ok(&st, n, W))
                    tk_fail(gs, "box_wide n=%zu: stats ops=%llu slots=%llu active=%llu", n,
                            (unsigned long long)st.vector_ops, (unsigned long long)st.lane_slots,
                            (unsigned long long)st.active_lanes);
                for (size_t j = 0; j < n + 40; j++) {
                    bool h = j < n && lanes_mask_get(hw, j);
                    if (want_te && !h && !tk_is_sentinel(te[j])) {
                        tk_fail(g, "box_wide: tentry[%zu] written for a %s (n=%zu)", j, j < n ? "miss" : "lane past n", n);
                        break;
                    }
                    if (j < n) {
                        size_t p = b->pair0 + i * b->np + j;
                        res->hit[p] = h;
                        res->te[p] = want_te ? te[j] : tk_from_bits(TK_SENTINEL_F);
                    }
                }
                *cases += n;
            }
            continue;
        }
        lanes_rays Rb = rays_at(RR, b->r0, b->nr);
        for (size_t pj = 0; pj < b->np; pj++, call++) {
            const lanes_box *box = &w->aos[b->p0 + pj];
            uint32_t sent = tk_word_sentinel(call);
            lanes_lane_stats st = {0, 0, 0};
            size_t n;
            const uint32_t *idx_used = NULL;
            if (v == V_PACKET || v == V_PACKET_IDX || v == V_PACKET_FAST) {
                const uint32_t *idx = v == V_PACKET_IDX ? ix : NULL;
                const lanes_rays *rr = v == V_PACKET_IDX ? RR : &Rb;
                n = v == V_PACKET_IDX ? nix : b->nr;
                idx_used = idx;
                bool want_te = call % 4 != 3;
                for (int q = 0; q < 8; q++) hw[q] = hw2[q] = sent;
                tk_fill_sentinel(te, n + 40);
                tk_fill_sentinel(te2, n + 40);
                size_t hits = k->box_packet(rr, idx, n, box, hw, want_te ? te : NULL, NULL);
                size_t hits2 = k->box_packet(rr, idx, n, box, hw2, want_te ? te2 : NULL, &st);
                check_words(g, hw, n, sent, vname[v]);
                if (hits != popcount_n(hw, n)) tk_fail(g, "%s returned %zu, %zu bits set", vname[v], hits, popcount_n(hw, n));
                if (hits2 != hits || memcmp(hw, hw2, sizeof hw) || memcmp(te, te2, (n + 40) * sizeof(float)))
                    tk_fail(gs, "%s: results with stats differ from stats=NULL (block %zu box %zu)", vname[v], blk, pj);
                for (size_t j = 0; j < n + 40; j++) {
                    bool h = j < n && lanes_mask_get(hw, j);
                    if (want_te && !h && !tk_is_sentinel(te[j])) {
                        tk_fail(g, "%s: tentry[%zu] written for a %s (n=%zu)", vname[v], j, j < n ? "miss" : "lane past n", n);
                        break;
                    }
                    if (j < n) {
                        size_t ri = idx ? idx[j] - b->r0 : j;
                        size_t p = b->pair0 + ri * b->np + pj;
                        res->hit[p] = h;
                        res->te[p] = want_te ? te[j] : tk_from_bits(TK_SENTINEL_F);
                    }
                }
            } else {
                /* partition: the kept entries, in order, tell the hits */
                uint32_t *o1 = out, *o2 = out2;
                const uint32_t *idx = NULL;
                uint32_t posn[BX_MAXN];
                if (v == V_PART_NOIDX) {
                    n = b->nr;
                    for (size_t j = 0; j < n; j++) posn[j] = (uint32_t)j;
                    idx_used = posn;
                } else {
                    n = nix;
                    idx_used = ix;
                }
                for (size_t j = 0; j < n + 40; j++) out[j] = out2[j] = 0xdeadbeefu;
                if (v == V_PART_INPL) {
                    memcpy(out, ix, n * sizeof *ix);
                    memcpy(out2, ix, n * sizeof *ix);
                    idx = out;
                } else if (v == V_PART) {
                    idx = ix;
                }
                const lanes_rays *rr = v == V_PART_NOIDX ? &Rb : RR;
                size_t kept = k->box_partition(rr, idx, n, box, o1, NULL);
                size_t kept2 = k->box_partition(rr, v == V_PART_INPL ? out2 : idx, n, box, o2, &st);
                if (kept2 != kept || memcmp(o1, o2, (n + 40) * sizeof *o1))
                    tk_fail(gs, "%s: results with stats differ from stats=NULL (block %zu box %zu)", vname[v], blk, pj);
                if (kept > n) {
                    tk_fail(g, "%s returned %zu > n=%zu", vname[v], kept, n);
                    kept = n;
                }
                /* past the kept entries: in place, the rest of idx unchanged;
                 * otherwise nothing written; past n, never anything */
                for (size_t j = kept; j < n + 40; j++) {
                    uint32_t want = (v == V_PART_INPL && j < n) ? ix[j] : 0xdeadbeefu;
                    if (o1[j] != want) {
                        tk_fail(g, "%s: out[%zu] = 0x%x written past the %zu kept entries (n=%zu)",
                                vname[v], j, o1[j], kept, n);
                        break;
                    }
                }
                size_t q = 0;
                for (size_t j = 0; j < n; j++) {
                    bool h = q < kept && o1[q] == idx_used[j];
                    q += h;
                    size_t ri = v == V_PART_NOIDX ? j : idx_used[j] - b->r0;
                    res->hit[b->pair0 + ri * b->np + pj] = h;
                    res->te[b->pair0 + ri * b->np + pj] = tk_from_bits(TK_SENTINEL_F);
                }
                if (q != kept)
                    tk_fail(g, "%s: the %zu kept entries are not an ordered subsequence of idx (block %zu box %zu)",
                            vname[v], kept, blk, pj);
            }
            (void)idx_used;
            if (!tk_stats_ok(&st, n, W))
                tk_fail(gs, "%s n=%zu: stats ops=%llu slots=%llu active=%llu", vname[v], n,
                        (unsigned long long)st.vector_ops, (unsigned long long)st.lane_slots,
                        (unsigned long long)st.active_lanes);
            *cases += n;
        }
    }
}

void tk_family_box(tk_ctx *c, int arg)
{
    (void)arg;
    bx_world w;
    memset(&w, 0, sizeof w);
    if (c->n_isa == 0) return;
    build(c, &w);
    const bx_set *s = &w.s;
    bx_res res, rep[V_COUNT], same[2];
    res_alloc(&res, s->npairs);
    for (int v = 0; v < V_COUNT; v++) rep[v].hit = NULL, rep[v].te = NULL;
    res_alloc(&same[0], s->npairs);
    res_alloc(&same[1], s->npairs);
    const char *rep_name[V_COUNT] = {0};
    /* the tolerance for tentry: slab distances carry three roundings (b - o,
     * 1/d, the product), 5 with the fast reciprocal */
    const double te_tol[2] = {4 * 0x1p-24, 8 * 0x1p-24};

    for (int i = 0; i < c->n_isa; i++) {
        const lanes_kernels *k = c->isa[i];
        tk_group gs;
        tk_begin(&gs, c, "%s box kernels: lane stats and stats-independence", k->name);
        for (int v = 0; v < V_COUNT; v++) {
            tk_group g;
            tk_begin(&g, c, "%s %s vs reference", k->name, vname[v]);
            size_t cases;
            run_variant(k, &w, v, &res, &g, &gs, &cases);
            size_t te_checked = 0, hand_checked = 0;
            double te_worst = 0;
            tk_tally tally;
            memset(&tally, 0, sizeof tally);
            for (size_t blk = 0; blk < s->nblocks; blk++) {
                const bx_block *b = &s->blocks[blk];
                for (size_t ri = 0; ri < b->nr; ri++)
                    for (size_t pj = 0; pj < b->np; pj++) {
                        size_t p = b->pair0 + ri * b->np + pj;
                        if (res.hit[p] == 0xff) continue;
                        /* hand cases are exact only with exact reciprocals */
                        bool hard = (s->flags[p] & PF_HARD) && v != V_PACKET_FAST;
                        double margin = hard ? INFINITY : s->margin[p];
                        hand_checked += s->hand[p] >= 0;
                        bool want = s->ref_hit[p], got = res.hit[p];
                        size_t before = tally.dis;
                        if (tk_tally_case(&tally, s->flags[p] & PF_TARGETED, margin, want, got)) {
                            char buf[600];
                            describe(&w, blk, ri, pj, buf, sizeof buf);
                            tk_fail(&g, "%s: expected %s, got %s (margin %.3g)", buf,
                                    want ? "hit" : "miss", got ? "hit" : "miss", margin);
                            continue;
                        }
                        if (tally.dis != before && c->show_band &&
                                ((s->flags[p] & PF_TARGETED) ? tally.dis_targeted <= 10 : tally.dis - tally.dis_targeted <= 30)) {
                            char buf[600];
                            describe(&w, blk, ri, pj, buf, sizeof buf);
                            tk_band(&g, "%s %s: expected %s (margin %.3g)",
                                    (s->flags[p] & PF_TARGETED) ? "[boundary-built]" : "[generic]", buf,
                                    want ? "hit" : "miss", margin);
                        }
                        if (want && got && !tk_is_sentinel(res.te[p]) && margin >= REF_BAND) {
                            double wt = s->ref_te[p], gt = res.te[p];
                            double tol = te_tol[v == V_PACKET_FAST] * fabs(wt) + REF_TINY;
                            te_checked++;
                            double err = fabs(gt - wt);
                            if (isinf(wt)) err = gt == wt ? 0 : INFINITY;
                            if (fabs(wt) > REF_TINY && isfinite(err)) te_worst = fmax(te_worst, err / fabs(wt));
                            if (!(err <= tol)) {
                                char buf[600];
                                describe(&w, blk, ri, pj, buf, sizeof buf);
                                tk_fail(&g, "%s: tentry %a, reference %a", buf, gt, wt);
                            }
                        }
                    }
            }
            char summary[600];
            tk_tally_close(&g, &tally, summary, sizeof summary);
            if (!c->quick && cases < 1000000)
                tk_fail(&g, "only %zu cases (at least 10^6 wanted)", cases);
            tk_end(&g, "%s; %zu hand; tentry max rel. err %.2g u over %zu (bound %.0f u)", summary,
                   hand_checked, te_worst / 0x1p-24, te_checked,
                   te_tol[v == V_PACKET_FAST] / 0x1p-24);

            /* cross-ISA: box tests use no FMA, so every set must agree bit for bit */
            if (!rep[v].hit) {
                res_alloc(&rep[v], s->npairs);
                memcpy(rep[v].hit, res.hit, s->npairs);
                memcpy(rep[v].te, res.te, s->npairs * sizeof(float));
                rep_name[v] = k->name;
            } else {
                tk_group gx;
                tk_begin(&gx, c, "%s %s == %s bitwise", k->name, vname[v], rep_name[v]);
                for (size_t p = 0; p < s->npairs; p++) {
                    if (res.hit[p] == 0xff) continue;
                    if (res.hit[p] != rep[v].hit[p] ||
                        (res.hit[p] && tk_bits(res.te[p]) != tk_bits(rep[v].te[p])))
                        tk_fail(&gx, "pair %zu: hit %d tentry %a vs %d %a", p, res.hit[p],
                                (double)res.te[p], rep[v].hit[p], (double)rep[v].te[p]);
                }
                tk_end(&gx, NULL);
            }
            /* within a set: the forms agree with each other */
            if (v == V_PACKET) {
                memcpy(same[0].hit, res.hit, s->npairs);
                memcpy(same[0].te, res.te, s->npairs * sizeof(float));
            } else if (v == V_PACKET_IDX) {
                memcpy(same[1].hit, res.hit, s->npairs);
            } else if (v == V_WIDE || v == V_PART || v == V_PART_INPL || v == V_PART_NOIDX) {
                const bx_res *ref = v == V_WIDE || v == V_PART_NOIDX ? &same[0] : &same[1];
                const char *rname = ref == &same[0] ? vname[V_PACKET] : vname[V_PACKET_IDX];
                tk_group gx;
                tk_begin(&gx, c, "%s %s == %s", k->name, vname[v], rname);
                for (size_t p = 0; p < s->npairs; p++) {
                    if (res.hit[p] == 0xff || ref->hit[p] == 0xff) continue;
                    bool te_both = v == V_WIDE && res.hit[p] && !tk_is_sentinel(res.te[p]) &&
                                   !tk_is_sentinel(ref->te[p]);
                    if (res.hit[p] != ref->hit[p] || (te_both && tk_bits(res.te[p]) != tk_bits(ref->te[p])))
                        tk_fail(&gx, "pair %zu: hit %d tentry %a vs %d %a", p, res.hit[p],
                                (double)res.te[p], ref->hit[p], (double)ref->te[p]);
                }
                tk_end(&gx, NULL);
            }
        }
        tk_end(&gs, NULL);
    }
    for (int v = 0; v < V_COUNT; v++) free(rep[v].hit), free(rep[v].te);
    free(res.hit), free(res.te);
    for (int q = 0; q < 2; q++) free(same[q].hit), free(same[q].te);
    lanes_rays_free(&w.R);
    lanes_rays_free(&w.Rfast);
    lanes_boxes_free(&w.B);
    free(w.aos), free(w.idx), free(w.idx_at), free(w.idx_n);
    free(w.s.raw), free(w.s.ray_gap), free(w.s.lo), free(w.s.hi), free(w.s.box_gap), free(w.s.blocks);
    free(w.s.ref_hit), free(w.s.margin), free(w.s.ref_te), free(w.s.hand), free(w.s.flags);
    free(w.s.target), free(w.s.targeted), free(w.s.box_special);
}
