/* Correctness tests of the kernels of every instruction set this CPU runs,
 * against the double-precision references in reference.c and against each
 * other. One family per ctest entry (--family), all sets in one process so
 * that the cross-ISA comparisons see every set's results.
 *
 *   test_kernels [--quick] [--isa a,b,...] [--family f,g,...] [--seed N]
 *                [--cases N] [--print N] [--show-band]
 *
 * Families: meta, prepare, box, tri_moller, tri_watertight, frustum (default:
 * all). --show-band also prints disagreements inside the tolerance band.
 * --quick runs 10^4 cases per kernel instead of 1.2*10^6 (for emulators).
 * The last line is "N passed, N failed, N skipped", counting check groups;
 * the exit status is 1 when any check failed. */
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <stdarg.h>
#include <stdlib.h>
#include <time.h>

#include "name_list.h"
#include "test_kernels_common.h"

/* ---- check groups ---- */

void tk_begin(tk_group *g, tk_ctx *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(g->name, sizeof g->name, fmt, ap);
    va_end(ap);
    g->ctx = c;
    g->fails = 0;
}

void tk_fail(tk_group *g, const char *fmt, ...)
{
    if (g->fails++ < g->ctx->max_print) {
        va_list ap;
        va_start(ap, fmt);
        printf("  FAIL %s: ", g->name);
        vprintf(fmt, ap);
        printf("\n");
        va_end(ap);
    }
}

void tk_band(tk_group *g, const char *fmt, ...)
{
    if (!g->ctx->show_band) return;
    va_list ap;
    va_start(ap, fmt);
    printf("  band %s: ", g->name);
    vprintf(fmt, ap);
    printf("\n");
    va_end(ap);
}

bool tk_end(tk_group *g, const char *fmt, ...)
{
    bool ok = g->fails == 0;
    printf("%s %s", ok ? "PASS" : "FAIL", g->name);
    if (fmt && *fmt) {
        va_list ap;
        va_start(ap, fmt);
        printf(" (");
        vprintf(fmt, ap);
        printf(")");
        va_end(ap);
    }
    if (!ok) printf(" [%ld failures]", g->fails);
    printf("\n");
    if (ok)
        g->ctx->passed++;
    else
        g->ctx->failed++;
    fflush(stdout);
    return ok;
}

void tk_tally_close(tk_group *g, const tk_tally *t, char *buf, size_t size)
{
    size_t generic = t->cases - t->targeted, dis_generic = t->dis - t->dis_targeted;
    double f = t->query_factor > 0 ? t->query_factor : 1.0;
    double gen_bound = REF_BAND_MAX_FRACTION * f, tgt_bound = fmin(REF_BAND_TARGETED_FRACTION * f, 0.5);
    if ((double)dis_generic > gen_bound * (double)generic)
        tk_fail(g, "%zu in-band disagreements on %zu generic cases exceed the bound %.0e", dis_generic,
                generic, gen_bound);
    if ((double)t->dis_targeted > tgt_bound * (double)t->band_targeted)
        tk_fail(g, "%zu in-band disagreements on %zu in-band boundary cases exceed the bound %.2f",
                t->dis_targeted, t->band_targeted, tgt_bound);
    snprintf(buf, size,
             "%zu cases; band (margin < %.0e): generic %zu in band, %zu disagree = %.1e of %zu (bound "
             "%.0e); boundary-built %zu in band, %zu disagree = %.3f of them (bound %.2f); "
             "%zu false hits, %zu false misses",
             t->cases, REF_BAND, t->band - t->band_targeted, dis_generic,
             generic ? (double)dis_generic / (double)generic : 0.0, generic, gen_bound, t->band_targeted,
             t->dis_targeted, t->band_targeted ? (double)t->dis_targeted / (double)t->band_targeted : 0.0,
             tgt_bound, t->false_hits, t->false_misses);
}

void tk_skip(tk_ctx *c, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    printf("SKIP ");
    vprintf(fmt, ap);
    printf("\n");
    va_end(ap);
    c->skipped++;
}

/* ---- rays and padding ---- */

void tk_put_ray(lanes_rays *R, size_t at, const ref_ray *r)
{
    lanes_ray one;
    for (int a = 0; a < 3; a++) one.o[a] = r->o[a], one.d[a] = r->d[a];
    one.tnear = r->tnear, one.tfar = r->tfar;
    lanes_ray_prepare(&one);
    R->ox[at] = one.o[0], R->oy[at] = one.o[1], R->oz[at] = one.o[2];
    R->dx[at] = one.d[0], R->dy[at] = one.d[1], R->dz[at] = one.d[2];
    R->rdx[at] = one.rd[0], R->rdy[at] = one.rd[1], R->rdz[at] = one.rd[2];
    R->tnear[at] = one.tnear, R->tfar[at] = one.tfar;
}

void tk_get_ray(const lanes_rays *R, size_t at, lanes_ray *out)
{
    out->o[0] = R->ox[at], out->o[1] = R->oy[at], out->o[2] = R->oz[at];
    out->d[0] = R->dx[at], out->d[1] = R->dy[at], out->d[2] = R->dz[at];
    out->rd[0] = R->rdx[at], out->rd[1] = R->rdy[at], out->rd[2] = R->rdz[at];
    out->tnear = R->tnear[at], out->tfar = R->tfar[at];
}

void tk_garbage_ray(lanes_rays *R, size_t at, unsigned kind)
{
    float nan = tk_from_bits(0x7fc00bad);
    if (kind & 1) {
        /* all NaN */
        R->ox[at] = R->oy[at] = R->oz[at] = nan;
        R->dx[at] = R->dy[at] = R->dz[at] = nan;
        R->rdx[at] = R->rdy[at] = R->rdz[at] = nan;
        R->tnear[at] = R->tfar[at] = nan;
    } else {
        /* 1/d = 0 makes every slab [0, 0] and the interval is everything:
         * an unmasked lane of this kind hits every box; d = (1, 1, 1) from
         * the origin crosses many triangles */
        R->ox[at] = R->oy[at] = R->oz[at] = 0.0f;
        R->dx[at] = R->dy[at] = R->dz[at] = 1.0f;
        R->rdx[at] = R->rdy[at] = R->rdz[at] = 0.0f;
        R->tnear[at] = -INFINITY, R->tfar[at] = INFINITY;
    }
}

void tk_garbage_box(lanes_boxes *B, size_t at, unsigned kind)
{
    float lo = kind & 1 ? tk_from_bits(0x7fc00bad) : -INFINITY;
    float hi = kind & 1 ? tk_from_bits(0x7fc00bad) : INFINITY;
    B->minx[at] = B->miny[at] = B->minz[at] = lo;
    B->maxx[at] = B->maxy[at] = B->maxz[at] = hi;
}

void tk_garbage_tri(lanes_triangles *T, size_t at, unsigned kind)
{
    if (kind & 1) {
        float nan = tk_from_bits(0x7fc00bad);
        T->v0x[at] = T->v0y[at] = T->v0z[at] = nan;
        T->v1x[at] = T->v1y[at] = T->v1z[at] = nan;
        T->v2x[at] = T->v2y[at] = T->v2z[at] = nan;
    } else {
        /* a huge triangle around the origin in each of the planes x+y+z = c */
        const float s = 1e6f;
        T->v0x[at] = -s, T->v0y[at] = -s, T->v0z[at] = 2 * s;
        T->v1x[at] = 2 * s, T->v1y[at] = -s, T->v1z[at] = -s;
        T->v2x[at] = -s, T->v2y[at] = 2 * s, T->v2z[at] = -s;
    }
}

int tk_fmt3(char *buf, size_t size, const float v[3])
{
    return snprintf(buf, size, "(%a, %a, %a)", (double)v[0], (double)v[1], (double)v[2]);
}

int tk_fmt_ray(char *buf, size_t size, const ref_ray *r)
{
    char o[96], d[96];
    tk_fmt3(o, sizeof o, r->o);
    tk_fmt3(d, sizeof d, r->d);
    return snprintf(buf, size, "o=%s d=%s tnear=%a tfar=%a", o, d, (double)r->tnear,
                    (double)r->tfar);
}

void tk_hist_add(tk_hist *h, uint32_t v)
{
    int b = 0;
    if (v == UINT32_MAX)
        b = 33;
    else
        while (b < 32 && (v >> b) != 0) b++;
    h->bucket[b]++;
    h->count++;
    if (v != UINT32_MAX && v > h->max) h->max = v;
}

void tk_hist_print(const tk_hist *h, const char *what)
{
    printf("  %s: %llu values, max %u;", what, (unsigned long long)h->count, h->max);
    for (int b = 0; b < 34; b++) {
        if (!h->bucket[b]) continue;
        if (b == 0)
            printf(" [0]=%llu", (unsigned long long)h->bucket[b]);
        else if (b == 33)
            printf(" [NaN/inf mismatch]=%llu", (unsigned long long)h->bucket[b]);
        else
            printf(" [%u..%u]=%llu", 1u << (b - 1), b == 32 ? UINT32_MAX : (1u << b) - 1,
                   (unsigned long long)h->bucket[b]);
    }
    printf("\n");
}

/* ---- meta: the tables themselves ---- */

void tk_family_meta(tk_ctx *c, int arg)
{
    (void)arg;
    /* bit 0 SSE4.1, 1 AVX, 2 AVX2, 3 FMA, 4 AVX-512F, as kernels.h defines
     * them: the compiler must have been told exactly what the set's row in
     * simd/kernel_sets.h says it needs. A set built with the wrong flags
     * would pass every other test while running different instructions
     * than its name says. */
    static const uint32_t feature_of_bit[] = {LANES_CPU_SSE41, LANES_CPU_AVX, LANES_CPU_AVX2,
                                              LANES_CPU_FMA, LANES_CPU_AVX512F};
    uint32_t want_features[LANES_ISA_COUNT] = {0};
    for (int isa = 0; isa < LANES_ISA_COUNT; isa++)
        for (unsigned b = 0; b < sizeof feature_of_bit / sizeof feature_of_bit[0]; b++)
            if (lanes_isa_required_features((lanes_isa)isa) & feature_of_bit[b]) want_features[isa] |= 1u << b;
    for (int i = 0; i < c->n_isa; i++) {
        const lanes_kernels *k = c->isa[i];
        tk_group g;
        tk_begin(&g, c, "%s meta: table, lanes, compiled features", k->name);
        lanes_isa isa = k->isa;
        if (lanes_kernels_for(isa) != k) tk_fail(&g, "lanes_kernels_for(%d) is another table", isa);
        if (k->lanes != lanes_isa_lanes(isa))
            tk_fail(&g, "lanes %d, lanes_isa_lanes says %d", k->lanes, lanes_isa_lanes(isa));
        if (strcmp(k->name, lanes_isa_name(isa)) != 0)
            tk_fail(&g, "name %s, lanes_isa_name says %s", k->name, lanes_isa_name(isa));
        if (k->compiled_features != want_features[isa])
            tk_fail(&g, "compiled_features 0x%x, expected 0x%x", k->compiled_features,
                    want_features[isa]);
        /* every member of kernel_list.h filled */
#define META_CHECK_ONE_(member, label)                                                      \
    if (!(member)) tk_fail(&g, "table entry %s is NULL", label);
#define META_CHECK(kind, ret, name, params, args) META_CHECK_##kind(name)
#define META_CHECK_PLAIN(name) META_CHECK_ONE_(k->name, #name)
#define META_CHECK_COUNTED(name) META_CHECK_ONE_(k->name, #name)
#define META_CHECK_COUNTED_VOID(name) META_CHECK_ONE_(k->name, #name)
#define META_CHECK_PER_ALGO(name)                                                            \
    for (int a = 0; a < LANES_TRI_ALGO_COUNT; a++) META_CHECK_ONE_(k->name[a], #name "[algo]")
        LANES_KERNELS(META_CHECK)
        tk_end(&g, "%d lanes, features 0x%x", k->lanes, k->compiled_features);
    }
}

/* ---- rays_prepare ---- */

/* A ray for the set-up test: mostly valid with components over the whole
 * float range (denormal, tiny, huge), plus every kind of invalid input. */
static void prepare_ray(tk_rng *rng, ref_ray *r)
{
    static const float specials[] = {0.0f, -0.0f, 1.0f, -1.0f, 0x1p-149f, -0x1p-149f, 0x1p-127f,
                                     0x1p-126f, 0x1p-61f, 0x1p-60f, -0x1p-60f, 0x1.fffffep-61f,
                                     0x1p126f, 0x1p127f, -0x1.fffffep127f, 3.0f, 1e-30f};
    for (int a = 0; a < 3; a++) {
        r->o[a] = (float)tk_range(rng, -100, 100);
        switch (tk_below(rng, 4)) {
        case 0: r->d[a] = specials[tk_below(rng, sizeof specials / sizeof specials[0])]; break;
        case 1: r->d[a] = (float)(tk_sign(rng) * ldexp(tk_range(rng, 1, 2), (int)tk_below(rng, 277) - 150)); break;
        default: r->d[a] = (float)tk_range(rng, -1, 1); break;
        }
    }
    r->tnear = tk_chance(rng, 0.8) ? 0.0f : (float)tk_range(rng, -10, 10);
    r->tfar = tk_chance(rng, 0.8) ? INFINITY : (float)tk_range(rng, -10, 100);
    if (tk_chance(rng, 0.05)) r->tnear = -INFINITY;
    if (tk_chance(rng, 0.03)) r->tnear = INFINITY;
    if (tk_chance(rng, 0.03)) r->tfar = -INFINITY;
    if (tk_chance(rng, 0.2)) {
        float nan = tk_from_bits(0x7fc00000u | tk_below(rng, 1u << 22));
        if (tk_chance(rng, 0.5)) nan = -nan;
        switch (tk_below(rng, 8)) {
        case 0: r->o[tk_below(rng, 3)] = nan; break;
        case 1: r->d[tk_below(rng, 3)] = nan; break;
        case 2: r->o[tk_below(rng, 3)] = (float)tk_sign(rng) * INFINITY; break;
        case 3: r->d[tk_below(rng, 3)] = (float)tk_sign(rng) * INFINITY; break;
        case 4: r->tnear = nan; break;
        case 5: r->tfar = nan; break;
        default:
            for (int a = 0; a < 3; a++) r->d[a] = tk_chance(rng, 0.5) ? 0.0f : -0.0f;
            break;
        }
    }
}

/* Upper bounds of |rcp_nr(x) - 1/x| / |1/x| per reciprocal group (RCPPS with
 * a plain or a fused Newton step; RCP14 with a fused step), from the
 * estimates' specified error squared plus the step's roundings (see
 * test_simd_ops_set.c); one CPU's table may do better, another worse. */
static const double prepare_fast_bound[3] = {5.0 * 0x1p-24, 4.0 * 0x1p-24, 2.0 * 0x1p-24};

/* rays_load_soa against the one-ray set-up: the same rays bit for bit,
 * from arrays at an odd offset, every count up to a few vectors; the
 * invalid flagged; every ray whose span with the box reaches beyond far2
 * (in double) flagged, and none flagged that falls short by 2^-17; nothing
 * written past n. */
static void load_soa(tk_ctx *c, const ref_ray *raw, size_t n, tk_rng *rng)
{
    float *arrays[8];
    lanes_ray *out = malloc((n + 1) * sizeof *out);
    uint8_t *flags = malloc(n + 1);
    for (int k = 0; k < 8; k++) arrays[k] = malloc((n + 1) * sizeof(float));
    if (!out || !flags) abort();
    for (int k = 0; k < 8; k++)
        if (!arrays[k]) abort();
    for (size_t j = 0; j < n; j++) {
        for (int a = 0; a < 3; a++) arrays[a][j + 1] = raw[j].o[a], arrays[3 + a][j + 1] = raw[j].d[a];
        arrays[6][j + 1] = raw[j].tnear, arrays[7][j + 1] = raw[j].tfar;
    }
    const float *soa[8];
    for (int k = 0; k < 8; k++) soa[k] = arrays[k] + 1; /* unaligned */
    for (int i = 0; i < c->n_isa; i++) {
        const lanes_kernels *k = c->isa[i];
        tk_group g;
        tk_begin(&g, c, "%s rays_load_soa", k->name);
        size_t far_rays = 0, flagged_far = 0;
        for (int round = 0; round < 2 * LANES_MAX_W + 2; round++) {
            /* the last round all rays; the others every count up to 2W */
            bool last = round == 2 * LANES_MAX_W + 1, with_box = last || !(round & 1);
            size_t m = last ? n : (size_t)round;
            const float box[6] = {-10.0f, -20.0f, -5.0f, 10.0f, 5.0f, 30.0f};
            float far2 = (float)tk_range(rng, 400.0, 60000.0);
            memset(out, 0xa5, (n + 1) * sizeof *out);
            memset(flags, 0xa5, n + 1);
            size_t got = k->rays_load_soa(soa, m, with_box ? box : NULL, far2, out, flags);
            size_t counted = 0;
            for (size_t j = 0; j < m; j++) {
                lanes_ray want = {{raw[j].o[0], raw[j].o[1], raw[j].o[2]},
                                  {raw[j].d[0], raw[j].d[1], raw[j].d[2]},
                                  {0, 0, 0},
                                  raw[j].tnear,
                                  raw[j].tfar};
                bool valid = lanes_ray_prepare(&want);
                counted += flags[j] != 0;
                bool same = tk_bits(out[j].tnear) == tk_bits(want.tnear) && tk_bits(out[j].tfar) == tk_bits(want.tfar);
                for (int a = 0; a < 3; a++)
                    same = same && tk_bits(out[j].o[a]) == tk_bits(want.o[a]) && tk_bits(out[j].d[a]) == tk_bits(want.d[a]) &&
                           (!valid || tk_bits(out[j].rd[a]) == tk_bits(want.rd[a]));
                if (!same) tk_fail(&g, "count %zu ray %zu: differs from lanes_ray_prepare", m, j);
                if (!valid) {
                    if (flags[j] != LANES_RAY_INVALID) tk_fail(&g, "count %zu ray %zu: invalid, flags %d", m, j, flags[j]);
                    continue;
                }
                double reach2 = 0.0;
                for (int a = 0; a < 3; a++) {
                    double o = raw[j].o[a], e = fmax(box[3 + a], o) - fmin(box[a], o);
                    reach2 += e * e;
                }
                bool beyond = with_box && reach2 > far2, short_of = !with_box || reach2 < far2 * (1.0 - 0x1p-17);
                far_rays += beyond, flagged_far += flags[j] == LANES_RAY_MAYBE_FAR;
                if ((beyond && flags[j] != LANES_RAY_MAYBE_FAR) || (short_of && flags[j] != 0))
                    tk_fail(&g, "count %zu ray %zu: span^2 %.9g against %.9g, flags %d", m, j, reach2, (double)far2,
                            flags[j]);
            }
            if (got != counted) tk_fail(&g, "count %zu: returned %zu flagged, %zu are", m, got, counted);
            if (flags[m] != 0xa5 || tk_bits(out[m].tnear) != 0xa5a5a5a5u)
                tk_fail(&g, "count %zu: written past the count", m);
        }
        tk_end(&g, "%zu rays beyond the reach, %zu flagged", far_rays, flagged_far);
    }
    for (int k = 0; k < 8; k++) free(arrays[k]);
    free(out), free(flags);
}

void tk_family_prepare(tk_ctx *c, int arg)
{
    (void)arg;
    size_t n = c->target;
    tk_rng rng;
    tk_seed(&rng, c->seed ^ 0x9e9a9e);
    ref_ray *raw = malloc(n * sizeof *raw);
    if (!raw) abort();
    for (size_t i = 0; i < n; i++) prepare_ray(&rng, &raw[i]);

    /* reference results of the one-ray baseline set-up */
    lanes_rays want;
    if (!lanes_rays_alloc(&want, n)) abort();
    for (size_t i = 0; i < n; i++) tk_put_ray(&want, i, &raw[i]);

    lanes_rays R;
    if (!lanes_rays_alloc(&R, n)) abort();
    float *rep[2][3][3] = {{{0}}}; /* [mode][group][axis]: first set of each group */
    float *rep_t[2][3][2] = {{{0}}};

    for (int mode = 0; mode < 2; mode++) {
        for (int i = 0; i < c->n_isa; i++) {
            const lanes_kernels *k = c->isa[i];
            int grp = mode == LANES_RCP_EXACT ? 0 : tk_rcp_group(k->isa);
            tk_group g;
            tk_begin(&g, c, "%s rays_prepare(%s)", k->name, mode ? "fast" : "exact");
            for (size_t j = 0; j < n; j++) {
                R.ox[j] = raw[j].o[0], R.oy[j] = raw[j].o[1], R.oz[j] = raw[j].o[2];
                R.dx[j] = raw[j].d[0], R.dy[j] = raw[j].d[1], R.dz[j] = raw[j].d[2];
                R.tnear[j] = raw[j].tnear, R.tfar[j] = raw[j].tfar;
                R.rdx[j] = R.rdy[j] = R.rdz[j] = tk_from_bits(TK_SENTINEL_F);
            }
            R.count = n;
            k->rays_prepare(&R, (lanes_rcp_mode)mode);
            double worst = 0.0;
            size_t flushed = 0;
            for (size_t j = 0; j < n; j++) {
                const ref_ray *r = &raw[j];
                bool valid = ref_ray_valid(r);
                const float *rd[3] = {&R.rdx[j], &R.rdy[j], &R.rdz[j]};
                const float o[3] = {R.ox[j], R.oy[j], R.oz[j]}, d[3] = {R.dx[j], R.dy[j], R.dz[j]};
                char buf[256];
                for (int a = 0; a < 3; a++) {
                    if (tk_bits(o[a]) != tk_bits(r->o[a]) || tk_bits(d[a]) != tk_bits(r->d[a])) {
                        tk_fmt_ray(buf, sizeof buf, r);
                        tk_fail(&g, "ray %zu %s: o or d changed", j, buf);
                        break;
                    }
                }
                float tn = R.tnear[j], tf = R.tfar[j];
                if (!valid) {
                    if (!(tn == INFINITY && tf == -INFINITY)) {
                        tk_fmt_ray(buf, sizeof buf, r);
                        tk_fail(&g, "ray %zu %s is invalid: expected tnear=inf tfar=-inf, got %a %a",
                                j, buf, (double)tn, (double)tf);
                    }
                    continue;
                }
                /* valid rays keep their interval, with infinite ends made finite */
                ref_ray cl = tk_prepared(r);
                if (tk_bits(tn) != tk_bits(cl.tnear) || tk_bits(tf) != tk_bits(cl.tfar)) {
                    tk_fmt_ray(buf, sizeof buf, r);
                    tk_fail(&g, "ray %zu %s is valid: tnear/tfar are %a %a, expected %a %a", j, buf,
                            (double)tn, (double)tf, (double)cl.tnear, (double)cl.tfar);
                }
                for (int a = 0; a < 3; a++) {
                    float exact = 1.0f / r->d[a];
                    float got = *rd[a];
                    bool ok;
                    if (mode == LANES_RCP_EXACT || fabsf(r->d[a]) < 0x1p-60f) {
                        ok = tk_bits(got) == tk_bits(exact);
                    } else {
                        /* 1/d below FLT_MIN: the estimate may flush to 0 */
                        double e = 1.0 / (double)r->d[a];
                        double err = fabs((double)got - e);
                        /* the hardware estimate flushes results at or below
                         * FLT_MIN to 0 (|d| >= 2^126); the set-up keeps it */
                        bool flush = fabs(e) <= FLT_MIN && got == 0.0f;
                        flushed += flush;
                        ok = flush || err <= prepare_fast_bound[grp] * fabs(e) ||
                             (fabs(e) < FLT_MIN && err <= 0x1p-149);
                        if (!flush && fabs(e) >= FLT_MIN && isfinite(e)) worst = fmax(worst, err / fabs(e));
                        if (isinf(exact)) ok = tk_bits(got) == tk_bits(exact);
                    }
                    if (!ok) {
                        tk_fmt_ray(buf, sizeof buf, r);
                        tk_fail(&g, "ray %zu %s: rd[%d] = %a, expected %a", j, buf, a, (double)got,
                                (double)exact);
                    }
                }
            }
            /* the same inputs give the same outputs within a group */
            if (!rep[mode][grp][0]) {
                for (int a = 0; a < 3; a++) {
                    rep[mode][grp][a] = malloc(n * sizeof(float));
                    if (!rep[mode][grp][a]) abort();
                }
                rep_t[mode][grp][0] = malloc(n * sizeof(float));
                rep_t[mode][grp][1] = malloc(n * sizeof(float));
                if (!rep_t[mode][grp][0] || !rep_t[mode][grp][1]) abort();
                memcpy(rep[mode][grp][0], R.rdx, n * sizeof(float));
                memcpy(rep[mode][grp][1], R.rdy, n * sizeof(float));
                memcpy(rep[mode][grp][2], R.rdz, n * sizeof(float));
                memcpy(rep_t[mode][grp][0], R.tnear, n * sizeof(float));
                memcpy(rep_t[mode][grp][1], R.tfar, n * sizeof(float));
            } else {
                const float *cur[5] = {R.rdx, R.rdy, R.rdz, R.tnear, R.tfar};
                const float *ref[5] = {rep[mode][grp][0], rep[mode][grp][1], rep[mode][grp][2],
                                       rep_t[mode][grp][0], rep_t[mode][grp][1]};
                for (size_t j = 0; j < n; j++)
                    for (int f = 0; f < 5; f++)
                        if (tk_bits(cur[f][j]) != tk_bits(ref[f][j]) && ref_ray_valid(&raw[j])) {
                            tk_fail(&g, "ray %zu field %d: %a differs from the first set of its "
                                        "group (%a)", j, f, (double)cur[f][j], (double)ref[f][j]);
                        }
            }
            /* exact mode equals the baseline one-ray set-up bit for bit */
            if (mode == LANES_RCP_EXACT) {
                for (size_t j = 0; j < n; j++) {
                    if (!ref_ray_valid(&raw[j])) continue;
                    if (tk_bits(R.rdx[j]) != tk_bits(want.rdx[j]) ||
                        tk_bits(R.rdy[j]) != tk_bits(want.rdy[j]) ||
                        tk_bits(R.rdz[j]) != tk_bits(want.rdz[j]))
                        tk_fail(&g, "ray %zu: differs from lanes_ray_prepare", j);
                }
            }
            /* nothing past count is written: short runs into sentinel-filled arrays */
            lanes_rays S;
            if (!lanes_rays_alloc(&S, 48)) abort();
            for (size_t cnt = 0; cnt <= 40; cnt++) {
                float *arrs[] = {S.ox, S.oy, S.oz, S.dx, S.dy, S.dz, S.rdx, S.rdy, S.rdz, S.tnear, S.tfar};
                for (int f = 0; f < 11; f++) tk_fill_sentinel(arrs[f], S.capacity);
                for (size_t j = 0; j < cnt; j++) {
                    const ref_ray *r = &raw[(cnt * 41 + j) % n];
                    S.ox[j] = r->o[0], S.oy[j] = r->o[1], S.oz[j] = r->o[2];
                    S.dx[j] = r->d[0], S.dy[j] = r->d[1], S.dz[j] = r->d[2];
                    S.tnear[j] = r->tnear, S.tfar[j] = r->tfar;
                }
                S.count = cnt;
                k->rays_prepare(&S, (lanes_rcp_mode)mode);
                for (int f = 0; f < 11; f++)
                    for (size_t j = cnt; j < S.capacity; j++)
                        if (!tk_is_sentinel(arrs[f][j])) {
                            tk_fail(&g, "count %zu: array %d element %zu past count was written",
                                    cnt, f, j);
                            break;
                        }
            }
            lanes_rays_free(&S);
            if (mode == LANES_RCP_FAST)
                tk_end(&g, "%zu rays; fast 1/d: max rel. error %.3g u, bound %.2g u, %zu flushed to 0",
                       n, worst / 0x1p-24, prepare_fast_bound[grp] / 0x1p-24, flushed);
            else
                tk_end(&g, "%zu rays", n);
        }
    }
    for (int m = 0; m < 2; m++)
        for (int gi = 0; gi < 3; gi++) {
            for (int a = 0; a < 3; a++) free(rep[m][gi][a]);
            free(rep_t[m][gi][0]);
            free(rep_t[m][gi][1]);
        }
    lanes_rays_free(&R);
    lanes_rays_free(&want);
    load_soa(c, raw, n, &rng);
    free(raw);
}

/* ---- driver ---- */


static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#define TK_FAMILY_NAME_(name, run, arg) " " #name
#define TK_FAMILY_NAMES TK_FAMILIES(TK_FAMILY_NAME_)

static int usage(const char *argv0)
{
    fprintf(stderr,
            "usage: %s [--quick] [--isa a,b,...] [--family f,...] [--seed N] [--cases N] [--print N] [--show-band]\n"
            "  sets: %s\n"
            "  families:%s\n",
            argv0, lanes_isa_all_names(), TK_FAMILY_NAMES);
    return 2;
}

int main(int argc, char **argv)
{
    tk_ctx c;
    memset(&c, 0, sizeof c);
    c.seed = 20240601;
    c.max_print = 10;
    const char *isa_list = NULL, *family_list = NULL;
    size_t cases = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--quick") == 0) {
            c.quick = true;
        } else if (strcmp(a, "--isa") == 0 && v) {
            isa_list = v, i++;
        } else if (strcmp(a, "--family") == 0 && v) {
            family_list = v, i++;
        } else if (strcmp(a, "--seed") == 0 && v) {
            c.seed = strtoull(v, NULL, 0), i++;
        } else if (strcmp(a, "--cases") == 0 && v) {
            cases = (size_t)strtoull(v, NULL, 0), i++;
        } else if (strcmp(a, "--show-band") == 0) {
            c.show_band = true;
        } else if (strcmp(a, "--print") == 0 && v) {
            c.max_print = atoi(v), i++;
        } else {
            return usage(argv[0]);
        }
    }
    if (isa_list) {
        for (const char *p = isa_list; *p;) {
            const char *e = strchr(p, ',');
            size_t l = e ? (size_t)(e - p) : strlen(p);
            char name[32];
            snprintf(name, sizeof name, "%.*s", (int)(l < 31 ? l : 31), p);
            if (lanes_isa_from_name(name) == LANES_ISA_NONE) {
                fprintf(stderr, "test_kernels: unknown set '%s' (valid: %s)\n", name,
                        lanes_isa_all_names());
                return 2;
            }
            if (!e) break;
            p = e + 1;
        }
    }
    static const struct {
        const char *name;
        void (*run)(tk_ctx *, int);
        int arg;
    } family_table[] = {
#define FAMILY(name, run, arg) {#name, run, arg},
        TK_FAMILIES(FAMILY)
#undef FAMILY
    };
    const int n_families = (int)(sizeof family_table / sizeof family_table[0]);
    const char *families[sizeof family_table / sizeof family_table[0]];
    for (int f = 0; f < n_families; f++) families[f] = family_table[f].name;
    if (family_list) {
        for (const char *p = family_list; *p;) {
            const char *e = strchr(p, ',');
            size_t l = e ? (size_t)(e - p) : strlen(p);
            bool known = false;
            for (int f = 0; f < n_families; f++)
                known = known || (strlen(families[f]) == l && strncmp(families[f], p, l) == 0);
            if (!known) {
                fprintf(stderr, "test_kernels: unknown family '%.*s'\n", (int)l, p);
                return usage(argv[0]);
            }
            if (!e) break;
            p = e + 1;
        }
    }
    c.target = cases ? cases : c.quick ? 10000 : 1200000;

    const lanes_cpu_features *cpu = lanes_cpu();
    printf("test_kernels: CPU %s (%s); %zu cases per kernel%s; seed %llu\n", cpu->brand,
           cpu->vendor, c.target, c.quick ? " (--quick)" : "", (unsigned long long)c.seed);
    const char *skip_reason[LANES_ISA_COUNT] = {0};
    char reasons[LANES_ISA_COUNT][160];
    for (int i = 0; i < LANES_ISA_COUNT; i++) {
        lanes_isa isa = (lanes_isa)i;
        const char *name = lanes_isa_name(isa);
        if (!harness_in_list(isa_list, name)) {
            snprintf(reasons[i], sizeof reasons[i], "not selected by --isa");
        } else if (!lanes_isa_compiled(isa)) {
            snprintf(reasons[i], sizeof reasons[i], "not compiled into this build (LANES_ISAS)");
        } else if (!lanes_isa_cpu_can_run(isa)) {
            uint32_t missing = lanes_isa_required_features(isa) & ~cpu->bits;
            char list[120] = "";
            lanes_cpu_feature_list(missing, list, sizeof list);
            snprintf(reasons[i], sizeof reasons[i], "this CPU (or OS) lacks %s", list);
        } else {
            c.isa[c.n_isa++] = lanes_kernels_for(isa);
            continue;
        }
        skip_reason[i] = reasons[i];
    }

    double t_start = now();
    for (int f = 0; f < n_families; f++) {
        if (!harness_in_list(family_list, families[f])) continue;
        printf("== family %s\n", families[f]);
        for (int i = 0; i < LANES_ISA_COUNT; i++)
            if (skip_reason[i]) tk_skip(&c, "%s: %s (family %s)", lanes_isa_name((lanes_isa)i),
                                        skip_reason[i], families[f]);
        double t0 = now();
        family_table[f].run(&c, family_table[f].arg);
        printf("== family %s: %.2f s\n", families[f], now() - t0);
    }
    printf("total %.2f s\n", now() - t_start);
    printf("%ld passed, %ld failed, %ld skipped\n", c.passed, c.failed, c.skipped);
    return c.failed ? 1 : 0;
}
