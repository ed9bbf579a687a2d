/* The accuracy modes' promises, measured with the code behind
 * `lanes accuracy` (bench/accuracy_measure.c), at every kernel set this CPU
 * runs:
 *
 *   test_accuracy reference
 *       the exact reference (bench/accuracy_reference.c) against integer
 *       arithmetic on float inputs built to sit on and one unit beside its
 *       decision boundaries, where plain double evaluation is wrong;
 *   test_accuracy closed
 *       closedness of the built-in meshes, the filling of the dragon's holes,
 *       refusal of an open mesh and of a missing file;
 *   test_accuracy leaks MESH [--rays N] [--threads N]
 *       robust mode leaks no ray out of N rays in random directions (default
 *       10^7) per translation (0, 1e3, 1e5) and set through trace_wide, nor
 *       out of N/10 through trace_bvh2 and through trace_packet (packets of
 *       the 256 rays of one interior point, partition scheme); nor out of
 *       N/10 rays aimed at vertices and edges through trace_wide and N/100
 *       through the other two. Fast and default leak at most what was
 *       measured when this test was written (table below), through
 *       trace_wide on min(N/10, 10^6) random and min(N/100, 10^5) aimed rays.
 *
 * Exit status 77 (skipped) when the CGAL meshes are not fetched. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench/accuracy_measure.h"
#include "bench/accuracy_reference.h"
#include "build/parallel.h"
#include "build/scenes_builtin.h"
#include "simd/isa.h"
#include "tests/harness.h"

#define SKIP 77

static double now(void)
{
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* ---- the reference ---------------------------------------------------- */

static harness_rng rng_state = {0x2545F4914F6CDD1Dull};
static uint64_t rng(void) { return harness_next(&rng_state); }
static int64_t rint_in(int64_t lo, int64_t hi) { return lo + (int64_t)(rng() % (uint64_t)(hi - lo + 1)); }

typedef __int128 i128;

static int sign128(i128 x) { return (x > 0) - (x < 0); }

/* d . (b x c) for integer vectors, exactly. */
static i128 triple(const int64_t d[3], const int64_t b[3], const int64_t c[3])
{
    i128 s = 0;
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        s += (i128)d[i] * ((i128)b[j] * c[k] - (i128)b[k] * c[j]);
    }
    return s;
}

/* The same in plain double, as a naive reference would compute it. */
static double triple_double(const double d[3], const double b[3], const double c[3])
{
    double s = 0.0;
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        s += d[i] * (b[j] * c[k] - b[k] * c[j]);
    }
    return s;
}

/* One case: the reference's decision against the exact one, computed in
 * 128-bit integers from the inputs scaled by 2^scale (all of them are
 * multiples of 2^-scale); t's sign too when with_t. Also what plain double
 * evaluation says. Returns false when the reference is wrong. */
typedef struct {
    int cases, on_boundary, naive_wrong, wrong;
} ref_stats;

static bool check_case(const float o[3], const float d[3], const float v[9], int scale, bool with_t, ref_stats *st)
{
    int64_t A[3], B[3], C[3], D[3];
    double Ad[3], Bd[3], Cd[3], dd[3];
    double k = ldexp(1.0, scale);
    for (int a = 0; a < 3; a++) {
        int64_t oi = (int64_t)(o[a] * k);
        A[a] = (int64_t)(v[a] * k) - oi, B[a] = (int64_t)(v[3 + a] * k) - oi, C[a] = (int64_t)(v[6 + a] * k) - oi;
        D[a] = (int64_t)d[a];
        Ad[a] = (double)v[a] - o[a], Bd[a] = (double)v[3 + a] - o[a], Cd[a] = (double)v[6 + a] - o[a];
        dd[a] = d[a];
    }
    int su = sign128(triple(D, B, C)), sv = sign128(triple(D, C, A)), sw = sign128(triple(D, A, B));
    bool pos = su > 0 || sv > 0 || sw > 0, neg = su < 0 || sv < 0 || sw < 0;
    bool crosses = (pos || neg) && !(pos && neg);
    int t_sign = with_t ? sign128(triple(A, B, C)) * (neg ? -1 : 1) : 0;
    st->cases++;
    st->on_boundary += su == 0 || sv == 0 || sw == 0;
    double nu = triple_double(dd, Bd, Cd), nv = triple_double(dd, Cd, Ad), nw = triple_double(dd, Ad, Bd);
    bool npos = nu > 0 || nv > 0 || nw > 0, nneg = nu < 0 || nv < 0 || nw < 0;
    st->naive_wrong += ((npos || nneg) && !(npos && nneg)) != crosses;
    acc_tri_result r = acc_ref_tri(o, d, v);
    if (r.crosses == crosses && (!with_t || !crosses || r.t_sign == t_sign)) return true;
    if (st->wrong++ < 5)
        printf("  reference wrong: o (%a %a %a) d (%a %a %a): crosses %d (exact %d), t sign %d (exact %d)\n", o[0],
               o[1], o[2], d[0], d[1], d[2], r.crosses, crosses, r.t_sign, t_sign);
    return false;
}

/* Two families of float inputs built to sit on the reference's decision
 * boundaries and one unit beside them:
 * - integer-valued floats up to 2^24: the ray passes exactly through a point
 *   of an edge, one unit beside it, or through a vertex;
 * - mixed scales: an origin with coordinates of a few 2^-30 against
 *   vertices of up to 2^24 whose edge B C lies on the line through the
 *   origin along d (the edge function is exactly 0) or 2^-30 beside it (it
 *   is about 2^-6 while its products are 2^48, where double rounds at
 *   2^-5): plain double gets signs wrong, the reference must not. */
static void test_reference(void)
{
    ref_stats st = {0};
    uint64_t fallbacks0 = acc_ref_exact_fallbacks();
    for (int n = 0; n < 200000; n++) {
        int64_t o[3], d[3], P[3], v[3][3];
        const int64_t big = (int64_t)1 << 22;
        for (int a = 0; a < 3; a++) {
            o[a] = rint_in(-big, big);
            d[a] = rint_in(-(1 << 10), 1 << 10);
        }
        if (d[0] == 0 && d[1] == 0 && d[2] == 0) d[2] = 1;
        int64_t t0 = rint_in(1, 3000);
        for (int a = 0; a < 3; a++) P[a] = o[a] + t0 * d[a]; /* on the ray's line */
        /* an edge v0 v1 through P (v0 = P + e, v1 = P - m e), v2 off it */
        int64_t e[3], m = rint_in(1, 7), kind = rint_in(0, 3);
        for (int a = 0; a < 3; a++) {
            e[a] = rint_in(-(1 << 12), 1 << 12);
            v[0][a] = P[a] + e[a];
            v[1][a] = P[a] - m * e[a];
            v[2][a] = P[a] + rint_in(-(1 << 13), 1 << 13);
        }
        if (kind == 1) v[1][rint_in(0, 2)] += rint_in(0, 1) ? 1 : -1; /* one unit beside the edge */
        if (kind == 2)
            for (int a = 0; a < 3; a++) v[2][a] = P[a]; /* through a vertex */
        float fo[3], fd[3], fv[9];
        bool representable = true;
        for (int a = 0; a < 3; a++) {
            fo[a] = (float)o[a], fd[a] = (float)d[a];
            for (int k = 0; k < 3; k++) {
                fv[3 * k + a] = (float)v[k][a];
                representable &= llabs(v[k][a]) < ((int64_t)1 << 24);
            }
        }
        if (representable) check_case(fo, fd, fv, 0, true, &st);
    }
    ref_stats mixed = {0};
    for (int n = 0; n < 200000; n++) {
        float fo[3], fd[3] = {rint_in(0, 1) ? 1.0f : -1.0f, 0.0f, 0.0f}, fv[9];
        /* B and C on the line through 0 along (p, q) in y, z; the origin on
         * it too (the edge function is exactly 0) or 2^-30 beside it */
        int64_t p = rint_in(1, 7), q = rint_in(-7, 7), j = rint_in(-4, 4);
        int64_t k1 = rint_in(1 << 19, (1 << 21) - 1), k2 = -rint_in(1 << 19, (1 << 21) - 1);
        int64_t beside = rint_in(0, 1) ? rint_in(-1, 1) : 0;
        fo[0] = (float)ldexp((double)rint_in(-(1 << 20), 1 << 20), -30);
        fo[1] = (float)ldexp((double)(j * p + beside), -30);
        fo[2] = (float)ldexp((double)(j * q), -30);
        fv[0] = (float)rint_in(-(1 << 20), 1 << 20), fv[1] = (float)rint_in(-(1 << 20), 1 << 20);
        fv[2] = (float)rint_in(-(1 << 20), 1 << 20);
        fv[3] = (float)rint_in(-(1 << 20), 1 << 20), fv[4] = (float)(k1 * p), fv[5] = (float)(k1 * q);
        fv[6] = (float)rint_in(-(1 << 20), 1 << 20), fv[7] = (float)(k2 * p), fv[8] = (float)(k2 * q);
        check_case(fo, fd, fv, 30, false, &mixed);
    }
    uint64_t fallbacks = acc_ref_exact_fallbacks() - fallbacks0;
    printf("reference: %d integer cases (%d on an edge or vertex), %d mixed-scale cases (%d exactly on an edge); "
           "%llu decided by exact arithmetic; plain double gets %d + %d hit/miss decisions wrong, the reference "
           "%d + %d\n",
           st.cases, st.on_boundary, mixed.cases, mixed.on_boundary, (unsigned long long)fallbacks, st.naive_wrong,
           mixed.naive_wrong, st.wrong, mixed.wrong);
    CHECK(st.wrong == 0 && mixed.wrong == 0, "the exact reference disagrees with integer arithmetic in %d cases",
          st.wrong + mixed.wrong);
    CHECK(mixed.naive_wrong > 0,
          "no case defeats plain double: the test cannot tell an exact reference from a naive one");
    CHECK(fallbacks > 0, "the exact path was never taken");

    /* a unit cube's closed surface: every ray from its centre crosses once */
    static const float cube[12][9] = {
        {0, 0, 0, 0, 1, 0, 1, 1, 0}, {0, 0, 0, 1, 1, 0, 1, 0, 0}, {0, 0, 1, 1, 0, 1, 1, 1, 1},
        {0, 0, 1, 1, 1, 1, 0, 1, 1}, {0, 0, 0, 1, 0, 0, 1, 0, 1}, {0, 0, 0, 1, 0, 1, 0, 0, 1},
        {0, 1, 0, 0, 1, 1, 1, 1, 1}, {0, 1, 0, 1, 1, 1, 1, 1, 0}, {0, 0, 0, 0, 0, 1, 0, 1, 1},
        {0, 0, 0, 0, 1, 1, 0, 1, 0}, {1, 0, 0, 1, 1, 0, 1, 1, 1}, {1, 0, 0, 1, 1, 1, 1, 0, 1}};
    int bad = 0;
    for (int n = 0; n < 1000; n++) {
        float o[3] = {0.5f, 0.5f, 0.5f}, d[3];
        for (int a = 0; a < 3; a++) d[a] = (float)rint_in(-4, 4); /* often through edges and corners */
        if (d[0] == 0 && d[1] == 0 && d[2] == 0) continue;
        int hits = 0;
        for (int t = 0; t < 12; t++) {
            acc_tri_result r = acc_ref_tri(o, d, cube[t]);
            hits += r.crosses && r.t_sign > 0;
        }
        bad += hits < 1;
    }
    CHECK(bad == 0, "%d rays from the centre of a closed cube cross nothing", bad);
}

/* ---- closedness ------------------------------------------------------- */

static void test_closed(void)
{
    lanes_mesh m;
    lanes_error err;
    char note[320];
    CHECK(acc_mesh_load("sphere", false, &m, note, sizeof note, &err) == LANES_OK, "sphere: %s", err.message);
    if (m.triangle_count) CHECK(note[0] == '\0', "sphere: unexpected note '%s'", note);
    lanes_mesh_free(&m);
    if (lanes_builtin_meshes_available()) {
        CHECK(acc_mesh_load("bunny", false, &m, note, sizeof note, &err) == LANES_OK, "bunny: %s",
              err.message);
        lanes_mesh_free(&m);
        CHECK(acc_mesh_load("dragon", false, &m, note, sizeof note, &err) == LANES_OK, "dragon: %s",
              err.message);
        CHECK(strstr(note, "filling") != NULL, "dragon: the hole filling is not reported ('%s')", note);
        printf("closed: %s\n", note);
        acc_closure c;
        CHECK(acc_mesh_closure(&m, &c, &err) == LANES_OK && acc_closure_closed(&c),
              "dragon: not closed after filling");
        lanes_mesh_free(&m);
    } else {
        printf("closed: meshes not fetched; bunny and dragon not checked\n");
    }
    /* one triangle removed from the sphere: three boundary edges */
    CHECK(acc_mesh_load("sphere", false, &m, NULL, 0, &err) == LANES_OK, "sphere: %s", err.message);
    m.triangle_count--;
    acc_closure c;
    CHECK(acc_mesh_closure(&m, &c, &err) == LANES_OK && c.boundary == 3 && !acc_closure_closed(&c),
          "a sphere without one triangle: %zu boundary edges", c.boundary);
    /* flipping a triangle makes its three edges run the same way as their neighbours' */
    m.triangle_count++;
    uint32_t s = m.indices[0];
    m.indices[0] = m.indices[1], m.indices[1] = s;
    CHECK(acc_mesh_closure(&m, &c, &err) == LANES_OK && c.misoriented == 3 && !acc_closure_closed(&c),
          "a sphere with one flipped triangle: %zu misoriented edges", c.misoriented);
    char what[256];
    acc_closure_describe(&c, what, sizeof what);
    printf("closed: a flipped triangle: %s\n", what);
    lanes_mesh_free(&m);
    /* the plane is open and too open to fill */
    CHECK(acc_mesh_load("plane", false, &m, NULL, 0, &err) != LANES_OK &&
              strstr(err.message, "not a closed mesh"),
          "plane accepted as closed (%s)", err.message);
    printf("closed: plane refused: %s\n", err.message);
}

/* ---- leaks ------------------------------------------------------------- */

/* Fast and default leaks through trace_wide, seed 1, size 100, measured at
 * every set on an AMD Zen 5 (scalar, sse4, avx, avx2, avx512emu, avx512)
 * with gcc 12 and with clang 14 (the same counts), as the maximum over the
 * sets: of leak rays 0 .. 10^6-1 (random directions) and of aimed rays
 * 0 .. 10^5-1 (at vertices and edge midpoints). The sets with FMA (avx2,
 * avx512emu, avx512) leak about twice as many aimed rays as those without:
 * Möller-Trumbore's fused cross products are not antisymmetric, so two
 * triangles disagree more often about a shared edge. The rays are
 * deterministic, so these are counts, not rates; a shorter run traces a
 * prefix and can only count fewer. The bound adds a tenth plus 2, for
 * changes of rounding that are not regressions. Fast mode's random rays at
 * 1e5 were measured again when its box test became one FMA on the ray's
 * precomputed o * (1/d) (about 4% faster): that product's rounding grows
 * with |o|, and 1e5 from the origin it loses a box a ray grazes in up to 26
 * of 10^6 random rays (bunny; default mode: 1). */
typedef struct {
    const char *mesh;
    double translation;
    lanes_accuracy mode;
    uint64_t random;   /* of 10^6 */
    uint64_t aimed;    /* of 10^5 */
} leak_bound;

static const leak_bound bounds[] = {
    {"sphere", 0, LANES_ACCURACY_FAST, 0, 24031},   {"sphere", 0, LANES_ACCURACY_DEFAULT, 0, 22747},
    {"sphere", 1e3, LANES_ACCURACY_FAST, 0, 19250}, {"sphere", 1e3, LANES_ACCURACY_DEFAULT, 0, 18060},
    {"sphere", 1e5, LANES_ACCURACY_FAST, 6, 14066}, {"sphere", 1e5, LANES_ACCURACY_DEFAULT, 0, 13195},
    {"bunny", 0, LANES_ACCURACY_FAST, 2, 14785},    {"bunny", 0, LANES_ACCURACY_DEFAULT, 2, 14031},
    {"bunny", 1e3, LANES_ACCURACY_FAST, 1, 11857},  {"bunny", 1e3, LANES_ACCURACY_DEFAULT, 1, 11151},
    {"bunny", 1e5, LANES_ACCURACY_FAST, 26, 5626},   {"bunny", 1e5, LANES_ACCURACY_DEFAULT, 1, 5251},
    {"dragon", 0, LANES_ACCURACY_FAST, 1, 10647},   {"dragon", 0, LANES_ACCURACY_DEFAULT, 1, 10090},
    {"dragon", 1e3, LANES_ACCURACY_FAST, 1, 8556},  {"dragon", 1e3, LANES_ACCURACY_DEFAULT, 1, 7996},
    {"dragon", 1e5, LANES_ACCURACY_FAST, 4, 5131},  {"dragon", 1e5, LANES_ACCURACY_DEFAULT, 1, 4791},
};
#define BOUND_RANDOM_RAYS 1000000ull
#define BOUND_AIMED_RAYS 100000ull

static uint64_t leak_bound_for(const char *mesh, double t, lanes_accuracy mode, bool aimed, uint64_t rays)
{
    for (size_t i = 0; i < sizeof bounds / sizeof bounds[0]; i++) {
        const leak_bound *b = &bounds[i];
        if (strcmp(b->mesh, mesh) || b->translation != t || b->mode != mode) continue;
        uint64_t measured = aimed ? b->aimed : b->random, at = aimed ? BOUND_AIMED_RAYS : BOUND_RANDOM_RAYS;
        uint64_t bound = measured + measured / 10 + 2;
        /* more rays than measured: the count may grow in proportion */
        if (rays > at) bound = (uint64_t)ceil((double)bound * (double)rays / (double)at);
        return bound;
    }
    return 0;
}

static int test_leaks(const char *mesh_name, uint64_t rays, int threads)
{
    static const double translations[] = {0, 1e3, 1e5};
    lanes_mesh mesh;
    lanes_error err;
    if (strcmp(mesh_name, "sphere") != 0 && !lanes_builtin_meshes_available()) {
        printf("SKIP: %s: the CGAL meshes are not fetched (cmake/fetch_meshes.sh)\n", mesh_name);
        return SKIP;
    }
    if (acc_mesh_load(mesh_name, false, &mesh, NULL, 0, &err) != LANES_OK) {
        printf("FAIL: %s\n", err.message);
        return 1;
    }
    /* fast and default: as many rays as the bounds were measured on, or
     * the same fraction of a shorter run */
    uint64_t fd_rays = rays / 10 < BOUND_RANDOM_RAYS ? rays / 10 : BOUND_RANDOM_RAYS;
    uint64_t fd_aimed = rays / 100 < BOUND_AIMED_RAYS ? rays / 100 : BOUND_AIMED_RAYS;
    unsigned widths = 0;
    for (int i = 0; i < LANES_ISA_COUNT; i++)
        if (lanes_isa_supported((lanes_isa)i)) widths |= acc_width_bit(lanes_kernels_for((lanes_isa)i)->wide_width);
    printf("%s, per translation and set: robust %llu random rays through trace_wide, %llu through trace_bvh2 "
           "and trace_packet, %llu aimed rays through trace_wide, %llu through trace_bvh2 and trace_packet; fast and "
           "default %llu random and %llu aimed rays through trace_wide\n",
           mesh_name, (unsigned long long)rays, (unsigned long long)(rays / 10), (unsigned long long)(rays / 10),
           (unsigned long long)(rays / 100), (unsigned long long)fd_rays, (unsigned long long)fd_aimed);
    printf("%-8s %-12s %-10s %-8s %-8s %-7s %12s %8s %8s\n", "mesh", "translation", "set", "via", "mode", "rays",
           "count", "leaks", "bound");
    for (size_t t = 0; t < sizeof translations / sizeof translations[0]; t++) {
        acc_world w;
        if (acc_world_build(&w, mesh_name, &mesh, ACC_DEFAULT_SIZE, translations[t], widths, threads, 1,
                            &err) != LANES_OK) {
            harness_fail("%s", err.message);
            continue;
        }
        CHECK(w.point_count == ACC_POINTS, "%s at %g: %zu interior points of %d", mesh_name, translations[t],
              w.point_count, ACC_POINTS);
        if (w.point_count == 0) {
            acc_world_free(&w);
            continue;
        }
        for (int i = 0; i < LANES_ISA_COUNT; i++) {
            if (!lanes_isa_supported((lanes_isa)i)) continue;
            const lanes_kernels *k = lanes_kernels_for((lanes_isa)i);
            struct {
                lanes_accuracy mode;
                acc_via via;
                bool aimed;
                uint64_t rays;
            } runs[] = {{LANES_ACCURACY_ROBUST, ACC_VIA_WIDE, false, rays},
                        {LANES_ACCURACY_ROBUST, ACC_VIA_BVH2, false, rays / 10},
                        {LANES_ACCURACY_ROBUST, ACC_VIA_PACKET, false, rays / 10},
                        {LANES_ACCURACY_ROBUST, ACC_VIA_WIDE, true, rays / 10},
                        {LANES_ACCURACY_ROBUST, ACC_VIA_BVH2, true, rays / 100},
                        {LANES_ACCURACY_ROBUST, ACC_VIA_PACKET, true, rays / 100},
                        {LANES_ACCURACY_FAST, ACC_VIA_WIDE, false, fd_rays},
                        {LANES_ACCURACY_DEFAULT, ACC_VIA_WIDE, false, fd_rays},
                        {LANES_ACCURACY_FAST, ACC_VIA_WIDE, true, fd_aimed},
                        {LANES_ACCURACY_DEFAULT, ACC_VIA_WIDE, true, fd_aimed}};
            for (size_t r = 0; r < sizeof runs / sizeof runs[0]; r++) {
                if (runs[r].rays == 0) continue;
                acc_counts c;
                memset(&c, 0, sizeof c);
                acc_job job = {.k = k, .mode = runs[r].mode, .via = runs[r].via, .first = 0, .count = runs[r].rays,
                               .aimed = runs[r].aimed, .threads = threads};
                if (acc_measure(&w, &job, &c, &err) != LANES_OK) {
                    harness_fail("%s", err.message);
                    continue;
                }
                uint64_t bound = runs[r].mode == LANES_ACCURACY_ROBUST
                                     ? 0
                                     : leak_bound_for(mesh_name, translations[t], runs[r].mode, runs[r].aimed,
                                                      runs[r].rays);
                uint64_t traced = runs[r].aimed ? c.aimed_rays : c.rays;
                uint64_t leaks = runs[r].aimed ? c.aimed_leaks : c.leaks;
                const char *kind = runs[r].aimed ? "aimed" : "random";
                printf("%-8s %-12g %-10s %-8s %-8s %-7s %12llu %8llu %8llu\n", mesh_name, translations[t], k->name,
                       acc_via_name(runs[r].via), lanes_accuracy_name(runs[r].mode), kind, (unsigned long long)traced,
                       (unsigned long long)leaks, (unsigned long long)bound);
                CHECK(traced == runs[r].rays, "traced %llu rays of %llu", (unsigned long long)traced,
                      (unsigned long long)runs[r].rays);
                CHECK(leaks <= bound, "%s at translation %g, %s, %s via %s: %llu leaks of %llu %s rays, bound %llu",
                      mesh_name, translations[t], k->name, lanes_accuracy_name(runs[r].mode),
                      acc_via_name(runs[r].via), (unsigned long long)leaks, (unsigned long long)traced, kind,
                      (unsigned long long)bound);
                fflush(stdout);
            }
        }
        acc_world_free(&w);
    }
    lanes_mesh_free(&mesh);
    return 0;
}

int main(int argc, char **argv)
{
    double t0 = now();
    const char *what = argc > 1 ? argv[1] : "";
    printf("sets:");
    for (int i = 0; i < LANES_ISA_COUNT; i++)
        if (lanes_isa_supported((lanes_isa)i)) printf(" %s", lanes_isa_name((lanes_isa)i));
    printf("\n");
    if (strcmp(what, "reference") == 0) {
        test_reference();
    } else if (strcmp(what, "closed") == 0) {
        test_closed();
    } else if (strcmp(what, "leaks") == 0 && argc > 2) {
        uint64_t rays = 10000000;
        int threads = 0;
        for (int i = 3; i < argc; i++) {
            char *end = NULL;
            if (strcmp(argv[i], "--rays") == 0 && i + 1 < argc) {
                rays = strtoull(argv[++i], &end, 10);
            } else if (strcmp(argv[i], "--threads") == 0 && i + 1 < argc) {
                threads = (int)strtol(argv[++i], &end, 10);
            }
            if (!end || *end != '\0' || rays == 0) {
                fprintf(stderr, "usage: test_accuracy leaks MESH [--rays N] [--threads N]\n");
                return 2;
            }
        }
        int rc = test_leaks(argv[2], rays, threads);
        if (rc == SKIP) return SKIP;
        if (rc) return rc;
    } else {
        fprintf(stderr, "usage: test_accuracy reference | closed | leaks MESH [--rays N] [--threads N]\n");
        return 2;
    }
    printf("%s in %.1f s on %d threads\n", what, now() - t0, lanes_parallel_threads(0));
    return harness_summary("test_accuracy");
}
