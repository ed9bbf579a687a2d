/* The SIMD layer of one kernel set, operation by operation, against plain
 * scalar C (the semantics are spelled out in simd/vec1_scalar.h). Compiled
 * once per set with that set's flags and LANES_KSET_<SET>, like the kernels;
 * everything here is static except the suffixed entry point, so no helper
 * compiled with AVX-512 flags can be merged into another set's code.
 *
 * Expected values are computed in C in this same file, which is compiled
 * with -ffp-contract=off: a * b + c here is two roundings on every set. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "simd/isa.h"
#include "simd/simd.h"
#include "test_simd_ops.h"

#define W LANES_W
#define NMASKS_16 4096

/* What the set's row in simd/kernel_sets.h says it needs (not the
 * compiler's flags, which are checked against it): a fused fmadd where it
 * needs FMA, AVX-512's VRCP14PS where it needs AVX-512F. */
#define EXPECT_FMA ((lanes_isa_required_features(LANES_THIS_ISA) & LANES_CPU_FMA) != 0)
#define EXPECT_RCP14 ((lanes_isa_required_features(LANES_THIS_ISA) & LANES_CPU_AVX512F) != 0)

static inline uint32_t fbits(float x)
{
    uint32_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}
static inline float ffrom(uint32_t u)
{
    float x;
    memcpy(&x, &u, sizeof x);
    return x;
}
static inline bool same(float a, float b) { return fbits(a) == fbits(b) || (a != a && b != b); }

typedef struct {
    uint64_t s;
} rng;
static inline uint64_t next(rng *r)
{
    uint64_t z = (r->s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* Zeros of both signs, denormals, the extremes, infinities, NaNs with
 * payloads and signs, values around 2^24 and 2^31, and ordinary numbers. */
static const uint32_t special_bits[] = {
    0x00000000u, 0x80000000u, 0x3f800000u, 0xbf800000u, 0x3f000000u, 0x40000000u, 0x40400000u,
    0xc0400000u, 0x00800000u, 0x80800000u, 0x00000001u, 0x80000001u, 0x007fffffu, 0x00400000u,
    0x7f7fffffu, 0xff7fffffu, 0x7f800000u, 0xff800000u, 0x7fc00000u, 0xffc00001u, 0x7fc12345u,
    0x1e3ce508u, 0x60ad78ecu, 0x4b800000u, 0x4b800001u, 0x3dcccccdu, 0x4f000000u, 0xcf000000u,
    0x4effffffu, 0x7e800000u, 0x01000000u, 0x3f800001u, 0x3f7fffffu, 0xc2c80000u,
};
#define NSPECIAL (sizeof special_bits / sizeof special_bits[0])

static float rand_float(rng *r)
{
    uint64_t x = next(r);
    switch (x & 7) {
    case 0: return ffrom(special_bits[(x >> 8) % NSPECIAL]);
    case 1: return ffrom((uint32_t)(x >> 32)); /* any bit pattern */
    case 2: return (float)((int32_t)(x >> 40) % 1000); /* small integers */
    default: {
        /* moderate magnitudes, both signs */
        float m = 1.0f + (float)((x >> 20) & 0xffffff) * 0x1p-24f;
        int e = (int)((x >> 8) % 41) - 20;
        return ((x >> 63) ? -1.0f : 1.0f) * ldexpf(m, e);
    }
    }
}

/* A float with no NaN (for the reductions). */
static float rand_number(rng *r)
{
    float f;
    do f = rand_float(r);
    while (f != f);
    return f;
}

static vfloat vload(const float *p) { return vf_loadu(p); }
static void vstore(float *p, vfloat v) { vf_storeu(p, v); }
static vint iload(const int32_t *p) { return vi_loadu(p); }
static void istore(int32_t *p, vint v) { vi_storeu(p, v); }

static uint32_t all_bits(void) { return W == 32 ? 0xffffffffu : (1u << W) - 1u; }

/* Mask patterns to try: every one up to 8 lanes, a sample of 16-lane ones
 * (with the obvious ones included). */
static size_t mask_count(void) { return W <= 8 ? (size_t)1 << W : NMASKS_16; }
static uint32_t mask_pattern(size_t i, rng *r)
{
    if (W <= 8) return (uint32_t)i;
    static const uint32_t fixed[] = {0u, 0xffffu, 1u, 0x8000u, 0x5555u, 0xaaaau, 0x00ffu, 0xff00u, 0x0180u, 0x7ffeu};
    if (i < sizeof fixed / sizeof fixed[0]) return fixed[i];
    if (i < 26) return 1u << (i - 10);
    return (uint32_t)next(r) & 0xffffu;
}

static int popc(uint32_t x) { return __builtin_popcount(x); }

/* ---------------------------------------------------------------- */

static void test_construct(simd_ctx *c, rng *r)
{
    simd_begin(c, "zero/set1/iota/lane");
    float out[W];
    int32_t io[W];
    vstore(out, vf_zero());
    for (int i = 0; i < W; i++)
        if (fbits(out[i]) != 0) simd_fail(c, "vf_zero lane %d = %a", i, (double)out[i]);
    istore(io, vi_zero());
    for (int i = 0; i < W; i++)
        if (io[i] != 0) simd_fail(c, "vi_zero lane %d = %d", i, io[i]);
    istore(io, vi_iota());
    for (int i = 0; i < W; i++)
        if (io[i] != i) simd_fail(c, "vi_iota lane %d = %d", i, io[i]);
    for (int k = 0; k < 2000; k++) {
        float x = rand_float(r);
        int32_t n = (int32_t)next(r);
        vfloat v = vf_set1(x);
        vint vi = vi_set1(n);
        vstore(out, v);
        istore(io, vi);
        for (int i = 0; i < W; i++) {
            if (fbits(out[i]) != fbits(x)) simd_fail(c, "vf_set1(%a) lane %d = %a", (double)x, i, (double)out[i]);
            if (fbits(vf_lane(v, i)) != fbits(x)) simd_fail(c, "vf_lane(set1(%a), %d) = %a", (double)x, i, (double)vf_lane(v, i));
            if (io[i] != n || vi_lane(vi, i) != n) simd_fail(c, "vi_set1(%d) lane %d = %d / %d", n, i, io[i], vi_lane(vi, i));
        }
    }
    /* vf_lane on distinct lanes */
    float in[W];
    for (int i = 0; i < W; i++) in[i] = (float)(i * 3 + 1);
    vfloat v = vload(in);
    for (int i = 0; i < W; i++)
        if (vf_lane(v, i) != in[i]) simd_fail(c, "vf_lane(v, %d) = %g, expected %g", i, (double)vf_lane(v, i), (double)in[i]);
    simd_end(c);
}

static void test_load_store(simd_ctx *c, rng *r)
{
    simd_begin(c, "load/loadu/store/storeu");
    _Alignas(64) float a[W + 64], b[W + 64];
    _Alignas(64) int32_t ia[W + 64], ib[W + 64];
    for (int rep = 0; rep < 200; rep++) {
        for (int i = 0; i < W + 64; i++) a[i] = rand_float(r), ia[i] = (int32_t)next(r);
        /* aligned: every multiple of the vector size inside the buffer */
        for (int at = 0; at + W <= W + 64; at += W) {
            for (int i = 0; i < W + 64; i++) b[i] = ffrom(0x7fcdead0u), ib[i] = 0x5eed;
            vf_store(b + at, vf_load(a + at));
            vi_store(ib + at, vi_load(ia + at));
            for (int i = 0; i < W + 64; i++) {
                bool inside = i >= at && i < at + W;
                uint32_t want = inside ? fbits(a[i]) : 0x7fcdead0u;
                if (fbits(b[i]) != want) simd_fail(c, "vf_load/vf_store at %d: element %d = 0x%08x, expected 0x%08x", at, i, fbits(b[i]), want);
                int32_t iw = inside ? ia[i] : 0x5eed;
                if (ib[i] != iw) simd_fail(c, "vi_load/vi_store at %d: element %d = %d, expected %d", at, i, ib[i], iw);
            }
        }
        /* unaligned at every offset */
        for (int off = 0; off < 17 && off + W <= W + 64; off++) {
            int doff = (off * 7 + 3) % 17;
            for (int i = 0; i < W + 64; i++) b[i] = ffrom(0x7fcdead0u), ib[i] = 0x5eed;
            vf_storeu(b + doff, vf_loadu(a + off));
            vi_storeu(ib + doff, vi_loadu(ia + off));
            for (int i = 0; i < W + 64; i++) {
                bool inside = i >= doff && i < doff + W;
                uint32_t want = inside ? fbits(a[off + i - doff]) : 0x7fcdead0u;
                if (fbits(b[i]) != want) simd_fail(c, "vf_loadu(+%d)/vf_storeu(+%d): element %d = 0x%08x, expected 0x%08x", off, doff, i, fbits(b[i]), want);
                int32_t iw = inside ? ia[off + i - doff] : 0x5eed;
                if (ib[i] != iw) simd_fail(c, "vi_loadu(+%d)/vi_storeu(+%d): element %d = %d, expected %d", off, doff, i, ib[i], iw);
            }
        }
    }
    simd_end(c);
}

static void test_masked(simd_ctx *c, rng *r)
{
    simd_begin(c, "load_masked/store_masked/store_merge");
    float a[W], b[W + 16];
    int32_t ib[W + 16], ia[W];
    for (size_t mi = 0; mi < mask_count(); mi++) {
        uint32_t bits = mask_pattern(mi, r);
        vmask m = vm_from_bits(bits);
        for (int i = 0; i < W; i++) a[i] = rand_float(r), ia[i] = (int32_t)next(r);
        float got[W];
        vstore(got, vf_load_masked(m, a));
        for (int i = 0; i < W; i++) {
            uint32_t want = (bits >> i) & 1 ? fbits(a[i]) : 0u;
            if (fbits(got[i]) != want)
                simd_fail(c, "vf_load_masked(mask 0x%x) lane %d = 0x%08x, expected 0x%08x", bits, i, fbits(got[i]), want);
        }
        for (int i = 0; i < W + 16; i++) b[i] = ffrom(0x7fcdead0u), ib[i] = 0x5eed;
        vf_store_masked(b, m, vload(a));
        vi_store_masked(ib, m, iload(ia));
        for (int i = 0; i < W + 16; i++) {
            bool on = i < W && ((bits >> i) & 1);
            uint32_t want = on ? fbits(a[i]) : 0x7fcdead0u;
            if (fbits(b[i]) != want)
                simd_fail(c, "vf_store_masked(mask 0x%x) element %d = 0x%08x, expected 0x%08x", bits, i, fbits(b[i]), want);
            int32_t iw = on ? ia[i] : 0x5eed;
            if (ib[i] != iw) simd_fail(c, "vi_store_masked(mask 0x%x) element %d = %d, expected %d", bits, i, ib[i], iw);
        }
        /* store_merge: the same result on its W elements, and the last of
         * them may be the last of a page */
        float *fp = c->page_end - W;
        int32_t *ip = (int32_t *)(void *)(c->page_end - W);
        float fold[W];
        int32_t iold[W];
        for (int i = 0; i < W; i++) fold[i] = fp[i] = rand_float(r);
        vf_store_merge(fp, m, vload(a));
        for (int i = 0; i < W; i++) {
            uint32_t want = (bits >> i) & 1 ? fbits(a[i]) : fbits(fold[i]);
            if (fbits(fp[i]) != want)
                simd_fail(c, "vf_store_merge(mask 0x%x) element %d = 0x%08x, expected 0x%08x", bits, i, fbits(fp[i]), want);
        }
        for (int i = 0; i < W; i++) iold[i] = ip[i] = (int32_t)next(r);
        vi_store_merge(ip, m, iload(ia));
        for (int i = 0; i < W; i++) {
            int32_t want = (bits >> i) & 1 ? ia[i] : iold[i];
            if (ip[i] != want) simd_fail(c, "vi_store_merge(mask 0x%x) element %d = %d, expected %d", bits, i, ip[i], want);
        }
    }
    /* inactive lanes past the end of a page: no access at all (a fault
     * would end the test here) */
    for (int k = 1; k <= W; k++) {
        float *p = c->page_end - k;
        int32_t *ip = (int32_t *)(void *)(c->page_end - k);
        for (int i = 0; i < k; i++) p[i] = (float)(i + 100);
        vmask m = vm_first_n((size_t)k);
        float got[W];
        vstore(got, vf_load_masked(m, p));
        for (int i = 0; i < W; i++) {
            float want = i < k ? (float)(i + 100) : 0.0f;
            if (fbits(got[i]) != fbits(want))
                simd_fail(c, "vf_load_masked at the page end, %d active: lane %d = %a, expected %a", k, i, (double)got[i], (double)want);
        }
        vf_store_masked(p, m, vf_set1(-7.0f));
        for (int i = 0; i < k; i++)
            if (p[i] != -7.0f) simd_fail(c, "vf_store_masked at the page end, %d active: element %d = %g", k, i, (double)p[i]);
        vi_store_masked(ip, m, vi_set1(77));
        for (int i = 0; i < k; i++)
            if (ip[i] != 77) simd_fail(c, "vi_store_masked at the page end, %d active: element %d = %d", k, i, ip[i]);
    }
    simd_end(c);
}

static void test_gather(simd_ctx *c, rng *r)
{
    simd_begin(c, "gather");
    static float tab[1024];
    static int32_t itab[1024];
    for (int i = 0; i < 1024; i++) tab[i] = rand_float(r), itab[i] = (int32_t)next(r);
    int32_t idx[W];
    for (int rep = 0; rep < 3000; rep++) {
        for (int i = 0; i < W; i++) {
            switch (rep % 4) {
            case 0: idx[i] = (int32_t)(next(r) % 1024); break;
            case 1: idx[i] = 1023 - i; break;
            case 2: idx[i] = 5; break;
            default: idx[i] = (int32_t)(next(r) % 4) * 256; break;
            }
        }
        float got[W];
        int32_t igot[W];
        vstore(got, vf_gather(tab, iload(idx)));
        istore(igot, vi_gather(itab, iload(idx)));
        for (int i = 0; i < W; i++) {
            if (fbits(got[i]) != fbits(tab[idx[i]]))
                simd_fail(c, "vf_gather lane %d (index %d) = 0x%08x, expected 0x%08x", i, idx[i], fbits(got[i]), fbits(tab[idx[i]]));
            if (igot[i] != itab[idx[i]]) simd_fail(c, "vi_gather lane %d (index %d) = %d, expected %d", i, idx[i], igot[i], itab[idx[i]]);
        }
    }
    simd_end(c);
}

static void test_compress(simd_ctx *c, rng *r)
{
    simd_begin(c, "compress_store");
    float src[W], dst[W + 16];
    int32_t isrc[W], idst[W + 16];
    for (size_t mi = 0; mi < mask_count(); mi++) {
        uint32_t bits = mask_pattern(mi, r);
        vmask m = vm_from_bits(bits);
        for (int i = 0; i < W; i++) {
            /* distinct, and NaN payloads among them: a compress store moves bits */
            src[i] = (i % 5 == 3) ? ffrom(0x7fc00100u + (uint32_t)i) : (float)(1000 + i);
            isrc[i] = (int32_t)(0x10000 * i + 7);
        }
        for (int i = 0; i < W + 16; i++) dst[i] = ffrom(0x7fcdead0u), idst[i] = 0x5eed;
        int n = vf_compress_store(dst, m, vload(src));
        int ni = vi_compress_store(idst, m, iload(isrc));
        int want_n = popc(bits & all_bits());
        if (n != want_n || ni != want_n)
            simd_fail(c, "mask 0x%x: returned %d (float) / %d (int), expected %d", bits, n, ni, want_n);
        int j = 0;
        for (int i = 0; i < W; i++) {
            if (!((bits >> i) & 1)) continue;
            if (fbits(dst[j]) != fbits(src[i]))
                simd_fail(c, "mask 0x%x: float element %d = 0x%08x, expected lane %d's 0x%08x", bits, j, fbits(dst[j]), i, fbits(src[i]));
            if (idst[j] != isrc[i]) simd_fail(c, "mask 0x%x: int element %d = %d, expected lane %d's %d", bits, j, idst[j], i, isrc[i]);
            j++;
        }
        for (int k = want_n; k < W + 16; k++) {
            if (fbits(dst[k]) != 0x7fcdead0u) simd_fail(c, "mask 0x%x: float element %d past the %d active written", bits, k, want_n);
            if (idst[k] != 0x5eed) simd_fail(c, "mask 0x%x: int element %d past the %d active written", bits, k, want_n);
        }
        /* right before an inaccessible page: exactly popcount elements */
        if (want_n > 0) {
            float *p = c->page_end - want_n;
            vf_compress_store(p, m, vload(src));
            vi_compress_store((int32_t *)(void *)(c->page_end - want_n), m, iload(isrc));
        }
    }
    simd_end(c);
}

/* Binary float operations lane by lane over pairs of special and random
 * values. */
#define BINARY_TEST(NAME, VEXPR, CEXPR)                                                      \
    do {                                                                                     \
        simd_begin(c, NAME);                                                                 \
        float A[W], B[W], R[W];                                                              \
        for (size_t k = 0; k < NSPECIAL * NSPECIAL + 20000; k += W) {                       \
            for (int i = 0; i < W; i++) {                                                    \
                size_t q = k + (size_t)i;                                                    \
                if (q < NSPECIAL * NSPECIAL)                                                 \
                    A[i] = ffrom(special_bits[q / NSPECIAL]), B[i] = ffrom(special_bits[q % NSPECIAL]); \
                else                                                                         \
                    A[i] = rand_float(r), B[i] = rand_float(r);                              \
            }                                                                                \
            vfloat a = vload(A), b = vload(B);                                               \
            vstore(R, VEXPR);                                                                \
            for (int i = 0; i < W; i++) {                                                    \
                float x = A[i], y = B[i], want = CEXPR;                                      \
                if (!CMP(R[i], want))                                                        \
                    simd_fail(c, "%s(%a, %a) = %a (0x%08x), expected %a (0x%08x)", NAME, (double)x, (double)y, \
                              (double)R[i], fbits(R[i]), (double)want, fbits(want));         \
            }                                                                                \
        }                                                                                    \
        simd_end(c);                                                                         \
    } while (0)

#define CMP(got, want) same(got, want)
static float c_min(float x, float y) { return x < y ? x : y; }
static float c_max(float x, float y) { return x > y ? x : y; }

static void test_arith(simd_ctx *c, rng *r)
{
    BINARY_TEST("add", vf_add(a, b), x + y);
    BINARY_TEST("sub", vf_sub(a, b), x - y);
    BINARY_TEST("mul", vf_mul(a, b), x * y);
    BINARY_TEST("div", vf_div(a, b), x / y);
#undef CMP
    /* min and max return their second operand when either is NaN, and
     * decide -0 against +0 the same way: bit for bit, NaN payload included */
#define CMP(got, want) (fbits(got) == fbits(want))
    BINARY_TEST("min (second operand on NaN)", vf_min(a, b), c_min(x, y));
    BINARY_TEST("max (second operand on NaN)", vf_max(a, b), c_max(x, y));
#undef CMP
}

static void test_fma(simd_ctx *c, rng *r)
{
    simd_begin(c, EXPECT_FMA ? "fmadd/fmsub/fnmadd (fused)" : "fmadd/fmsub/fnmadd (two roundings)");
#if defined(__FMA__)
    const bool built_with_fma = true;
#else
    const bool built_with_fma = false;
#endif
    if (built_with_fma != EXPECT_FMA)
        simd_fail(c, "the set is built %s FMA, but its fmadd is expected %s", built_with_fma ? "with" : "without",
                  EXPECT_FMA ? "fused" : "unfused");
    float A[W], B[W], C[W], R1[W], R2[W], R3[W];
    for (int k = 0; k < 60000; k += W) {
        for (int i = 0; i < W; i++) {
            A[i] = rand_float(r), B[i] = rand_float(r);
            /* c near -a*b makes the single rounding visible */
            C[i] = (k / W) % 3 == 0 ? -(A[i] * B[i]) * (1.0f + (float)(next(r) % 5) * 0x1p-23f) : rand_float(r);
        }
        vfloat a = vload(A), b = vload(B), cc = vload(C);
        vstore(R1, vf_fmadd(a, b, cc));
        vstore(R2, vf_fmsub(a, b, cc));
        vstore(R3, vf_fnmadd(a, b, cc));
        for (int i = 0; i < W; i++) {
            float x = A[i], y = B[i], z = C[i];
            float w1 = x * y + z, w2 = x * y - z, w3 = z - x * y;
            if (EXPECT_FMA) w1 = fmaf(x, y, z), w2 = fmaf(x, y, -z), w3 = fmaf(-x, y, z);
            if (!same(R1[i], w1)) simd_fail(c, "fmadd(%a, %a, %a) = %a, expected %a", (double)x, (double)y, (double)z, (double)R1[i], (double)w1);
            if (!same(R2[i], w2)) simd_fail(c, "fmsub(%a, %a, %a) = %a, expected %a", (double)x, (double)y, (double)z, (double)R2[i], (double)w2);
            if (!same(R3[i], w3)) simd_fail(c, "fnmadd(%a, %a, %a) = %a, expected %a", (double)x, (double)y, (double)z, (double)R3[i], (double)w3);
        }
    }
    /* a case that tells the two apart: (1 + 2^-12)^2 - (1 + 2^-11) is 2^-24
     * exactly, and 0 when the product is rounded first */
    float x = 1.0f + 0x1p-12f, z = -(1.0f + 0x1p-11f);
    float got = vf_lane(vf_fmadd(vf_set1(x), vf_set1(x), vf_set1(z)), 0);
    float want = EXPECT_FMA ? 0x1p-24f : 0.0f;
    if (fbits(got) != fbits(want)) simd_fail(c, "fmadd(1+2^-12, 1+2^-12, -(1+2^-11)) = %a, expected %a", (double)got, (double)want);
    simd_end(c);
}

/* Unary operations over specials, random values and a sweep. */
#define UNARY_LOOP(...)                                                                      \
    for (int k = 0; k < 40000 + (int)NSPECIAL; k += W) {                                    \
        float A[W], R[W];                                                                    \
        for (int i = 0; i < W; i++)                                                          \
            A[i] = k + i < (int)NSPECIAL ? ffrom(special_bits[k + i]) : rand_float(r);      \
        __VA_ARGS__                                                                          \
    }

static void test_unary(simd_ctx *c, rng *r)
{
    simd_begin(c, "abs/neg");
    UNARY_LOOP({
        vfloat a = vload(A);
        vstore(R, vf_abs(a));
        for (int i = 0; i < W; i++)
            if (fbits(R[i]) != (fbits(A[i]) & 0x7fffffffu)) simd_fail(c, "abs(0x%08x) = 0x%08x", fbits(A[i]), fbits(R[i]));
        vstore(R, vf_neg(a));
        for (int i = 0; i < W; i++)
            if (fbits(R[i]) != (fbits(A[i]) ^ 0x80000000u)) simd_fail(c, "neg(0x%08x) = 0x%08x", fbits(A[i]), fbits(R[i]));
    })
    simd_end(c);

    simd_begin(c, "floor");
    UNARY_LOOP({
        vstore(R, vf_floor(vload(A)));
        for (int i = 0; i < W; i++) {
            /* bit for bit, -0 and infinities kept; a NaN comes back a NaN */
            float want = floorf(A[i]);
            if (!same(R[i], want)) simd_fail(c, "floor(%a) = %a, expected %a", (double)A[i], (double)R[i], (double)want);
        }
    })
    /* just below and above integers, where a floor by conversion goes wrong */
    for (int k = -300; k <= 300; k++) {
        float x = ldexpf((float)k, (k % 7) * 3), lo = nextafterf(x, -INFINITY), hi = nextafterf(x, INFINITY);
        float A[3] = {lo, x, hi};
        for (int j = 0; j < 3; j++) {
            float got = vf_lane(vf_floor(vf_set1(A[j])), 0);
            if (!same(got, floorf(A[j]))) simd_fail(c, "floor(%a) = %a, expected %a", (double)A[j], (double)got, (double)floorf(A[j]));
        }
    }
    simd_end(c);

    simd_begin(c, "sqrt");
    UNARY_LOOP({
        vstore(R, vf_sqrt(vload(A)));
        for (int i = 0; i < W; i++)
            if (!same(R[i], sqrtf(A[i]))) simd_fail(c, "sqrt(%a) = %a, expected %a", (double)A[i], (double)R[i], (double)sqrtf(A[i]));
    })
    simd_end(c);

    simd_begin(c, "rcp (exact)");
    UNARY_LOOP({
        vstore(R, vf_rcp(vload(A)));
        for (int i = 0; i < W; i++)
            if (!same(R[i], 1.0f / A[i])) simd_fail(c, "rcp(%a) = %a, expected %a", (double)A[i], (double)R[i], (double)(1.0f / A[i]));
    })
    simd_end(c);

    /* The hardware estimates: RCPPS (and RCPSS) guarantee 1.5 * 2^-12
     * relative error, AVX-512's VRCP14PS 2^-14. Both give ±inf for ±0
     * and ±0 for ±inf; RCPPS treats denormal inputs as 0 and flushes
     * denormal results to 0. */
    const double fast_bound = EXPECT_RCP14 ? 0x1p-14 : 1.5 * 0x1p-12;
    const char *fast_name = EXPECT_RCP14 ? "rcp_fast (RCP14, 2^-14)" : "rcp_fast (RCPPS, 1.5 * 2^-12)";
    simd_begin(c, fast_name);
    double worst = 0;
    UNARY_LOOP({
        vstore(R, vf_rcp_fast(vload(A)));
        for (int i = 0; i < W; i++) {
            float a = A[i], g = R[i];
            double e = 1.0 / (double)a;
            bool ok;
            if (a != a) ok = g != g;
            else if (a == 0) ok = isinf(g) && signbit(g) == signbit(a);
            else if (isinf(a)) ok = g == 0 && signbit(g) == signbit(a);
            else if (fabsf(a) < FLT_MIN) ok = (isinf(g) || fabs(g - e) <= fast_bound * fabs(e)) && signbit(g) == signbit(a);
            else if (fabs(e) <= FLT_MIN * (1 + fast_bound)) /* the estimate may fall below FLT_MIN and flush */
                ok = fabs(g) <= FLT_MIN * (1 + fast_bound) && signbit(g) == signbit(a);
            else {
                double rel = fabs(g - e) / fabs(e);
                worst = fmax(worst, rel);
                ok = rel <= fast_bound;
            }
            if (!ok) simd_fail(c, "rcp_fast(%a) = %a, 1/x = %a", (double)a, (double)g, e);
        }
    })
    /* and every mantissa of one binade */
    for (uint32_t m = 0; m < (1u << 23); m += W * 37) {
        float A[W], R[W];
        for (int i = 0; i < W; i++) A[i] = ffrom(0x3f800000u | ((m + (uint32_t)i) & 0x7fffffu));
        vstore(R, vf_rcp_fast(vload(A)));
        for (int i = 0; i < W; i++) {
            double e = 1.0 / (double)A[i], rel = fabs(R[i] - e) / e;
            worst = fmax(worst, rel);
            if (rel > fast_bound) simd_fail(c, "rcp_fast(%a) = %a, relative error %.3g", (double)A[i], (double)R[i], rel);
        }
    }
    printf("  %s %s: max relative error %.3g = 2^%.2f (bound 2^%.2f)\n", c->isa, fast_name, worst, log2(worst),
           log2(fast_bound));
    simd_end(c);

    /* One Newton step squares the estimate's error e0 and adds its own
     * roundings: from the specified e0 (not one CPU's table), RCPPS gives
     * e0^2 <= 2.25u, plus about 1.5u of rounding with FMA and 2.5u without;
     * RCP14 gives e0^2 <= u/16 plus the FMA step's rounding. Measured on an
     * AMD EPYC: 3.37u, 2.58u and 1.02u; Intel parts measure 2.93u, 2.02u and
     * 1.02u (shared/research/robustness.md §4). */
    const double nr_bound = EXPECT_RCP14 ? 2.0 * 0x1p-24 : EXPECT_FMA ? 4.0 * 0x1p-24 : 5.0 * 0x1p-24;
    simd_begin(c, "rcp_nr");
    worst = 0;
    for (uint32_t m = 0; m < (1u << 23); m += W * 13) {
        float A[W], R[W];
        for (int i = 0; i < W; i++) {
            uint32_t e = 127u + (m % 200u) - 100u; /* exponents 2^-100 .. 2^99 */
            A[i] = ffrom((e << 23) | ((m + (uint32_t)i) & 0x7fffffu) | (m & 1u ? 0x80000000u : 0u));
        }
        vstore(R, vf_rcp_nr(vload(A)));
        for (int i = 0; i < W; i++) {
            double e = 1.0 / (double)A[i], rel = fabs(R[i] - e) / fabs(e);
            worst = fmax(worst, rel);
            if (rel > nr_bound) simd_fail(c, "rcp_nr(%a) = %a, relative error %.3g u", (double)A[i], (double)R[i], rel / 0x1p-24);
        }
    }
    printf("  %s rcp_nr: max relative error %.3g u (bound %.2g u)\n", c->isa, worst / 0x1p-24, nr_bound / 0x1p-24);
    simd_end(c);
}

static void test_compare(simd_ctx *c, rng *r)
{
    simd_begin(c, "compares lt/le/gt/ge/eq/neq/isnan");
    float A[W], B[W];
    for (size_t k = 0; k < NSPECIAL * NSPECIAL + 20000; k += W) {
        for (int i = 0; i < W; i++) {
            size_t q = k + (size_t)i;
            if (q < NSPECIAL * NSPECIAL)
                A[i] = ffrom(special_bits[q / NSPECIAL]), B[i] = ffrom(special_bits[q % NSPECIAL]);
            else
                A[i] = rand_float(r), B[i] = (next(r) & 1) ? A[i] : rand_float(r);
        }
        vfloat a = vload(A), b = vload(B);
        uint32_t got[7] = {vm_bits(vf_lt(a, b)), vm_bits(vf_le(a, b)), vm_bits(vf_gt(a, b)), vm_bits(vf_ge(a, b)),
                           vm_bits(vf_eq(a, b)), vm_bits(vf_neq(a, b)), vm_bits(vf_isnan(a))};
        static const char *const names[7] = {"lt", "le", "gt", "ge", "eq", "neq", "isnan"};
        for (int i = 0; i < W; i++) {
            float x = A[i], y = B[i];
            bool want[7] = {x < y, x <= y, x > y, x >= y, x == y, !(x == y), x != x};
            for (int o = 0; o < 7; o++)
                if (((got[o] >> i) & 1) != want[o])
                    simd_fail(c, "%s(%a, %a) lane %d = %u, expected %d", names[o], (double)x, (double)y, i, (got[o] >> i) & 1, want[o]);
        }
    }
    simd_end(c);
}

static void test_masks(simd_ctx *c, rng *r)
{
    simd_begin(c, "masks from_bits/bits/logic/any/all/none/popcount");
    const uint32_t full = all_bits();
    size_t n = mask_count();
    for (size_t i = 0; i < n; i++) {
        uint32_t x = mask_pattern(i, r);
        /* bits above the width are ignored */
        vmask a = vm_from_bits(x | (~full & (uint32_t)next(r)));
        if (vm_bits(a) != x) simd_fail(c, "vm_bits(vm_from_bits(0x%x)) = 0x%x", x, vm_bits(a));
        if (vm_any(a) != (x != 0)) simd_fail(c, "any(0x%x) = %d", x, vm_any(a));
        if (vm_none(a) != (x == 0)) simd_fail(c, "none(0x%x) = %d", x, vm_none(a));
        if (vm_all(a) != (x == full)) simd_fail(c, "all(0x%x) = %d", x, vm_all(a));
        if (vm_popcount(a) != popc(x)) simd_fail(c, "popcount(0x%x) = %d", x, vm_popcount(a));
        if (vm_bits(vm_not(a)) != (~x & full)) simd_fail(c, "not(0x%x) = 0x%x", x, vm_bits(vm_not(a)));
        size_t inner = W <= 4 ? n : 64;
        for (size_t j = 0; j < inner; j++) {
            uint32_t y = W <= 4 ? (uint32_t)j : (uint32_t)next(r) & full;
            vmask b = vm_from_bits(y);
            if (vm_bits(vm_and(a, b)) != (x & y)) simd_fail(c, "and(0x%x, 0x%x) = 0x%x", x, y, vm_bits(vm_and(a, b)));
            if (vm_bits(vm_or(a, b)) != (x | y)) simd_fail(c, "or(0x%x, 0x%x) = 0x%x", x, y, vm_bits(vm_or(a, b)));
            if (vm_bits(vm_xor(a, b)) != (x ^ y)) simd_fail(c, "xor(0x%x, 0x%x) = 0x%x", x, y, vm_bits(vm_xor(a, b)));
            /* andnot(a, b) is a and not b (vec1_scalar.h) */
            if (vm_bits(vm_andnot(a, b)) != (x & ~y & full))
                simd_fail(c, "andnot(0x%x, 0x%x) = 0x%x, expected a & ~b = 0x%x", x, y, vm_bits(vm_andnot(a, b)), x & ~y & full);
        }
    }
    if (vm_bits(vm_true()) != full || vm_bits(vm_false()) != 0)
        simd_fail(c, "true/false = 0x%x/0x%x", vm_bits(vm_true()), vm_bits(vm_false()));
    static const size_t big[] = {(size_t)1 << 31, (size_t)1 << 32, ((size_t)1 << 32) + 3, (size_t)-1, (size_t)-1 / 2};
    for (size_t k = 0; k < (size_t)W + 4 + sizeof big / sizeof big[0]; k++) {
        size_t nn = k < (size_t)W + 4 ? k : big[k - (W + 4)];
        uint32_t want = nn >= W ? full : (1u << nn) - 1u;
        if (vm_bits(vm_first_n(nn)) != want) simd_fail(c, "first_n(%zu) = 0x%x, expected 0x%x", nn, vm_bits(vm_first_n(nn)), want);
    }
    simd_end(c);

    simd_begin(c, "select");
    for (int k = 0; k < 5000; k++) {
        float A[W], B[W], R[W];
        int32_t IA[W], IB[W], IR[W];
        uint32_t bits = (uint32_t)next(r) & full;
        for (int i = 0; i < W; i++) A[i] = rand_float(r), B[i] = rand_float(r), IA[i] = (int32_t)next(r), IB[i] = (int32_t)next(r);
        vmask m = vm_from_bits(bits);
        vstore(R, vf_select(m, vload(A), vload(B)));
        istore(IR, vi_select(m, iload(IA), iload(IB)));
        for (int i = 0; i < W; i++) {
            bool on = (bits >> i) & 1;
            if (fbits(R[i]) != fbits(on ? A[i] : B[i])) simd_fail(c, "vf_select mask 0x%x lane %d = 0x%08x", bits, i, fbits(R[i]));
            if (IR[i] != (on ? IA[i] : IB[i])) simd_fail(c, "vi_select mask 0x%x lane %d = %d", bits, i, IR[i]);
        }
    }
    simd_end(c);
}

static void test_reduce(simd_ctx *c, rng *r)
{
    simd_begin(c, "reduce_min/max/add");
    for (int k = 0; k < 20000; k++) {
        float A[W];
        bool ints = k % 2 == 0;
        for (int i = 0; i < W; i++) A[i] = ints ? (float)((int32_t)(next(r) % 2001) - 1000) : rand_number(r);
        if (k % 7 == 0) A[next(r) % W] = (next(r) & 1) ? -0.0f : 0.0f;
        vfloat a = vload(A);
        float mn = A[0], mx = A[0];
        double sum = 0, mag = 0;
        for (int i = 0; i < W; i++) {
            if (A[i] < mn) mn = A[i];
            if (A[i] > mx) mx = A[i];
            sum += A[i], mag += fabs(A[i]);
        }
        /* NaN-free input: the minimum and maximum are exact (-0 and +0 may
         * come out either way, they compare equal) */
        if (vf_reduce_min(a) != mn) simd_fail(c, "reduce_min = %a, expected %a", (double)vf_reduce_min(a), (double)mn);
        if (vf_reduce_max(a) != mx) simd_fail(c, "reduce_max = %a, expected %a", (double)vf_reduce_max(a), (double)mx);
        float s = vf_reduce_add(a);
        /* integers sum exactly; otherwise W - 1 roundings in some order */
        bool ok = ints ? s == (float)sum
                       : (isinf(sum) || mag > FLT_MAX ? true : fabs(s - sum) <= (W - 1) * 0x1p-24 * mag * 1.0001 + 1e-45);
        if (!ok) simd_fail(c, "reduce_add = %a, exact sum %a", (double)s, sum);
    }
    simd_end(c);
}

static void test_int(simd_ctx *c, rng *r)
{
    simd_begin(c, "int add/sub/mul/and/or/xor/shifts/min/max/compares");
    static const int32_t specials[] = {0, 1, -1, 2147483647, -2147483647 - 1, 0x55555555, -0x55555556, 65536, -65536};
    for (int k = 0; k < 20000; k++) {
        int32_t A[W], B[W], R[12][W];
        for (int i = 0; i < W; i++) {
            A[i] = (next(r) & 3) ? (int32_t)next(r) : specials[next(r) % 9];
            B[i] = (next(r) & 3) ? (int32_t)next(r) : specials[next(r) % 9];
        }
        int sh = (int)(next(r) % 32);
        vint a = iload(A), b = iload(B);
        istore(R[0], vi_add(a, b));
        istore(R[1], vi_sub(a, b));
        istore(R[2], vi_and(a, b));
        istore(R[3], vi_or(a, b));
        istore(R[4], vi_xor(a, b));
        istore(R[5], vi_sll(a, sh));
        istore(R[6], vi_srl(a, sh));
        istore(R[7], vi_min(a, b));
        istore(R[8], vi_max(a, b));
        istore(R[9], vi_mul(a, b));
        uint32_t eq = vm_bits(vi_eq(a, b)), lt = vm_bits(vi_lt(a, b)), gt = vm_bits(vi_gt(a, b));
        static const char *const names[10] = {"add", "sub", "and", "or", "xor", "sll", "srl", "min", "max", "mul"};
        for (int i = 0; i < W; i++) {
            uint32_t x = (uint32_t)A[i], y = (uint32_t)B[i];
            int32_t want[10] = {(int32_t)(x + y), (int32_t)(x - y), (int32_t)(x & y), (int32_t)(x | y), (int32_t)(x ^ y),
                                (int32_t)(x << sh), (int32_t)(x >> sh), A[i] < B[i] ? A[i] : B[i], A[i] > B[i] ? A[i] : B[i],
                                (int32_t)(x * y)};
            for (int o = 0; o < 10; o++)
                if (R[o][i] != want[o]) simd_fail(c, "vi_%s(%d, %d%s) = %d, expected %d", names[o], A[i], o == 5 || o == 6 ? sh : B[i],
                                                  o == 5 || o == 6 ? " (shift)" : "", R[o][i], want[o]);
            if (((eq >> i) & 1) != (A[i] == B[i])) simd_fail(c, "vi_eq(%d, %d) = %u", A[i], B[i], (eq >> i) & 1);
            if (((lt >> i) & 1) != (A[i] < B[i])) simd_fail(c, "vi_lt(%d, %d) = %u", A[i], B[i], (lt >> i) & 1);
            if (((gt >> i) & 1) != (A[i] > B[i])) simd_fail(c, "vi_gt(%d, %d) = %u", A[i], B[i], (gt >> i) & 1);
        }
    }
    simd_end(c);
}

static void test_convert(simd_ctx *c, rng *r)
{
    simd_begin(c, "conversions as_vi/as_vf/to_vf/to_vi");
    for (int k = 0; k < 40000; k += W) {
        float A[W], RF[W];
        int32_t I[W], RI[W];
        for (int i = 0; i < W; i++) {
            A[i] = k + i < (int)NSPECIAL ? ffrom(special_bits[k + i]) : rand_float(r);
            I[i] = (next(r) & 1) ? (int32_t)next(r) : (int32_t)(next(r) % 100000) - 50000;
        }
        istore(RI, vf_as_vi(vload(A)));
        for (int i = 0; i < W; i++)
            if ((uint32_t)RI[i] != fbits(A[i])) simd_fail(c, "as_vi(0x%08x) = 0x%08x", fbits(A[i]), (uint32_t)RI[i]);
        vstore(RF, vi_as_vf(iload(I)));
        for (int i = 0; i < W; i++)
            if (fbits(RF[i]) != (uint32_t)I[i]) simd_fail(c, "as_vf(0x%08x) = 0x%08x", (uint32_t)I[i], fbits(RF[i]));
        vstore(RF, vi_to_vf(iload(I)));
        for (int i = 0; i < W; i++)
            if (fbits(RF[i]) != fbits((float)I[i])) simd_fail(c, "to_vf(%d) = %a, expected %a", I[i], (double)RF[i], (double)(float)I[i]);
        /* truncation toward zero; NaN and out-of-range give INT32_MIN (the
         * x86 "integer indefinite"), on every set alike */
        istore(RI, vf_to_vi(vload(A)));
        for (int i = 0; i < W; i++) {
            float a = A[i];
            int32_t want = (a == a && a > -2147483904.0f && a < 2147483648.0f) ? (int32_t)a : INT32_MIN;
            if (RI[i] != want) simd_fail(c, "to_vi(%a) = %d, expected %d", (double)a, RI[i], want);
        }
    }
    simd_end(c);
}

void LANES_FN(test_simd_ops_run)(simd_ctx *c)
{
    rng r = {c->seed ^ (uint64_t)W * 0x1234567ull};
    test_construct(c, &r);
    test_load_store(c, &r);
    test_masked(c, &r);
    test_gather(c, &r);
    test_compress(c, &r);
    test_arith(c, &r);
    test_fma(c, &r);
    test_unary(c, &r);
    test_compare(c, &r);
    test_masks(c, &r);
    test_reduce(c, &r);
    test_int(c, &r);
    test_convert(c, &r);
    LANES_FN(test_simd_math_run)(c);
}
