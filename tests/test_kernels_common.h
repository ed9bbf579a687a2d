/* Shared pieces of test_kernels: the random generator, the run context,
 * check groups with failure reporting, sentinels, and the ISA groupings the
 * cross-ISA comparisons use. Baseline code: no intrinsics. */
#ifndef LANES_TESTS_TEST_KERNELS_COMMON_H
#define LANES_TESTS_TEST_KERNELS_COMMON_H

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "reference.h"
#include "trace/kernels.h"

/* ---- random numbers: xoshiro256** seeded through splitmix64 ---- */
typedef struct tk_rng {
    uint64_t s[4];
} tk_rng;

static inline uint64_t tk_rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
static inline uint64_t tk_next(tk_rng *r)
{
    uint64_t *s = r->s;
    uint64_t result = tk_rotl(s[1] * 5, 7) * 9, t = s[1] << 17;
    s[2] ^= s[0], s[3] ^= s[1], s[1] ^= s[2], s[0] ^= s[3], s[2] ^= t, s[3] = tk_rotl(s[3], 45);
    return result;
}
static inline void tk_seed(tk_rng *r, uint64_t seed)
{
    for (int i = 0; i < 4; i++) {
        uint64_t z = (seed += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        r->s[i] = z ^ (z >> 31);
    }
}
/* uniform in [0, 1) */
static inline double tk_unit(tk_rng *r) { return (double)(tk_next(r) >> 11) * 0x1p-53; }
static inline double tk_range(tk_rng *r, double lo, double hi) { return lo + (hi - lo) * tk_unit(r); }
static inline uint32_t tk_below(tk_rng *r, uint32_t n) { return (uint32_t)((tk_next(r) >> 32) * n >> 32); }
static inline bool tk_chance(tk_rng *r, double p) { return tk_unit(r) < p; }
static inline double tk_sign(tk_rng *r) { return (tk_next(r) >> 63) ? -1.0 : 1.0; }

/* x moved by k representable floats (toward +inf for k > 0). */
static inline float tk_ulps(float x, int k)
{
    for (; k > 0; k--) x = nextafterf(x, INFINITY);
    for (; k < 0; k++) x = nextafterf(x, -INFINITY);
    return x;
}

static inline uint32_t tk_bits(float x)
{
    uint32_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}
static inline float tk_from_bits(uint32_t u)
{
    float x;
    memcpy(&x, &u, sizeof x);
    return x;
}

/* ---- sentinels: values no kernel produces, to see what it wrote ---- */
#define TK_SENTINEL_F 0x7fc5a5a5u /* a quiet NaN with a payload */
static inline void tk_fill_sentinel(float *p, size_t n)
{
    for (size_t i = 0; i < n; i++) p[i] = tk_from_bits(TK_SENTINEL_F);
}
static inline bool tk_is_sentinel(float x) { return tk_bits(x) == TK_SENTINEL_F; }
/* Hit words get one of two complementary patterns (per call), so that over
 * many calls every bit position past n is watched for a stray 1. */
static inline uint32_t tk_word_sentinel(size_t call) { return call & 1 ? 0x5a5a5a5au : 0xa5a5a5a5u; }

/* ---- run context and check groups ---- */
typedef struct tk_ctx {
    bool quick;
    uint64_t seed;
    size_t target;     /* ray/primitive pairs per kernel */
    int n_isa;
    const lanes_kernels *isa[LANES_ISA_COUNT]; /* the sets that run, in enum order */
    long passed, failed, skipped;
    int max_print;     /* failure lines printed per group */
    bool show_band;    /* print in-band disagreements too */
} tk_ctx;

typedef struct tk_group {
    tk_ctx *ctx;
    char name[160];
    long fails;
} tk_group;

void tk_begin(tk_group *g, tk_ctx *c, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
/* One failure: counted always, printed for the first ctx->max_print. */
void tk_fail(tk_group *g, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Closes the group: one passed or failed check, with an optional summary. */
bool tk_end(tk_group *g, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* An in-band disagreement: printed only with --show-band. */
void tk_band(tk_group *g, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* Counts one skipped group and says why. */
void tk_skip(tk_ctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* Sets with and without FMA (as their rows in simd/kernel_sets.h say):
 * Möller–Trumbore's results are bitwise equal within a group, and differ by
 * rounding between groups. */
static inline int tk_fma_group(lanes_isa isa)
{
    return (lanes_isa_required_features(isa) & LANES_CPU_FMA) != 0;
}
/* Sets with bitwise equal fast reciprocals: RCPPS with a plain Newton step,
 * RCPPS with a fused one, and AVX-512's RCP14. */
static inline int tk_rcp_group(lanes_isa isa)
{
    if (lanes_isa_required_features(isa) & LANES_CPU_AVX512F) return 2;
    return tk_fma_group(isa);
}

/* The ray the kernels see after lanes_rays_prepare(), as far as the
 * reference cares: infinite ends clamped to -FLT_MAX and FLT_MAX (the
 * documented set-up; it keeps a slab a d = ±0 ray never enters from
 * overlapping [tnear, tfar] at infinity). */
static inline ref_ray tk_prepared(const ref_ray *r)
{
    ref_ray c = *r;
    if (c.tnear < -FLT_MAX) c.tnear = -FLT_MAX;
    if (c.tfar > FLT_MAX) c.tfar = FLT_MAX;
    return c;
}

/* Ray arrays: copies ref rays into a lanes_rays at position `at` and
 * prepares them with the baseline scalar set-up (exact reciprocals), which
 * is what every ISA's kernels then receive. */
void tk_put_ray(lanes_rays *R, size_t at, const ref_ray *r);
void tk_get_ray(const lanes_rays *R, size_t at, lanes_ray *out);
/* Padding lanes between blocks: values that hit everything (or are NaN) if a
 * kernel forgets to mask them. `kind` alternates the flavours. */
void tk_garbage_ray(lanes_rays *R, size_t at, unsigned kind);
void tk_garbage_box(lanes_boxes *B, size_t at, unsigned kind);
void tk_garbage_tri(lanes_triangles *T, size_t at, unsigned kind);

/* Lane accounting expected from a kernel whose main loop ran over n
 * elements at width w. */
static inline bool tk_stats_ok(const lanes_lane_stats *s, size_t n, int w)
{
    uint64_t ops = (n + (size_t)w - 1) / (size_t)w;
    return s->vector_ops == ops && s->lane_slots == ops * (uint64_t)w && s->active_lanes == n;
}

/* Pretty-printing of a ray for failure messages (hex floats: exact). */
int tk_fmt_ray(char *buf, size_t size, const ref_ray *r);
int tk_fmt3(char *buf, size_t size, const float v[3]);

/* Histogram of non-negative integer distances in power-of-two buckets. */
typedef struct tk_hist {
    uint64_t bucket[34]; /* 0, 1, 2-3, 4-7, ..., >= 2^31, NaN-vs-number */
    uint64_t count;
    uint32_t max;
} tk_hist;
void tk_hist_add(tk_hist *h, uint32_t v);
void tk_hist_print(const tk_hist *h, const char *what);

/* Agreement of one kernel with a reference, with the tolerance band:
 * disagreements outside it are failures (reported by the caller), inside
 * it they are counted here and bounded by tk_tally_close(). */
typedef struct tk_tally {
    size_t cases, targeted;           /* all cases; those built at a boundary */
    size_t band, band_targeted;       /* cases in the band */
    size_t dis, dis_targeted;         /* in-band disagreements */
    size_t false_hits, false_misses;  /* their direction */
    /* Queries over several primitives (closest hit, any hit) disagree when
     * either of two decisions flips or two distances nearly tie: their
     * bounds are this many times the per-pair ones (0 means 1). */
    double query_factor;
} tk_tally;
#define TK_QUERY_FACTOR 4.0
/* Returns true when want != got outside the band (a failure). A query
 * over several primitives (closest hit, any hit) counts as `weight` cases
 * (its pairs) but as one in-band case or disagreement. */
static inline bool tk_tally_weighted(tk_tally *t, bool targeted, double margin, bool want, bool got,
                                     size_t weight)
{
    bool band = margin < REF_BAND;
    t->cases += weight;
    t->targeted += targeted ? weight : 0;
    t->band += band;
    t->band_targeted += band && targeted;
    if (want == got) return false;
    if (!band) return true;
    t->dis++;
    t->dis_targeted += targeted;
    t->false_hits += got;
    t->false_misses += !got;
    return false;
}
static inline bool tk_tally_case(tk_tally *t, bool targeted, double margin, bool want, bool got)
{
    return tk_tally_weighted(t, targeted, margin, want, got, 1);
}
/* Checks the bounds on in-band disagreements (a failure of g if exceeded)
 * and writes a summary into buf. */
void tk_tally_close(tk_group *g, const tk_tally *t, char *buf, size_t size);

/* The families (one ctest entry each). */
void tk_family_meta(tk_ctx *c, int arg);
void tk_family_prepare(tk_ctx *c, int arg);
void tk_family_box(tk_ctx *c, int arg);
void tk_family_tri(tk_ctx *c, int algo);
void tk_family_frustum(tk_ctx *c, int arg);

/* The test families, one ctest entry each (tests/kernels.cmake reads the
 * names from these rows): X(name, function, argument). */
#define TK_FAMILIES(X)                                                                     \
    X(meta, tk_family_meta, 0)                                                             \
    X(prepare, tk_family_prepare, 0)                                                       \
    X(box, tk_family_box, 0)                                                               \
    X(tri_moller, tk_family_tri, LANES_TRI_MOLLER)                                         \
    X(tri_watertight, tk_family_tri, LANES_TRI_WATERTIGHT)                                 \
    X(frustum, tk_family_frustum, 0)

#endif
