/* Built-in scenes and objects. Everything here is deterministic: the only
 * randomness is PCG32 with fixed seeds, written out below so no library
 * version can change a scene.
 *
 * Compiled for the x86-64 baseline. */
#define _POSIX_C_SOURCE 200809L /* stat, to tell a missing mesh from a broken one */

#include "build/scenes_builtin.h"

#include "build/memory_limit.h"
#include "build/mesh_import.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#ifndef LANES_DEFAULT_MESH_DIR
#define LANES_DEFAULT_MESH_DIR "out/meshes"
#endif

#define PI 3.14159265358979323846

/* ---- PCG32 (O'Neill), the reference pcg32_random_r ---- */

typedef struct pcg32 {
    uint64_t state, inc;
} pcg32;

static uint32_t pcg32_next(pcg32 *r)
{
    uint64_t old = r->state;
    r->state = old * 6364136223846793005ull + r->inc;
    uint32_t xs = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = (uint32_t)(old >> 59u);
    return (xs >> rot) | (xs << ((32u - rot) & 31u));
}

static void pcg32_seed(pcg32 *r, uint64_t seed, uint64_t seq)
{
    r->state = 0;
    r->inc = (seq << 1u) | 1u;
    pcg32_next(r);
    r->state += seed;
    pcg32_next(r);
}

/* Uniform in [0, 1). */
static double rnd(pcg32 *r)
{
    return pcg32_next(r) * (1.0 / 4294967296.0);
}

/* Uniform in [-1, 1]^3 restricted to the unit ball (rejection). */
static void rnd_ball(pcg32 *r, double p[3])
{
    do {
        for (int a = 0; a < 3; a++)
            p[a] = 2.0 * rnd(r) - 1.0;
    } while (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] > 1.0);
}

/* ---- small vector helpers (double: generation precision is free) ---- */

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double a[3], const double b[3], double o[3])
{
    double r[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    memcpy(o, r, sizeof r);
}

static void normalize3(double v[3])
{
    double l = sqrt(dot3(v, v));
    if (l > 0.0)
        for (int a = 0; a < 3; a++)
            v[a] /= l;
}

/* ---- growing indexed meshes ---- */

typedef struct builder {
    lanes_mesh m;
    size_t vcap, tcap;
    bool failed; /* out of memory or too large; every later call is a no-op */
} builder;

static bool reserve(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return true;
    size_t c = *cap ? *cap : 64;
    while (c < need) {
        if (c > SIZE_MAX / 4 / elem)
            return false;
        c *= 2;
    }
    void *q = realloc(*p, c * elem);
    if (!q)
        return false;
    *p = q;
    *cap = c;
    return true;
}

static uint32_t bvert(builder *b, double x, double y, double z)
{
    if (b->failed)
        return 0;
    void *p = b->m.positions;
    if (b->m.vertex_count >= UINT32_MAX ||
        !reserve(&p, &b->vcap, b->m.vertex_count + 1, 3 * sizeof(float))) {
        b->failed = true;
        return 0;
    }
    b->m.positions = p;
    float *o = b->m.positions + 3 * b->m.vertex_count;
    o[0] = (float)x;
    o[1] = (float)y;
    o[2] = (float)z;
    return (uint32_t)b->m.vertex_count++;
}

static void btri(builder *b, uint32_t i, uint32_t j, uint32_t k)
{
    if (b->failed)
        return;
    void *p = b->m.indices;
    if (b->m.triangle_count >= LANES_SCENE_MAX_TRIANGLES ||
        !reserve(&p, &b->tcap, b->m.triangle_count + 1, 3 * sizeof(uint32_t))) {
        b->failed = true;
        return;
    }
    b->m.indices = p;
    uint32_t *o = b->m.indices + 3 * b->m.triangle_count++;
    o[0] = i;
    o[1] = j;
    o[2] = k;
}

/* Quad a b c d, counter-clockwise seen from its front. */
static void bquad(builder *b, uint32_t a, uint32_t c1, uint32_t c2, uint32_t d)
{
    btri(b, a, c1, c2);
    btri(b, a, c2, d);
}

/* Moves the mesh out of the builder (which is left empty either way, so
 * freeing every builder on an error path is always safe). */
static bool bfinish(builder *b, lanes_mesh *out, const char *what, lanes_error *err)
{
    bool ok = !b->failed;
    if (ok)
        *out = b->m;
    else
        lanes_mesh_free(&b->m);
    memset(b, 0, sizeof *b);
    if (!ok)
        lanes_error_set(err, "%s: out of memory generating geometry", what);
    return ok;
}

/* ---- an edge table: (a, b) with a < b -> value, open addressing ---- */

typedef struct edge_table {
    uint64_t *keys; /* 0 = empty; keys are stored +1 so edge (0,0) is not empty */
    uint32_t *vals;
    size_t mask;
} edge_table;

static bool edges_init(edge_table *t, size_t expected)
{
    size_t n = 16;
    while (n < 2 * expected) {
        if (n > SIZE_MAX / 16)
            return false;
        n *= 2;
    }
    t->keys = calloc(n, sizeof *t->keys);
    t->vals = malloc(n * sizeof *t->vals);
    t->mask = n - 1;
    return t->keys && t->vals;
}

static void edges_free(edge_table *t)
{
    free(t->keys);
    free(t->vals);
}

/* Slot of edge (a, b); *found tells whether it was there. */
static size_t edges_slot(const edge_table *t, uint32_t a, uint32_t b, bool *found)
{
    if (a > b) {
        uint32_t s = a;
        a = b;
        b = s;
    }
    uint64_t key = (((uint64_t)a << 32) | b) + 1;
    uint64_t h = key * 0x9e3779b97f4a7c15ull;
    size_t i = (size_t)(h >> 20) & t->mask;
    while (t->keys[i] != 0 && t->keys[i] != key)
        i = (i + 1) & t->mask;
    *found = t->keys[i] == key;
    t->keys[i] = key;
    return i;
}

/* ---- mesh operations ---- */

bool lanes_mesh_subdivide(const lanes_mesh *in, lanes_mesh *out, lanes_error *err)
{
    memset(out, 0, sizeof *out);
    size_t nt = in->triangle_count, nv = in->vertex_count;
    if (nt > LANES_SCENE_MAX_TRIANGLES / 4 || nv + 3 * nt > UINT32_MAX) {
        lanes_error_set(err, "subdivision: %zu triangles would exceed the limit", nt);
        return false;
    }
    edge_table et = {0};
    /* Per edge: its new vertex, the far vertices of up to two faces and
     * how many faces share it (more than two: non-manifold, kept sharp). */
    size_t emax = 3 * nt;
    uint32_t *e_far = malloc(emax * 2 * sizeof *e_far);
    uint32_t *e_faces = calloc(emax ? emax : 1, sizeof *e_faces);
    uint32_t *e_ends = malloc(emax * 2 * sizeof *e_ends);
    uint32_t *tri_edge = malloc(3 * nt * sizeof *tri_edge);
    double *sum = calloc(3 * (nv ? nv : 1), sizeof *sum);
    double *bsum = calloc(3 * (nv ? nv : 1), sizeof *bsum);
    uint32_t *valence = calloc(nv ? nv : 1, sizeof *valence);
    uint32_t *bcount = calloc(nv ? nv : 1, sizeof *bcount);
    bool ok = edges_init(&et, emax) && e_far && e_faces && e_ends && tri_edge && sum && bsum &&
              valence && bcount;
    size_t ne = 0;
    if (ok) {
        for (size_t t = 0; t < nt; t++) {
            const uint32_t *v = in->indices + 3 * t;
            for (int k = 0; k < 3; k++) {
                uint32_t a = v[k], b = v[(k + 1) % 3], c = v[(k + 2) % 3];
                bool found;
                size_t s = edges_slot(&et, a, b, &found);
                if (!found) {
                    et.vals[s] = (uint32_t)ne;
                    e_ends[2 * ne] = a;
                    e_ends[2 * ne + 1] = b;
                    ne++;
                }
                uint32_t e = et.vals[s];
                if (e_faces[e] < 2)
                    e_far[2 * e + e_faces[e]] = c;
                e_faces[e]++;
                tri_edge[3 * t + k] = e;
            }
        }
        out->vertex_count = nv + ne;
        out->triangle_count = 4 * nt;
        out->positions = malloc(out->vertex_count * 3 * sizeof(float));
        out->indices = malloc(out->triangle_count * 3 * sizeof(uint32_t));
        ok = out->positions && out->indices;
    }
    if (!ok) {
        lanes_mesh_free(out);
        lanes_error_set(err, "subdivision: out of memory");
        goto done;
    }
    const float *P = in->positions;
    for (size_t e = 0; e < ne; e++) {
        uint32_t a = e_ends[2 * e], b = e_ends[2 * e + 1];
        bool interior = e_faces[e] == 2;
        for (int k = 0; k < 3; k++) {
            double pa = P[3 * a + k], pb = P[3 * b + k];
            sum[3 * a + k] += pb;
            sum[3 * b + k] += pa;
            if (!interior) {
                bsum[3 * a + k] += pb;
                bsum[3 * b + k] += pa;
            }
        }
        valence[a]++;
        valence[b]++;
        if (!interior) {
            bcount[a]++;
            bcount[b]++;
        }
        float *o = out->positions + 3 * (nv + e);
        for (int k = 0; k < 3; k++) {
            double m = 0.5 * (P[3 * a + k] + P[3 * b + k]);
            if (interior)
                m = 0.375 * (P[3 * a + k] + P[3 * b + k]) +
                    0.125 * (P[3 * e_far[2 * e] + k] + P[3 * e_far[2 * e + 1] + k]);
            o[k] = (float)m;
        }
    }
    for (size_t v = 0; v < nv; v++) {
        float *o = out->positions + 3 * v;
        const float *p = P + 3 * v;
        double n = valence[v];
        for (int k = 0; k < 3; k++) {
            double r = p[k];
            if (bcount[v] == 2) {
                r = 0.75 * p[k] + 0.125 * bsum[3 * v + k];
            } else if (bcount[v] == 0 && n >= 3) {
                double beta = n == 3 ? 3.0 / 16.0 : 3.0 / (8.0 * n);
                r = (1.0 - n * beta) * p[k] + beta * sum[3 * v + k];
            } /* corners and non-manifold vertices stay put */
            o[k] = (float)r;
        }
    }
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *v = in->indices + 3 * t;
        uint32_t ab = (uint32_t)(nv + tri_edge[3 * t]), bc = (uint32_t)(nv + tri_edge[3 * t + 1]),
                 ca = (uint32_t)(nv + tri_edge[3 * t + 2]);
        uint32_t q[12] = {v[0], ab, ca, v[1], bc, ab, v[2], ca, bc, ab, bc, ca};
        memcpy(out->indices + 12 * t, q, sizeof q);
    }
done:
    edges_free(&et);
    free(e_far);
    free(e_faces);
    free(e_ends);
    free(tri_edge);
    free(sum);
    free(bsum);
    free(valence);
    free(bcount);
    return ok;
}

bool lanes_mesh_decimate(const lanes_mesh *in, int cells, lanes_mesh *out, lanes_error *err)
{
    memset(out, 0, sizeof *out);
    if (cells < 1 || cells > 4096) {
        lanes_error_set(err, "decimation: %d cells out of range [1, 4096]", cells);
        return false;
    }
    float mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < in->vertex_count; v++)
        for (int a = 0; a < 3; a++) {
            mn[a] = fminf(mn[a], in->positions[3 * v + a]);
            mx[a] = fmaxf(mx[a], in->positions[3 * v + a]);
        }
    double ext = 0.0;
    for (int a = 0; a < 3; a++)
        ext = fmax(ext, (double)mx[a] - mn[a]);
    double cell = ext > 0.0 ? ext / cells : 1.0;
    size_t nv = in->vertex_count;
    uint32_t *cluster = malloc((nv ? nv : 1) * sizeof *cluster);
    double *acc = calloc(4 * (nv ? nv : 1), sizeof *acc);
    edge_table cells_of = {0}; /* a cell key packs three 21-bit coordinates into (a, b) */
    bool ok = cluster && acc && edges_init(&cells_of, nv);
    size_t nc = 0;
    if (ok) {
        for (size_t v = 0; v < nv; v++) {
            uint32_t c[3];
            for (int a = 0; a < 3; a++) {
                double q = floor((in->positions[3 * v + a] - mn[a]) / cell);
                c[a] = (uint32_t)fmin(fmax(q, 0.0), (double)cells);
            }
            bool found;
            size_t s = edges_slot(&cells_of, c[0], (c[1] << 13) | c[2], &found);
            if (!found)
                cells_of.vals[s] = (uint32_t)nc++;
            uint32_t k = cells_of.vals[s];
            cluster[v] = k;
            for (int a = 0; a < 3; a++)
                acc[4 * k + a] += in->positions[3 * v + a];
            acc[4 * k + 3] += 1.0;
        }
        out->positions = malloc((nc ? nc : 1) * 3 * sizeof(float));
        out->indices = malloc((in->triangle_count ? in->triangle_count : 1) * 3 * sizeof(uint32_t));
        ok = out->positions && out->indices;
    }
    if (ok) {
        for (size_t k = 0; k < nc; k++)
            for (int a = 0; a < 3; a++)
                out->positions[3 * k + a] = (float)(acc[4 * k + a] / acc[4 * k + 3]);
        out->vertex_count = nc;
        size_t nt = 0;
        for (size_t t = 0; t < in->triangle_count; t++) {
            uint32_t a = cluster[in->indices[3 * t]], b = cluster[in->indices[3 * t + 1]],
                     c = cluster[in->indices[3 * t + 2]];
            if (a == b || b == c || a == c)
                continue;
            uint32_t *o = out->indices + 3 * nt++;
            o[0] = a;
            o[1] = b;
            o[2] = c;
        }
        out->triangle_count = nt;
    } else {
        lanes_mesh_free(out);
        lanes_error_set(err, "decimation: out of memory");
    }
    free(cluster);
    free(acc);
    edges_free(&cells_of);
    return ok;
}

void lanes_mesh_normalizing_xform(const lanes_mesh *m, lanes_xform *out)
{
    double mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < m->vertex_count; v++)
        for (int a = 0; a < 3; a++) {
            mn[a] = fmin(mn[a], m->positions[3 * v + a]);
            mx[a] = fmax(mx[a], m->positions[3 * v + a]);
        }
    double ext = 0.0;
    for (int a = 0; a < 3; a++)
        ext = fmax(ext, mx[a] - mn[a]);
    double s = ext > 0.0 ? 1.0 / ext : 1.0;
    lanes_xform_identity(out);
    if (m->vertex_count == 0)
        return;
    for (int a = 0; a < 3; a++)
        out->m[a][a] = s;
    out->m[0][3] = -s * 0.5 * (mn[0] + mx[0]);
    out->m[1][3] = -s * mn[1];
    out->m[2][3] = -s * 0.5 * (mn[2] + mx[2]);
}

/* ---- primitives ---- */

static bool make_icosphere(int level, lanes_mesh *out, lanes_error *err)
{
    builder b = {0};
    const double t = (1.0 + sqrt(5.0)) / 2.0;
    const double v[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                             {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                             {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    static const uint32_t f[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                      {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                      {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                      {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (int i = 0; i < 12; i++) {
        double p[3] = {v[i][0], v[i][1], v[i][2]};
        normalize3(p);
        bvert(&b, p[0], p[1], p[2]);
    }
    for (int i = 0; i < 20; i++)
        btri(&b, f[i][0], f[i][1], f[i][2]);
    if (!bfinish(&b, out, "sphere", err))
        return false;
    for (int l = 0; l < level; l++) {
        /* Midpoint split pushed back onto the sphere. */
        lanes_mesh fine;
        if (!lanes_mesh_subdivide(out, &fine, err)) {
            lanes_mesh_free(out);
            return false;
        }
        size_t nv0 = out->vertex_count;
        for (size_t t2 = 0; t2 < out->triangle_count; t2++) {
            const uint32_t *tri = out->indices + 3 * t2;
            const uint32_t *q = fine.indices + 12 * t2;
            /* q[1] = ab, q[4] = bc, q[2] = ca: the new vertices. */
            const uint32_t ends[3][3] = {
                {q[1], tri[0], tri[1]}, {q[4], tri[1], tri[2]}, {q[2], tri[2], tri[0]}};
            for (int k = 0; k < 3; k++) {
                double p[3];
                for (int a = 0; a < 3; a++)
                    p[a] = 0.5 * ((double)out->positions[3 * ends[k][1] + a] +
                                  out->positions[3 * ends[k][2] + a]);
                normalize3(p);
                for (int a = 0; a < 3; a++)
                    fine.positions[3 * ends[k][0] + a] = (float)p[a];
            }
        }
        memcpy(fine.positions, out->positions, nv0 * 3 * sizeof(float));
        lanes_mesh_free(out);
        *out = fine;
    }
    return true;
}

/* Axis-aligned box [lo, hi], faces outward. */
static void add_box(builder *b, const double lo[3], const double hi[3])
{
    uint32_t v[8];
    for (int i = 0; i < 8; i++)
        v[i] = bvert(b, i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]);
    bquad(b, v[0], v[4], v[6], v[2]); /* -x */
    bquad(b, v[1], v[3], v[7], v[5]); /* +x */
    bquad(b, v[0], v[1], v[5], v[4]); /* -y */
    bquad(b, v[2], v[6], v[7], v[3]); /* +y */
    bquad(b, v[0], v[2], v[3], v[1]); /* -z */
    bquad(b, v[4], v[5], v[7], v[6]); /* +z */
}

/* Grid over [x0, x1] x [z0, z1] (x0 < x1, z0 < z1) at height y, facing +y. */
static void add_grid(builder *b, double x0, double z0, double x1, double z1, double y, int nx,
                     int nz)
{
    uint32_t base = (uint32_t)b->m.vertex_count;
    for (int j = 0; j <= nz; j++)
        for (int i = 0; i <= nx; i++)
            bvert(b, x0 + (x1 - x0) * i / nx, y, z0 + (z1 - z0) * j / nz);
    for (int j = 0; j < nz; j++)
        for (int i = 0; i < nx; i++) {
            uint32_t a = base + (uint32_t)(j * (nx + 1) + i);
            bquad(b, a, a + (uint32_t)(nx + 1), a + (uint32_t)(nx + 2), a + 1);
        }
}

/* Surface of revolution about the y axis through (cx, cz): profile points
 * (radius, y) from bottom to top, `seg` segments around, open ends. */
static void add_lathe(builder *b, double cx, double cz, const double (*prof)[2], int np, int seg)
{
    uint32_t base = (uint32_t)b->m.vertex_count;
    for (int j = 0; j < np; j++)
        for (int i = 0; i < seg; i++) {
            double a = 2.0 * PI * i / seg;
            bvert(b, cx + prof[j][0] * cos(a), prof[j][1], cz - prof[j][0] * sin(a));
        }
    for (int j = 0; j + 1 < np; j++)
        for (int i = 0; i < seg; i++) {
            uint32_t a = base + (uint32_t)(j * seg + i),
                     c = base + (uint32_t)(j * seg + (i + 1) % seg);
            bquad(b, a, c, c + (uint32_t)seg, a + (uint32_t)seg);
        }
}

static void add_cylinder(builder *b, int seg)
{
    const double prof[2][2] = {{1.0, -1.0}, {1.0, 1.0}};
    uint32_t base = (uint32_t)b->m.vertex_count;
    add_lathe(b, 0.0, 0.0, prof, 2, seg);
    uint32_t bot = bvert(b, 0, -1, 0), top = bvert(b, 0, 1, 0);
    for (int i = 0; i < seg; i++) {
        uint32_t a = base + (uint32_t)i, c = base + (uint32_t)((i + 1) % seg);
        btri(b, bot, c, a);
        btri(b, top, a + (uint32_t)seg, c + (uint32_t)seg);
    }
}

/* ---- the CGAL meshes ---- */

static const struct {
    const char *name, *file;
    double yaw; /* degrees about +y so the model faces +z */
} cgal_meshes[] = {
    {"bunny", "bunny00.off", 90.0},
    {"dragon", "ChineseDragon-10kv.off", 0.0},
    {"armadillo", "armadillo.off", 180.0},
    {"elephant", "elephant.off", 0.0},
};
#define N_CGAL (sizeof cgal_meshes / sizeof cgal_meshes[0])

const char *lanes_mesh_dir(void)
{
    const char *e = getenv("LANES_MESH_DIR");
    return e && *e ? e : LANES_DEFAULT_MESH_DIR;
}

static bool mesh_path(const char *file, char *out, size_t n)
{
    int k = snprintf(out, n, "%s/%s", lanes_mesh_dir(), file);
    return k > 0 && (size_t)k < n;
}

bool lanes_builtin_meshes_available(void)
{
    for (size_t i = 0; i < N_CGAL; i++) {
        char p[4096];
        struct stat st;
        if (!mesh_path(cgal_meshes[i].file, p, sizeof p) || stat(p, &st) != 0)
            return false;
    }
    return true;
}

static bool load_cgal(size_t which, int subdiv, lanes_mesh *out, lanes_error *err)
{
    char path[4096];
    struct stat st;
    if (!mesh_path(cgal_meshes[which].file, path, sizeof path)) {
        lanes_error_set(err, "%s: mesh directory path too long", cgal_meshes[which].name);
        return false;
    }
    if (stat(path, &st) != 0) {
        lanes_error_set(err,
                        "%s: mesh file %s not found: run cmake/fetch_meshes.sh (or set "
                        "LANES_MESH_DIR to where it put the meshes)",
                        cgal_meshes[which].name, path);
        return false;
    }
    lanes_mesh m;
    if (!lanes_mesh_read(path, &m, err))
        return false;
    for (int i = 0; i < subdiv; i++) {
        lanes_mesh fine;
        bool ok = lanes_mesh_subdivide(&m, &fine, err);
        lanes_mesh_free(&m);
        if (!ok)
            return false;
        m = fine;
    }
    lanes_xform rot, norm, x;
    const double up[3] = {0, 1, 0};
    lanes_xform_rotation(&rot, up, cgal_meshes[which].yaw);
    for (size_t v = 0; v < m.vertex_count; v++)
        lanes_xform_apply(&rot, m.positions + 3 * v, m.positions + 3 * v);
    lanes_mesh_normalizing_xform(&m, &norm);
    x = norm;
    for (size_t v = 0; v < m.vertex_count; v++)
        lanes_xform_apply(&x, m.positions + 3 * v, m.positions + 3 * v);
    *out = m;
    return true;
}

static const char *const primitive_names[] = {"sphere", "box", "plane", "cylinder"};

const char *lanes_builtin_object_names(void)
{
    return "sphere, box, plane, cylinder, bunny, dragon, armadillo, elephant";
}

bool lanes_builtin_object(const char *name, int detail, lanes_mesh *out, lanes_error *err)
{
    memset(out, 0, sizeof *out);
    for (size_t i = 0; i < N_CGAL; i++) {
        if (strcmp(name, cgal_meshes[i].name) == 0) {
            if (detail > 4) {
                lanes_error_set(err, "%s: detail %d: at most 4 subdivision steps", name, detail);
                return false;
            }
            return load_cgal(i, detail < 0 ? 0 : detail, out, err);
        }
    }
    builder b = {0};
    if (strcmp(name, primitive_names[0]) == 0) {
        if (detail > 8) {
            lanes_error_set(err, "sphere: detail %d: at most 8", detail);
            return false;
        }
        return make_icosphere(detail < 0 ? 3 : detail, out, err);
    } else if (strcmp(name, primitive_names[1]) == 0) {
        const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
        add_box(&b, lo, hi);
    } else if (strcmp(name, primitive_names[2]) == 0) {
        int n = detail < 1 ? 1 : detail;
        if (n > 4096) {
            lanes_error_set(err, "plane: detail %d: at most 4096 cells a side", detail);
            return false;
        }
        add_grid(&b, -1, -1, 1, 1, 0, n, n);
    } else if (strcmp(name, primitive_names[3]) == 0) {
        int seg = detail < 3 ? 32 : detail;
        if (seg > 1 << 20) {
            lanes_error_set(err, "cylinder: detail %d: too many segments", detail);
            return false;
        }
        add_cylinder(&b, seg);
    } else {
        lanes_error_set(err, "unknown built-in object '%s' (valid: %s)", name,
                        lanes_builtin_object_names());
        return false;
    }
    return bfinish(&b, out, name, err);
}

/* ---- scene assembly helpers ---- */

static bool add_mat(lanes_scene *s, const char *name, lanes_material_kind kind, double r, double g,
                    double bl, uint32_t *idx, lanes_error *err)
{
    lanes_material m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "%s", name);
    m.kind = kind;
    m.ior = 1.5f;
    float c[3] = {(float)r, (float)g, (float)bl};
    if (kind == LANES_MAT_EMISSIVE)
        memcpy(m.emission, c, sizeof c);
    else
        memcpy(m.color, c, sizeof c);
    return lanes_scene_add_material(s, &m, idx, err);
}

static bool add_point(lanes_scene *s, double x, double y, double z, double i, lanes_error *err)
{
    lanes_point_light l = {{(float)x, (float)y, (float)z}, {(float)i, (float)i, (float)i}};
    return lanes_scene_add_point_light(s, &l, err);
}

static void set_camera(lanes_scene *s, double ex, double ey, double ez, double tx, double ty,
                       double tz, double fov)
{
    lanes_camera *c = &s->camera;
    c->eye[0] = (float)ex;
    c->eye[1] = (float)ey;
    c->eye[2] = (float)ez;
    c->target[0] = (float)tx;
    c->target[1] = (float)ty;
    c->target[2] = (float)tz;
    c->up[0] = 0.0f;
    c->up[1] = 1.0f;
    c->up[2] = 0.0f;
    c->fov_y_degrees = (float)fov;
    c->width = 512; /* the thesis rendered every scene at 512x512 */
    c->height = 512;
}

/* Places a mesh: scale, then rotate about +y, then translate. */
static bool place(lanes_scene *s, const lanes_mesh *m, double scale, double yaw, double x, double y,
                  double z, uint32_t mat, const char *what, lanes_error *err)
{
    lanes_xform r, x3;
    const double up[3] = {0, 1, 0}, t[3] = {x, y, z}, sc[3] = {scale, scale, scale};
    lanes_xform_rotation(&r, up, yaw);
    lanes_xform_trs(&x3, t, &r, sc);
    return lanes_scene_add_mesh(s, m, &x3, mat, what, err);
}

static bool add_builder(lanes_scene *s, builder *b, uint32_t mat, const char *what,
                        lanes_error *err)
{
    lanes_mesh m;
    if (!bfinish(b, &m, what, err))
        return false;
    bool ok = lanes_scene_add_mesh(s, &m, NULL, mat, what, err);
    lanes_mesh_free(&m);
    return ok;
}

bool lanes_scene_add_area_light_quad(lanes_scene *s, const lanes_area_light *l, bool visible,
                                     lanes_error *err)
{
    if (!lanes_scene_add_area_light(s, l, err))
        return false;
    if (!visible)
        return true;
    lanes_material m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "@area_light_%zu", s->area_light_count - 1);
    m.kind = LANES_MAT_EMISSIVE;
    m.ior = 1.0f;
    memcpy(m.emission, l->emission, sizeof m.emission);
    uint32_t mi;
    if (!lanes_scene_add_material(s, &m, &mi, err))
        return false;
    float p[4][3];
    for (int a = 0; a < 3; a++) {
        p[0][a] = l->corner[a];
        p[1][a] = l->corner[a] + l->edge_u[a];
        p[2][a] = l->corner[a] + l->edge_u[a] + l->edge_v[a];
        p[3][a] = l->corner[a] + l->edge_v[a];
    }
    /* Both triangles wind so their normal is edge_u x edge_v, the side the
     * light emits on. */
    float t0[9], t1[9];
    memcpy(t0, p[0], 12);
    memcpy(t0 + 3, p[1], 12);
    memcpy(t0 + 6, p[2], 12);
    memcpy(t1, p[0], 12);
    memcpy(t1 + 3, p[2], 12);
    memcpy(t1 + 6, p[3], 12);
    return lanes_scene_add_triangle(s, t0, mi, err) && lanes_scene_add_triangle(s, t1, mi, err);
}

/* ---- default: a Cornell-like room, no download needed ---- */

static bool scene_default(lanes_scene *s, lanes_error *err)
{
    uint32_t white, red, green, mirror, glass;
    if (!add_mat(s, "white", LANES_MAT_DIFFUSE, 0.73, 0.73, 0.73, &white, err) ||
        !add_mat(s, "red", LANES_MAT_DIFFUSE, 0.63, 0.065, 0.05, &red, err) ||
        !add_mat(s, "green", LANES_MAT_DIFFUSE, 0.14, 0.45, 0.091, &green, err) ||
        !add_mat(s, "mirror", LANES_MAT_MIRROR, 0.95, 0.95, 0.95, &mirror, err) ||
        !add_mat(s, "glass", LANES_MAT_GLASS, 1.0, 1.0, 1.0, &glass, err))
        return false;
    s->materials[glass].ior = 1.5f;
    /* Room x in [-1, 1], y in [0, 2], z in [-1, 1], open towards +z. */
    builder room = {0}, left = {0}, right = {0};
    uint32_t v[8];
    for (int i = 0; i < 8; i++)
        v[i] = bvert(&room, i & 1 ? 1 : -1, i & 2 ? 2 : 0, i & 4 ? 1 : -1);
    bquad(&room, v[0], v[4], v[5], v[1]); /* floor, facing up */
    bquad(&room, v[2], v[3], v[7], v[6]); /* ceiling, facing down */
    bquad(&room, v[0], v[1], v[3], v[2]); /* back wall, facing +z */
    /* Side walls face into the room. */
    uint32_t a = bvert(&left, -1, 0, -1), b = bvert(&left, -1, 0, 1), c = bvert(&left, -1, 2, 1),
             d = bvert(&left, -1, 2, -1);
    bquad(&left, a, d, c, b);
    a = bvert(&right, 1, 0, -1);
    b = bvert(&right, 1, 2, -1);
    c = bvert(&right, 1, 2, 1);
    d = bvert(&right, 1, 0, 1);
    bquad(&right, a, d, c, b);
    bool ok = add_builder(s, &room, white, "default room", err) &&
              add_builder(s, &left, red, "default room", err) &&
              add_builder(s, &right, green, "default room", err);
    lanes_mesh_free(&room.m);
    lanes_mesh_free(&left.m);
    lanes_mesh_free(&right.m);
    if (!ok)
        return false;
    /* A tall box, turned. */
    builder box = {0};
    const double lo[3] = {-1, 0, -1}, hi[3] = {1, 1, 1};
    add_box(&box, lo, hi);
    lanes_mesh boxm, sph;
    if (!bfinish(&box, &boxm, "box", err))
        return false;
    lanes_xform r, x;
    const double up[3] = {0, 1, 0}, t[3] = {-0.38, 0, -0.3}, sc[3] = {0.28, 1.2, 0.28};
    lanes_xform_rotation(&r, up, 20.0);
    lanes_xform_trs(&x, t, &r, sc);
    ok = lanes_scene_add_mesh(s, &boxm, &x, white, "default box", err);
    lanes_mesh_free(&boxm);
    if (!ok || !make_icosphere(3, &sph, err))
        return false;
    ok = place(s, &sph, 0.3, 0, 0.45, 0.3, -0.1, mirror, "default sphere", err) &&
         place(s, &sph, 0.3, 0, -0.25, 0.3, 0.5, glass, "default sphere", err);
    lanes_mesh_free(&sph);
    if (!ok)
        return false;
    lanes_area_light al = {{-0.25f, 1.98f, -0.2f}, {0.5f, 0, 0}, {0, 0, 0.4f}, {8, 7, 5.5f}};
    /* edge_u x edge_v = (0.5,0,0) x (0,0,0.4) = (0,-0.2,0): emits downward. */
    if (!lanes_scene_add_area_light_quad(s, &al, true, err) ||
        !add_point(s, 0.0, 1.6, 0.7, 1.2, err))
        return false;
    set_camera(s, 0.0, 1.0, 3.9, 0.0, 1.0, 0.0, 38.0);
    return true;
}

/* ---- dragon: the thesis' fully diffuse scene ---- */

static bool ground(lanes_scene *s, double half, uint32_t mat, lanes_error *err)
{
    builder b = {0};
    add_grid(&b, -half, -half, half, half, 0.0, 1, 1);
    return add_builder(s, &b, mat, "ground", err);
}

static bool scene_dragon(lanes_scene *s, lanes_error *err)
{
    uint32_t stone, floor;
    if (!add_mat(s, "dragon", LANES_MAT_DIFFUSE, 0.75, 0.62, 0.42, &stone, err) ||
        !add_mat(s, "ground", LANES_MAT_DIFFUSE, 0.5, 0.5, 0.55, &floor, err))
        return false;
    lanes_mesh d;
    /* CGAL's dragon has 19,994 triangles; one Loop step gives 79,976, near
     * the thesis' 100K, and keeps the surface smooth. */
    if (!lanes_builtin_object("dragon", 1, &d, err))
        return false;
    bool ok = place(s, &d, 2.0, -25.0, 0, 0, 0, stone, "dragon", err);
    lanes_mesh_free(&d);
    if (!ok || !ground(s, 1.5, floor, err) || !add_point(s, 2.5, 4.5, 3.5, 30.0, err))
        return false;
    set_camera(s, 2.2, 1.9, 4.2, 0.0, 0.9, 0.0, 36.0);
    return true;
}

/* ---- sponza-bunny: a procedural atrium with a mirror bunny ---- */

/* Atrium dimensions (meters): courtyard x in [-AX, AX], z in [-AZ, AZ],
 * bays of BAY between column centers, galleries GAL deep behind the
 * arcades, two stories. */
#define AX 13.5
#define AZ 4.5
#define BAY 3.0
#define GAL 3.0
#define ARCH_SEG 24
#define COL_SEG 24
#define COL_ROWS 16

/* A column at (x, z) from y0 to y1: base block, a shaft with entasis and
 * a capital block. */
static void add_column(builder *b, double x, double z, double y0, double y1, double r)
{
    double base_h = 0.22, cap_h = 0.2;
    const double blo[3] = {x - 1.35 * r, y0, z - 1.35 * r},
                 bhi[3] = {x + 1.35 * r, y0 + base_h, z + 1.35 * r};
    add_box(b, blo, bhi);
    const double clo[3] = {x - 1.3 * r, y1 - cap_h, z - 1.3 * r},
                 chi[3] = {x + 1.3 * r, y1, z + 1.3 * r};
    add_box(b, clo, chi);
    double prof[COL_ROWS + 1][2];
    for (int j = 0; j <= COL_ROWS; j++) {
        double u = (double)j / COL_ROWS;
        prof[j][0] = r * (1.0 - 0.12 * u * u + 0.04 * sin(PI * u));
        prof[j][1] = y0 + base_h + u * (y1 - cap_h - y0 - base_h);
    }
    add_lathe(b, x, z, (const double(*)[2])prof, COL_ROWS + 1, COL_SEG);
}

/* One bay of an arcade wall along the local u axis: from column center u0
 * to u1 (at wall coordinate w, thickness th, normal along the other
 * horizontal axis), a semicircular opening springing at y0 and the wall up
 * to y1. `along_x` chooses the orientation. */
static void add_arch_bay(builder *b, bool along_x, double w, double u0, double u1, double y0,
                         double y1, double th, double pier)
{
    double um = 0.5 * (u0 + u1), R = 0.5 * (u1 - u0) - pier;
#define P(u, y, ww) (along_x ? bvert(b, (u), (y), (ww)) : bvert(b, (ww), (y), (u)))
    for (int side = 0; side < 2; side++) {
        double ww = w + (side ? 0.5 : -0.5) * th;
        /* Vertical strips from the intrados up to the top of the wall, plus
         * the solid piers over the capitals. */
        uint32_t prev_a = 0, prev_t = 0;
        for (int i = 0; i <= ARCH_SEG; i++) {
            double ang = PI * (1.0 - (double)i / ARCH_SEG);
            double u = um + R * cos(ang), y = y0 + R * sin(ang);
            uint32_t a = P(u, y, ww), t = P(u, y1, ww);
            if (i > 0) {
                if (side ^ !along_x)
                    bquad(b, prev_a, a, t, prev_t);
                else
                    bquad(b, prev_a, prev_t, t, a);
            }
            prev_a = a;
            prev_t = t;
        }
        for (int k = 0; k < 2; k++) {
            double ua = k ? um + R : u0, ub = k ? u1 : um - R;
            uint32_t p0 = P(ua, y0, ww), p1 = P(ub, y0, ww), p2 = P(ub, y1, ww), p3 = P(ua, y1, ww);
            if (side ^ !along_x)
                bquad(b, p0, p1, p2, p3);
            else
                bquad(b, p0, p3, p2, p1);
        }
    }
    /* The intrados: the curved underside of the arch. */
    uint32_t pa = 0, pb = 0;
    for (int i = 0; i <= ARCH_SEG; i++) {
        double ang = PI * (1.0 - (double)i / ARCH_SEG);
        double u = um + R * cos(ang), y = y0 + R * sin(ang);
        uint32_t a = P(u, y, w - 0.5 * th), c = P(u, y, w + 0.5 * th);
        if (i > 0) {
            if (along_x)
                bquad(b, pa, pb, c, a);
            else
                bquad(b, pa, a, c, pb);
        }
        pa = a;
        pb = c;
    }
#undef P
}

/* A banner hanging in an upper arch: a cloth grid with soft folds. */
static void add_banner(builder *b, double x, double z, double y_top, double width, double height,
                       double facing)
{
    const int nu = 16, nv = 24;
    uint32_t base = (uint32_t)b->m.vertex_count;
    for (int j = 0; j <= nv; j++)
        for (int i = 0; i <= nu; i++) {
            double u = (double)i / nu, v = (double)j / nv;
            double fold = 0.08 * sin(6.0 * PI * u) * (0.3 + v) + 0.25 * v * v;
            bvert(b, x + (u - 0.5) * width, y_top - v * height, z + facing * fold);
        }
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            uint32_t a = base + (uint32_t)(j * (nu + 1) + i);
            bquad(b, a, a + 1, a + (uint32_t)(nu + 2), a + (uint32_t)(nu + 1));
        }
}

static bool scene_sponza(lanes_scene *s, lanes_error *err)
{
    uint32_t stone, floor, cloth[3], mirror;
    if (!add_mat(s, "stone", LANES_MAT_DIFFUSE, 0.78, 0.72, 0.6, &stone, err) ||
        !add_mat(s, "floor", LANES_MAT_DIFFUSE, 0.55, 0.5, 0.45, &floor, err) ||
        !add_mat(s, "cloth-red", LANES_MAT_DIFFUSE, 0.6, 0.1, 0.08, &cloth[0], err) ||
        !add_mat(s, "cloth-green", LANES_MAT_DIFFUSE, 0.1, 0.4, 0.15, &cloth[1], err) ||
        !add_mat(s, "cloth-blue", LANES_MAT_DIFFUSE, 0.1, 0.15, 0.5, &cloth[2], err) ||
        !add_mat(s, "mirror", LANES_MAT_MIRROR, 0.9, 0.9, 0.9, &mirror, err))
        return false;
    builder st = {0}, fl = {0}, cl[3];
    memset(cl, 0, sizeof cl);
    const double story_y[3] = {0.0, 4.8, 9.6}; /* floor of each story; roof at 13.2 */
    const double col_r[2] = {0.3, 0.24}, spring[2] = {3.0, 7.6};
    /* Floors: courtyard + galleries, and the upper gallery floor. */
    add_grid(&fl, -AX - GAL, -AZ - GAL, AX + GAL, AZ + GAL, 0.0, 24, 10);
    for (int sgn = -1; sgn <= 1; sgn += 2) {
        /* Upper gallery floor slabs (both faces) along the long sides. */
        double z0 = sgn * AZ, z1 = sgn * (AZ + GAL);
        double lo[3] = {-AX - GAL, story_y[1] - 0.3, fmin(z0, z1)},
               hi[3] = {AX + GAL, story_y[1], fmax(z0, z1)};
        add_box(&st, lo, hi);
        double lo2[3] = {-AX - GAL, story_y[2] - 0.3, fmin(z0, z1)},
               hi2[3] = {AX + GAL, story_y[2], fmax(z0, z1)};
        add_box(&st, lo2, hi2);
        /* Short sides. */
        double x0 = sgn * AX, x1 = sgn * (AX + GAL);
        double lo3[3] = {fmin(x0, x1), story_y[1] - 0.3, -AZ},
               hi3[3] = {fmax(x0, x1), story_y[1], AZ};
        add_box(&st, lo3, hi3);
        double lo4[3] = {fmin(x0, x1), story_y[2] - 0.3, -AZ},
               hi4[3] = {fmax(x0, x1), story_y[2], AZ};
        add_box(&st, lo4, hi4);
        /* Outer walls, full height. */
        double lo5[3] = {-AX - GAL - 0.4, 0, sgn > 0 ? AZ + GAL : -AZ - GAL - 0.4},
               hi5[3] = {AX + GAL + 0.4, 13.2, sgn > 0 ? AZ + GAL + 0.4 : -AZ - GAL};
        add_box(&st, lo5, hi5);
        double lo6[3] = {sgn > 0 ? AX + GAL : -AX - GAL - 0.4, 0, -AZ - GAL},
               hi6[3] = {sgn > 0 ? AX + GAL + 0.4 : -AX - GAL, 13.2, AZ + GAL};
        add_box(&st, lo6, hi6);
        /* Top story: a solid wall with a cornice over the arcades. */
        double lo7[3] = {-AX - 0.3, story_y[2], sgn * AZ - 0.3},
               hi7[3] = {AX + 0.3, 13.2, sgn * AZ + 0.3};
        add_box(&st, lo7, hi7);
        double lo8[3] = {sgn * AX - 0.3, story_y[2], -AZ}, hi8[3] = {sgn * AX + 0.3, 13.2, AZ};
        add_box(&st, lo8, hi8);
        double lo9[3] = {-AX - GAL, 13.2, fmin(sgn * (AZ - 0.6), sgn * (AZ + GAL))},
               hi9[3] = {AX + GAL, 13.5, fmax(sgn * (AZ - 0.6), sgn * (AZ + GAL))};
        add_box(&st, lo9, hi9);
    }
    for (int story = 0; story < 2; story++) {
        double y0 = story_y[story], r = col_r[story], ys = spring[story];
        double ytop = story_y[story + 1];
        int nx = (int)(2 * AX / BAY + 0.5), nz = (int)(2 * AZ / BAY + 0.5);
        for (int sgn = -1; sgn <= 1; sgn += 2) {
            for (int i = 0; i <= nx; i++)
                add_column(&st, -AX + BAY * i, sgn * AZ, y0, ys, r);
            for (int j = 1; j < nz; j++)
                add_column(&st, sgn * AX, -AZ + BAY * j, y0, ys, r);
            for (int i = 0; i < nx; i++)
                add_arch_bay(&st, true, sgn * AZ, -AX + BAY * i, -AX + BAY * (i + 1), ys, ytop, 0.6,
                             1.3 * r);
            for (int j = 0; j < nz; j++)
                add_arch_bay(&st, false, sgn * AX, -AZ + BAY * j, -AZ + BAY * (j + 1), ys, ytop,
                             0.6, 1.3 * r);
            /* Banners in the upper arches of the long sides, hung just
             * inside the courtyard, colors cycling. */
            if (story == 1)
                for (int i = 0; i < nx; i++)
                    add_banner(&cl[(i + (sgn > 0)) % 3], -AX + BAY * (i + 0.5), sgn * (AZ - 0.45),
                               ys + 0.9, 1.7, 3.2, -sgn);
        }
    }
    bool ok = add_builder(s, &fl, floor, "atrium floor", err) &&
              add_builder(s, &st, stone, "atrium", err);
    for (int k = 0; k < 3; k++)
        ok = ok && add_builder(s, &cl[k], cloth[k], "atrium banners", err);
    lanes_mesh_free(&fl.m);
    lanes_mesh_free(&st.m);
    for (int k = 0; k < 3; k++)
        lanes_mesh_free(&cl[k].m);
    if (!ok)
        return false;
    lanes_mesh bunny;
    if (!lanes_builtin_object("bunny", 0, &bunny, err))
        return false;
    ok = place(s, &bunny, 5.0, -60.0, 0.0, 0.0, 0.0, mirror, "bunny", err);
    lanes_mesh_free(&bunny);
    if (!ok || !add_point(s, -6.0, 10.5, 0.5, 90.0, err) ||
        !add_point(s, 7.0, 8.0, -1.5, 60.0, err))
        return false;
    set_camera(s, -10.0, 2.6, 0.8, 0.0, 2.7, 0.0, 60.0);
    return true;
}

/* ---- 20 bunnies ---- */

static bool scene_bunnies(lanes_scene *s, bool small, lanes_error *err)
{
    uint32_t diffuse, mirror, floor;
    if (!add_mat(s, "bunny", LANES_MAT_DIFFUSE, 0.7, 0.65, 0.55, &diffuse, err) ||
        !add_mat(s, "mirror", LANES_MAT_MIRROR, 0.9, 0.9, 0.9, &mirror, err) ||
        !add_mat(s, "ground", LANES_MAT_DIFFUSE, 0.45, 0.5, 0.45, &floor, err))
        return false;
    lanes_mesh bunny;
    if (!lanes_builtin_object("bunny", 0, &bunny, err))
        return false;
    if (small) {
        /* 75,408 -> about 4K triangles each; the same layout as the full
         * scene, so it stands in for it in quick tests. */
        lanes_mesh coarse;
        bool ok = lanes_mesh_decimate(&bunny, 26, &coarse, err);
        lanes_mesh_free(&bunny);
        if (!ok)
            return false;
        bunny = coarse;
    }
    /* The thesis spreads its 20 bunnies over a triangle: rejection-sample
     * positions in the triangle (-9,5) (9,5) (0,-12) of the xz plane with a
     * minimum spacing, a random turn each, and a shuffled half of them
     * mirrors, so the specular ones are scattered, not grouped. */
    pcg32 rng;
    pcg32_seed(&rng, 20140101u, 20u);
    double pos[20][2];
    int n = 0, tries = 0;
    const double A[2] = {-9, 5}, B[2] = {9, 5}, C[2] = {0, -12};
    while (n < 20) {
        double u = rnd(&rng), v = rnd(&rng);
        if (u + v > 1.0) {
            u = 1.0 - u;
            v = 1.0 - v;
        }
        double x = A[0] + u * (B[0] - A[0]) + v * (C[0] - A[0]);
        double z = A[1] + u * (B[1] - A[1]) + v * (C[1] - A[1]);
        bool far_enough = true;
        double min_d = ++tries < 100000 ? 2.6 : 1.8;
        for (int k = 0; k < n; k++) {
            double dx = pos[k][0] - x, dz = pos[k][1] - z;
            far_enough = far_enough && dx * dx + dz * dz >= min_d * min_d;
        }
        if (far_enough) {
            pos[n][0] = x;
            pos[n][1] = z;
            n++;
        }
    }
    int is_mirror[20];
    for (int i = 0; i < 20; i++)
        is_mirror[i] = i < 10;
    for (int i = 19; i > 0; i--) {
        int j = (int)(pcg32_next(&rng) % (uint32_t)(i + 1));
        int t = is_mirror[i];
        is_mirror[i] = is_mirror[j];
        is_mirror[j] = t;
    }
    bool ok = true;
    for (int i = 0; i < 20 && ok; i++) {
        double yaw = 360.0 * rnd(&rng);
        ok = place(s, &bunny, 2.4, yaw, pos[i][0], 0.0, pos[i][1], is_mirror[i] ? mirror : diffuse,
                   "bunny", err);
    }
    lanes_mesh_free(&bunny);
    if (!ok)
        return false;
    /* The ground: the triangle itself, enlarged around its centroid. */
    float g[9];
    const double cx = (A[0] + B[0] + C[0]) / 3.0, cz = (A[1] + B[1] + C[1]) / 3.0;
    const double *corner[3] = {A, B, C};
    for (int k = 0; k < 3; k++) {
        g[3 * k] = (float)(cx + 1.6 * (corner[k][0] - cx));
        g[3 * k + 1] = 0.0f;
        g[3 * k + 2] = (float)(cz + 1.6 * (corner[k][1] - cz));
    }
    /* A, B, C runs clockwise seen from above; swap to face +y. */
    float t3[3];
    memcpy(t3, g + 3, sizeof t3);
    memcpy(g + 3, g + 6, sizeof t3);
    memcpy(g + 6, t3, sizeof t3);
    if (!lanes_scene_add_triangle(s, g, floor, err) || !add_point(s, 5.0, 14.0, 8.0, 260.0, err))
        return false;
    set_camera(s, 0.0, 8.0, 13.5, 0.0, 0.4, -3.2, 50.0);
    return true;
}

/* ---- hairball ---- */

/* Thin tubes (triangular cross-section) along smooth random curves inside
 * the unit sphere, all mirror. Curves: a unit-speed walk whose direction
 * turns by a slowly varying curvature vector; near the sphere it is
 * steered back inside. Tubes follow parallel-transport frames so they do
 * not twist. */
#define HAIR_SIDES 3
#define HAIR_SEGMENTS 320

static bool scene_hairball(lanes_scene *s, bool small, lanes_error *err)
{
    uint32_t mirror;
    if (!add_mat(s, "hair", LANES_MAT_MIRROR, 0.85, 0.8, 0.7, &mirror, err))
        return false;
    const int curves = small ? 50 : 1500;
    const double radius = 0.006, step = 0.012;
    size_t tris = (size_t)curves * HAIR_SEGMENTS * HAIR_SIDES * 2;
    if (!lanes_scene_reserve_triangles(s, tris, err))
        return false;
    pcg32 rng;
    pcg32_seed(&rng, 0x4a1eba11u, 7u);
    float ring[2][HAIR_SIDES][3];
    double ring_cos[HAIR_SIDES], ring_sin[HAIR_SIDES];
    for (int j = 0; j < HAIR_SIDES; j++) {
        ring_cos[j] = cos(2.0 * PI * j / HAIR_SIDES);
        ring_sin[j] = sin(2.0 * PI * j / HAIR_SIDES);
    }
    float *out = s->verts + 9 * s->triangle_count;
    for (int c = 0; c < curves; c++) {
        double p[3], d[3], k[3] = {0, 0, 0}, n[3], bnorm[3];
        rnd_ball(&rng, p);
        for (int a = 0; a < 3; a++)
            p[a] *= 0.9;
        do
            rnd_ball(&rng, d);
        while (dot3(d, d) < 1e-4);
        normalize3(d);
        /* Any vector not parallel to d starts the frame. */
        double helper[3] = {fabs(d[0]) < 0.9 ? 1.0 : 0.0, fabs(d[0]) < 0.9 ? 0.0 : 1.0, 0.0};
        cross3(d, helper, n);
        normalize3(n);
        cross3(d, n, bnorm);
        for (int i = 0; i <= HAIR_SEGMENTS; i++) {
            float(*r)[3] = ring[i & 1];
            for (int j = 0; j < HAIR_SIDES; j++) {
                for (int a = 0; a < 3; a++)
                    r[j][a] =
                        (float)(p[a] + radius * (ring_cos[j] * n[a] + ring_sin[j] * bnorm[a]));
            }
            if (i > 0) {
                float(*q)[3] = ring[(i - 1) & 1];
                for (int j = 0; j < HAIR_SIDES; j++) {
                    int j1 = (j + 1) % HAIR_SIDES;
                    const float *quad[4] = {q[j], q[j1], r[j1], r[j]};
                    memcpy(out + 0, quad[0], 12);
                    memcpy(out + 3, quad[1], 12);
                    memcpy(out + 6, quad[2], 12);
                    memcpy(out + 9, quad[0], 12);
                    memcpy(out + 12, quad[2], 12);
                    memcpy(out + 15, quad[3], 12);
                    out += 18;
                }
            }
            /* Advance: the curvature vector drifts, the direction turns by
             * it, and the walk is pulled back when it nears the surface. */
            for (int a = 0; a < 3; a++)
                k[a] = 0.94 * k[a] + 0.6 * (2.0 * rnd(&rng) - 1.0);
            double nd[3], rad = sqrt(dot3(p, p)), outward = rad > 0.0 ? dot3(p, d) / rad : 0.0;
            /* Past 0.8 of the radius, a heading outward is bent back, more
             * strongly the further out: the walk stays inside the sphere
             * (up to the tube radius) without a kink. */
            double pull = rad > 0.8 && outward > 0.0 ? 2.0 * (rad - 0.8) / 0.2 * outward : 0.0;
            for (int a = 0; a < 3; a++)
                nd[a] = d[a] + step * 6.0 * k[a] - (pull > 0.0 ? pull * p[a] / rad : 0.0);
            normalize3(nd);
            /* Parallel transport: rotate n by the turn from d to nd
             * (project, re-orthonormalize: exact enough for small turns). */
            double proj = dot3(n, nd);
            for (int a = 0; a < 3; a++)
                n[a] -= proj * nd[a];
            normalize3(n);
            cross3(nd, n, bnorm);
            memcpy(d, nd, sizeof d);
            for (int a = 0; a < 3; a++)
                p[a] += step * d[a];
        }
    }
    for (size_t t = s->triangle_count; t < s->triangle_count + tris; t++)
        s->material_of[t] = mirror;
    s->triangle_count += tris;
    if (!add_point(s, 3.0, 4.0, 5.0, 40.0, err))
        return false;
    set_camera(s, 0.0, 0.0, 3.3, 0.0, 0.0, 0.0, 38.0);
    return true;
}

/* ---- the table ---- */

typedef struct builtin_scene {
    lanes_builtin_info info;
    bool (*make)(lanes_scene *s, lanes_error *err);
} builtin_scene;

static bool make_bunnies(lanes_scene *s, lanes_error *err)
{
    return scene_bunnies(s, false, err);
}
static bool make_bunnies_small(lanes_scene *s, lanes_error *err)
{
    return scene_bunnies(s, true, err);
}
static bool make_hairball(lanes_scene *s, lanes_error *err)
{
    return scene_hairball(s, false, err);
}
static bool make_hairball_small(lanes_scene *s, lanes_error *err)
{
    return scene_hairball(s, true, err);
}

static const builtin_scene scenes[] = {
    {{"default", "Cornell-like room: mirror and glass spheres, a box, point + area light", false},
     scene_default},
    {{"dragon", "diffuse CGAL Chinese dragon (one Loop step) on a ground square, 1 point light",
      true},
     scene_dragon},
    {{"sponza-bunny", "procedural two-story atrium, mirror bunny in the middle, 2 point lights",
      true},
     scene_sponza},
    {{"20-bunnies", "20 bunnies (10 mirror, 10 diffuse) spread over a ground triangle", true},
     make_bunnies},
    {{"20-bunnies-small", "20-bunnies with decimated bunnies (~4K triangles each)", true},
     make_bunnies_small},
    {{"hairball", "1500 thin mirror tubes along random curves in a sphere", false}, make_hairball},
    {{"hairball-small", "hairball with 50 tubes", false}, make_hairball_small},
};
#define N_SCENES (sizeof scenes / sizeof scenes[0])

size_t lanes_builtin_scene_count(void)
{
    return N_SCENES;
}

const lanes_builtin_info *lanes_builtin_scene_info(size_t i)
{
    return i < N_SCENES ? &scenes[i].info : NULL;
}

bool lanes_builtin_scene(const char *name, lanes_scene *out, lanes_error *err)
{
    lanes_scene_init(out);
    if (!lanes_scene_limit_to_memory(out, err)) return false;
    for (size_t i = 0; i < N_SCENES; i++) {
        if (strcmp(name, scenes[i].info.name) != 0)
            continue;
        snprintf(out->name, sizeof out->name, "%s", name);
        lanes_error sub;
        if (!scenes[i].make(out, &sub)) {
            lanes_scene_free(out);
            lanes_error_set(err, "scene '%s': %s", name, sub.message);
            return false;
        }
        return true;
    }
    char names[512] = "";
    for (size_t i = 0; i < N_SCENES; i++) {
        size_t len = strlen(names);
        snprintf(names + len, sizeof names - len, "%s%s", i ? ", " : "", scenes[i].info.name);
    }
    lanes_error_set(err, "unknown built-in scene '%s' (valid: %s)", name, names);
    return false;
}
