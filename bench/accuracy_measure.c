/* The measurements of `lanes accuracy` (see accuracy_measure.h): closed
 * meshes placed at a size and a translation, the rays that probe them, and
 * the counting of what each mode and kernel set does with those rays. */
#define _GNU_SOURCE /* sched_getaffinity, clock_gettime */
#include "bench/accuracy_measure.h"

#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "build/mesh_import.h"
#include "build/parallel.h"
#include "build/scenes_builtin.h"
#include "trace/render.h"
#include "trace/shading.h"

/* ---- small helpers --------------------------------------------------- */

static uint64_t mix64(uint64_t x)
{
    x ^= x >> 30;
    x *= 0xBF58476D1CE4E5B9ull;
    x ^= x >> 27;
    x *= 0x94D049BB133111EBull;
    x ^= x >> 31;
    return x;
}

/* Streams of the generator: each use draws from its own, so adding a draw
 * to one never shifts another. */
enum { S_POINT = 1, S_PARITY, S_DIRECTION, S_MISS, S_AIM };

static uint64_t draw(uint64_t seed, uint64_t stream, uint64_t index, uint64_t k)
{
    return mix64(seed ^ mix64(stream * 0x9E3779B97F4A7C15ull ^ mix64(index * 8 + k)));
}

static double draw01(uint64_t seed, uint64_t stream, uint64_t index, uint64_t k)
{
    return (double)(draw(seed, stream, index, k) >> 11) * 0x1p-53;
}

/* Uniform on the unit sphere, rounded to float. */
static void sphere_dir(uint64_t seed, uint64_t stream, uint64_t index, float d[3])
{
    double z = 1.0 - 2.0 * draw01(seed, stream, index, 0);
    double phi = 2.0 * 3.14159265358979323846 * draw01(seed, stream, index, 1);
    double r = sqrt(fmax(0.0, 1.0 - z * z));
    d[0] = (float)(r * cos(phi));
    d[1] = (float)(r * sin(phi));
    d[2] = (float)z;
}

/* x rounded to float, for when the rounded value is read back as a double
 * in the same loop. GCC 12.2 at -O3 (its SLP vectorizer) folds
 * (double)(float)x back to x in such loops: for
 *     for (a = 0; a < 3; a++) { q[a] = (float)e[a]; qd[a] = q[a]; }
 * it stores the rounded q but leaves qd unrounded (clang, and GCC at -O2,
 * round). The volatile store makes the rounding impossible to skip. */
static float to_float(double x)
{
    volatile float f = (float)x;
    return f;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

/* ---- closedness ------------------------------------------------------ */

typedef struct {
    uint32_t lo, hi;  /* vertex indices, lo < hi */
    uint32_t slot;    /* 3 * triangle + edge */
    bool forward;     /* the triangle runs lo -> hi */
} half_edge;

static int cmp_half_edge(const void *pa, const void *pb)
{
    const half_edge *a = pa, *b = pb;
    if (a->lo != b->lo) return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi) return a->hi < b->hi ? -1 : 1;
    return a->slot < b->slot ? -1 : a->slot > b->slot;
}

/* The mesh's half-edges sorted by edge, with the closedness counts; and,
 * when adjacent is not NULL, each paired edge's neighbour
 * (LANES_NO_HIT where there is none). */
static lanes_status analyse_edges(const lanes_mesh *m, acc_closure *c, half_edge **out, uint32_t *adjacent,
                                  lanes_error *err)
{
    memset(c, 0, sizeof *c);
    c->triangles = m->triangle_count;
    if (m->triangle_count > UINT32_MAX / 3) {
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY,
                               "mesh too large for the accuracy study (%zu triangles)", m->triangle_count);
    }
    size_t n = 0;
    half_edge *he = malloc((3 * m->triangle_count + 1) * sizeof *he);
    if (!he) {
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "out of memory for %zu triangles",
                               m->triangle_count);
    }
    for (size_t t = 0; t < m->triangle_count; t++) {
        const uint32_t *v = m->indices + 3 * t;
        if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) {
            c->degenerate++;
            continue;
        }
        for (int e = 0; e < 3; e++) {
            uint32_t a = v[e], b = v[(e + 1) % 3];
            he[n++] = (half_edge){a < b ? a : b, a < b ? b : a, (uint32_t)(3 * t + (size_t)e), a < b};
        }
    }
    qsort(he, n, sizeof *he, cmp_half_edge);
    if (adjacent)
        for (size_t i = 0; i < 3 * m->triangle_count; i++) adjacent[i] = LANES_NO_HIT;
    for (size_t i = 0; i < n;) {
        size_t j = i + 1;
        while (j < n && he[j].lo == he[i].lo && he[j].hi == he[i].hi) j++;
        c->edges++;
        if (j - i == 1) {
            c->boundary++;
        } else if (j - i > 2) {
            c->nonmanifold++;
        } else if (he[i].forward == he[i + 1].forward) {
            c->misoriented++;
        } else if (adjacent) {
            adjacent[he[i].slot] = he[i + 1].slot / 3;
            adjacent[he[i + 1].slot] = he[i].slot / 3;
        }
        i = j;
    }
    if (out) {
        he[n].slot = UINT32_MAX; /* sentinel: the end of the list */
        *out = he;
    } else {
        free(he);
    }
    return LANES_OK;
}

lanes_status acc_mesh_closure(const lanes_mesh *m, acc_closure *c, lanes_error *err)
{
    return analyse_edges(m, c, NULL, NULL, err);
}

bool acc_closure_closed(const acc_closure *c)
{
    return c->triangles > 0 && c->boundary == 0 && c->nonmanifold == 0 && c->misoriented == 0 && c->degenerate == 0;
}

void acc_closure_describe(const acc_closure *c, char *buf, size_t size)
{
    size_t used = 0;
    buf[0] = '\0';
    const struct {
        size_t n;
        const char *one, *many;
    } parts[] = {{c->boundary, "boundary edge", "boundary edges"},
                 {c->nonmanifold, "edge in more than two triangles", "edges in more than two triangles"},
                 {c->misoriented, "edge whose two triangles run the same way",
                  "edges whose two triangles run the same way"},
                 {c->degenerate, "triangle repeating a vertex", "triangles repeating a vertex"}};
    if (c->triangles == 0) {
        snprintf(buf, size, "no triangles");
        return;
    }
    for (size_t i = 0; i < sizeof parts / sizeof parts[0]; i++) {
        if (!parts[i].n || used >= size) continue;
        int k = snprintf(buf + used, size - used, "%s%zu %s", used ? ", " : "", parts[i].n,
                         parts[i].n == 1 ? parts[i].one : parts[i].many);
        if (k > 0) used += (size_t)k;
    }
    if (used == 0) snprintf(buf, size, "closed: %zu edges, each in two triangles running opposite ways", c->edges);
}

/* Closes each boundary loop with a fan of triangles that run against it. */
static lanes_status fill_holes(lanes_mesh *m, size_t *loops_out, size_t *added_out, lanes_error *err)
{
    lanes_status status;
    acc_closure c;
    half_edge *he = NULL;
    if ((status = analyse_edges(m, &c, &he, NULL, err)) != LANES_OK) return status;
    /* boundary half-edges as the triangles run them: from -> to */
    size_t nb = 0;
    uint32_t (*bnd)[2] = malloc((c.boundary + 1) * sizeof *bnd);
    bool ok = bnd != NULL;
    for (size_t i = 0; ok && he[i].slot != UINT32_MAX;) {
        size_t j = i + 1;
        while (he[j].slot != UINT32_MAX && he[j].lo == he[i].lo && he[j].hi == he[i].hi) j++;
        if (j - i == 1) {
            bnd[nb][0] = he[i].forward ? he[i].lo : he[i].hi;
            bnd[nb][1] = he[i].forward ? he[i].hi : he[i].lo;
            nb++;
        }
        i = j;
    }
    free(he);
    if (!ok) {
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "out of memory");
    }
    /* next[i]: the boundary half-edge leaving the end of half-edge i; a
     * vertex with two leaving boundary edges makes the loops ambiguous */
    size_t *next = malloc((nb + 1) * sizeof *next);
    bool *used = calloc(nb + 1, 1);
    uint32_t *loop = malloc((nb + 1) * sizeof *loop);
    uint32_t *idx = NULL;
    size_t loops = 0, added = 0;
    if (!next || !used || !loop) status = lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "out of memory");
    for (size_t i = 0; status == LANES_OK && i < nb; i++) {
        size_t found = 0, which = 0;
        for (size_t j = 0; j < nb; j++)
            if (bnd[j][0] == bnd[i][1]) found++, which = j;
        if (found != 1) {
            status = lanes_error_set(err, LANES_ERR_BAD_INPUT,
                                     "its boundary is not a set of simple loops (vertex %u)", bnd[i][1]);
        }
        next[i] = which;
    }
    if (status == LANES_OK) {
        idx = realloc(m->indices, (3 * m->triangle_count + 3 * nb) * sizeof *idx);
        if (!idx) {
            status = lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "out of memory");
        } else {
            m->indices = idx;
        }
    }
    for (size_t s = 0; status == LANES_OK && s < nb; s++) {
        if (used[s]) continue;
        size_t k = 0;
        for (size_t i = s; !used[i]; i = next[i]) {
            used[i] = true;
            loop[k++] = bnd[i][0];
        }
        /* the loop runs v0 -> v1 -> ...; the fan (v0, v_i+1, v_i) runs
         * each loop edge backwards and pairs its inner edges */
        for (size_t i = 1; i + 1 < k; i++) {
            uint32_t *t = m->indices + 3 * m->triangle_count;
            t[0] = loop[0], t[1] = loop[i + 1], t[2] = loop[i];
            m->triangle_count++;
            added++;
        }
        loops++;
    }
    free(bnd), free(next), free(used), free(loop);
    if (loops_out) *loops_out = loops;
    if (added_out) *added_out = added;
    return status;
}

lanes_status acc_mesh_load(const char *spec, bool is_file, lanes_mesh *out, char *note, size_t note_size,
                           lanes_error *err)
{
    lanes_status status;
    memset(out, 0, sizeof *out);
    if (note && note_size) note[0] = '\0';
    if (is_file) {
        if ((status = lanes_mesh_read(spec, out, err)) != LANES_OK) return status;
    } else {
        /* level 4: 5120 triangles, enough edges to count leaks on */
        if ((status = lanes_builtin_object(spec, strcmp(spec, "sphere") == 0 ? 4 : -1, out, err)) != LANES_OK)
            return status;
    }
    acc_closure c;
    char what[256];
    if ((status = acc_mesh_closure(out, &c, err)) != LANES_OK) goto fail;
    if (acc_closure_closed(&c)) return LANES_OK;
    acc_closure_describe(&c, what, sizeof what);
    if (!is_file && c.triangles > 0 && c.nonmanifold == 0 && c.misoriented == 0 && c.degenerate == 0 &&
        c.boundary * 100 < c.edges) {
        size_t loops = 0, added = 0;
        lanes_error sub;
        if ((status = fill_holes(out, &loops, &added, &sub)) != LANES_OK) {
            status = lanes_error_set(err, status,
                                     "%s: not a closed mesh (%s), and the holes cannot be filled: %s", spec,
                                     what, sub.message);
            goto fail;
        }
        acc_closure after;
        if ((status = acc_mesh_closure(out, &after, err)) != LANES_OK) goto fail;
        if (acc_closure_closed(&after)) {
            if (note && note_size)
                snprintf(note, note_size, "%s: %s, closed by filling %zu hole%s with %zu triangle%s", spec, what, loops,
                         loops == 1 ? "" : "s", added, added == 1 ? "" : "s");
            return LANES_OK;
        }
    }
    status = lanes_error_set(
        err, LANES_ERR_BAD_INPUT,
        "%s: not a closed mesh: %s (lanes accuracy counts rays escaping from inside, so every edge "
        "must be shared by exactly two triangles that run it in opposite directions)",
        spec, what);
fail:
    lanes_mesh_free(out);
    memset(out, 0, sizeof *out);
    return status;
}

/* ---- worlds ---------------------------------------------------------- */

const lanes_wbvh *acc_world_wide(const acc_world *w, int width)
{
    int i = width == 4 ? 0 : width == 8 ? 1 : width == 16 ? 2 : -1;
    return i >= 0 && w->wide[i].width == width ? &w->wide[i] : NULL;
}

void acc_leak_ray(const acc_world *w, uint64_t i, lanes_ray *r)
{
    const float *p = w->points[(i / ACC_RAYS_PER_POINT) % w->point_count];
    memset(r, 0, sizeof *r);
    memcpy(r->o, p, sizeof r->o);
    sphere_dir(w->seed, S_DIRECTION, i, r->d);
    r->tnear = 0.0f;
    r->tfar = INFINITY;
}

void acc_aimed_ray(const acc_world *w, uint64_t i, lanes_ray *r)
{
    const float *p = w->points[(i / ACC_RAYS_PER_POINT) % w->point_count];
    const float *v = w->scene.verts + 9 * (draw(w->seed, S_AIM, i, 0) % w->scene.triangle_count);
    int k = (int)(draw(w->seed, S_AIM, i, 1) % 3), k1 = (k + 1) % 3;
    memset(r, 0, sizeof *r);
    for (int a = 0; a < 3; a++) {
        float target = (i & 1) ? v[3 * k + a] : 0.5f * (v[3 * k + a] + v[3 * k1 + a]);
        r->o[a] = p[a];
        r->d[a] = target - p[a];
    }
    r->tnear = 0.0f;
    r->tfar = INFINITY;
}

typedef struct {
    const acc_world *w;
    float lo[3], hi[3];
    uint64_t base;
    float (*cand)[3];
    int8_t *inside; /* 1 inside, 0 outside or undecided */
} point_ctx;

enum { POINT_ROUND = 4096, POINT_BLOCK = 64 };

/* Inside: odd crossing counts along three random directions, all agreeing,
 * and clear of the surface. A ray through a shared edge counts that edge
 * twice and spoils its parity; disagreement discards the candidate. */
static void point_block(void *p, size_t block, int worker)
{
    point_ctx *c = p;
    const acc_world *w = c->w;
    (void)worker;
    for (size_t j = block * POINT_BLOCK; j < (block + 1) * POINT_BLOCK && j < POINT_ROUND; j++) {
        uint64_t id = c->base + j;
        float q[3];
        double qd[3];
        for (int a = 0; a < 3; a++) {
            double u = draw01(w->seed, S_POINT, id, (uint64_t)a);
            q[a] = to_float(c->lo[a] + (c->hi[a] - (double)c->lo[a]) * u);
            qd[a] = q[a];
        }
        memcpy(c->cand[j], q, sizeof q);
        c->inside[j] = 0;
        if (acc_ref_near(&w->ref, qd, ACC_CLEARANCE * w->size)) continue;
        int odd = 0;
        for (int k = 0; k < 3; k++) {
            float d[3];
            sphere_dir(w->seed, S_PARITY, id * 3 + (uint64_t)k, d);
            odd += (int)(acc_ref_crossings(&w->ref, q, d) & 1);
        }
        c->inside[j] = odd == 3;
    }
}

static lanes_status find_points(acc_world *w, int threads, lanes_error *err)
{
    point_ctx c = {.w = w};
    lanes_scene_bounds(&w->scene, c.lo, c.hi);
    c.cand = malloc(POINT_ROUND * sizeof *c.cand);
    c.inside = malloc(POINT_ROUND);
    w->points = malloc(ACC_POINTS * sizeof *w->points);
    if (!c.cand || !c.inside || !w->points) {
        free(c.cand), free(c.inside);
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "out of memory");
    }
    /* A mesh whose interior fills a few percent of its box needs a few
     * rounds; one whose rounding left no interior gives up after 16. */
    for (int round = 0; round < 16 && w->point_count < ACC_POINTS; round++) {
        c.base = (uint64_t)round * POINT_ROUND;
        lanes_parallel_for(threads, POINT_ROUND / POINT_BLOCK, point_block, &c);
        for (size_t j = 0; j < POINT_ROUND && w->point_count < ACC_POINTS; j++)
            if (c.inside[j]) memcpy(w->points[w->point_count++], c.cand[j], sizeof c.cand[j]);
        w->point_candidates += POINT_ROUND;
    }
    free(c.cand), free(c.inside);
    return LANES_OK;
}

lanes_status acc_world_build(acc_world *w, const char *name, const lanes_mesh *mesh, double size,
                             double translation, unsigned width_mask, int threads, uint64_t seed,
                             lanes_error *err)
{
    lanes_status status = LANES_OK;
    memset(w, 0, sizeof *w);
    lanes_scene_init(&w->scene);
    snprintf(w->name, sizeof w->name, "%s", name);
    snprintf(w->scene.name, sizeof w->scene.name, "%s", name);
    w->size = size;
    w->translation = translation;
    w->seed = mix64(seed);
    for (const char *s = name; *s; s++) w->seed = mix64(w->seed ^ (uint8_t)*s);

    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < mesh->vertex_count; v++)
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], mesh->positions[3 * v + a]);
            hi[a] = fmax(hi[a], mesh->positions[3 * v + a]);
        }
    double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
    if (!(diag > 0.0) || !isfinite(diag) || !(size > 0.0) || !isfinite(translation)) {
        return lanes_error_set(
            err, LANES_ERR_BAD_INPUT,
            "%s: cannot place the mesh (bounding-box diagonal %g, size %g, translation %g)", name, diag, size,
            translation);
    }
    /* Scaled and translated in double, rounded once to float: what a user's
     * scene far from the origin holds. */
    float *pos = malloc((mesh->vertex_count + 1) * 3 * sizeof *pos);
    if (!pos) {
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "out of memory");
    }
    double scale = size / diag;
    for (size_t v = 0; v < mesh->vertex_count; v++)
        for (int a = 0; a < 3; a++)
            pos[3 * v + a] = (float)((mesh->positions[3 * v + a] - 0.5 * (lo[a] + hi[a])) * scale + translation);
    lanes_mesh placed = *mesh;
    placed.positions = pos;
    lanes_material mat;
    memset(&mat, 0, sizeof mat);
    snprintf(mat.name, sizeof mat.name, "grey");
    mat.kind = LANES_MAT_DIFFUSE;
    mat.color[0] = mat.color[1] = mat.color[2] = 0.7f;
    uint32_t mi = 0;
    bool ok = lanes_scene_add_material(&w->scene, &mat, &mi, err) == LANES_OK &&
              lanes_scene_add_mesh(&w->scene, &placed, NULL, mi, name, err) == LANES_OK;
    free(pos);
    if (!ok) goto fail;
    if (w->scene.triangle_count != mesh->triangle_count) {
        status = lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: %zu of %zu triangles placed", name,
                                 w->scene.triangle_count, mesh->triangle_count);
        goto fail;
    }
    w->eps = lanes_scene_epsilon(&w->scene);

    lanes_render_accel accel;
    if ((status = lanes_render_accel_build(&w->scene, NULL, true, threads, &accel, err)) != LANES_OK) goto fail;
    w->bvh2 = accel.bvh2;
    static const int widths[3] = {4, 8, 16};
    lanes_bvh_build_options bo;
    lanes_bvh_default_options(&bo);
    bo.threads = threads;
    for (int i = 0; i < 3; i++)
        if ((width_mask & acc_width_bit(widths[i])) &&
            (status = lanes_wbvh_build(&w->scene, widths[i], &bo, &w->wide[i], err)) != LANES_OK)
            goto fail;
    if ((status = acc_ref_init(&w->ref, &w->bvh2, &w->scene, err)) != LANES_OK) goto fail;

    acc_closure c;
    w->adjacent = malloc((3 * mesh->triangle_count + 1) * sizeof *w->adjacent);
    if (!w->adjacent) {
        status = lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "out of memory");
        goto fail;
    }
    if ((status = analyse_edges(mesh, &c, NULL, w->adjacent, err)) != LANES_OK) goto fail;
    if ((status = find_points(w, threads, err)) != LANES_OK) goto fail;
    return LANES_OK;
fail:
    acc_world_free(w);
    return status;
}

void acc_world_free(acc_world *w)
{
    for (int i = 0; i < 3; i++)
        if (w->wide[i].width) lanes_wbvh_free(&w->wide[i]);
    if (w->bvh2.nodes) lanes_bvh2_free(&w->bvh2);
    lanes_scene_free(&w->scene);
    free(w->adjacent);
    free(w->points);
    free(w->misses);
    memset(w, 0, sizeof *w);
}

/* ---- rays that just miss --------------------------------------------- */

typedef struct {
    const acc_world *w;
    uint64_t base;
    lanes_ray *cand;
    int8_t *keep;
} miss_ctx;

enum { MISS_ROUND = 4096, MISS_BLOCK = 64 };

static void vnorm(double v[3])
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0.0)
        for (int a = 0; a < 3; a++) v[a] /= l;
}

static void vcross(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static bool tri_normal(const float *v, double n[3])
{
    double e1[3], e2[3];
    for (int a = 0; a < 3; a++) e1[a] = (double)v[3 + a] - v[a], e2[a] = (double)v[6 + a] - v[a];
    vcross(e1, e2, n);
    if (!(n[0] != 0.0 || n[1] != 0.0 || n[2] != 0.0)) return false;
    vnorm(n);
    return true;
}

/* A candidate: an edge between triangles with unit normals n1 and n2 is a
 * silhouette edge for any direction d = +-(t x m) + a t, with t the edge's
 * direction and m = (n1 + n2) / |n1 + n2| (d . n1 and d . n2 then have
 * opposite signs; edges bent by less than 0.1 degree are skipped, as d
 * would lie in their plane). The ray passes a point q of the edge moved
 * outward along m by 2^-4 to 2^3 ulps (log-uniform) of q's largest
 * coordinate. Its origin is `size` back along d, rounded to float, and its
 * direction is then aimed from that float origin at the moved point, so the
 * rounding of a far origin (an ulp of 1e7 is 1) does not decide how close
 * the ray passes: the direction's own rounding moves it by about
 * 2^-24 * size. Only rays the exact reference confirms as misses of the
 * whole mesh are kept. */
static bool miss_candidate(const acc_world *w, uint64_t id, lanes_ray *r)
{
    const lanes_scene *s = &w->scene;
    uint64_t seed = w->seed;
    size_t t = (size_t)(draw(seed, S_MISS, id, 0) % s->triangle_count);
    int e = (int)(draw(seed, S_MISS, id, 1) % 3);
    uint32_t nb = w->adjacent[3 * t + (size_t)e];
    if (nb == LANES_NO_HIT) return false;
    const float *v = s->verts + 9 * t;
    double n1[3], n2[3], m[3], tv[3], wv[3], d[3], q[3];
    if (!tri_normal(v, n1) || !tri_normal(s->verts + 9 * (size_t)nb, n2)) return false;
    double bend = 0.0;
    for (int a = 0; a < 3; a++) {
        m[a] = n1[a] + n2[a];
        bend += (n1[a] - n2[a]) * (n1[a] - n2[a]);
    }
    /* a flat edge is no silhouette (d would lie in the plane), nor is a knife edge */
    if (bend < 4e-6 || sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]) < 1e-6) return false;
    vnorm(m);
    const float *A = v + 3 * e, *B = v + 3 * ((e + 1) % 3);
    for (int a = 0; a < 3; a++) tv[a] = (double)B[a] - A[a];
    if (!(tv[0] != 0.0 || tv[1] != 0.0 || tv[2] != 0.0)) return false;
    vnorm(tv);
    vcross(tv, m, wv);
    double sgn = (draw(seed, S_MISS, id, 2) & 1) ? 1.0 : -1.0;
    double along = draw01(seed, S_MISS, id, 3) - 0.5;
    for (int a = 0; a < 3; a++) d[a] = sgn * wv[a] + along * tv[a];
    vnorm(d);
    double s01 = 0.1 + 0.8 * draw01(seed, S_MISS, id, 4), mag = 0.0;
    for (int a = 0; a < 3; a++) {
        q[a] = A[a] + s01 * ((double)B[a] - A[a]);
        mag = fmax(mag, fabs(q[a]));
    }
    float fm = (float)mag;
    double ulp = (double)nextafterf(fm, INFINITY) - fm;
    double off = exp2(-4.0 + 7.0 * draw01(seed, S_MISS, id, 5)) * ulp;
    memset(r, 0, sizeof *r);
    for (int a = 0; a < 3; a++) {
        q[a] += off * m[a];
        r->o[a] = to_float(q[a] - w->size * d[a]);
    }
    for (int a = 0; a < 3; a++) r->d[a] = (float)((q[a] - r->o[a]) / w->size);
    r->tnear = 0.0f;
    r->tfar = INFINITY;
    return !acc_ref_any(&w->ref, r->o, r->d);
}

static void miss_block(void *p, size_t block, int worker)
{
    miss_ctx *c = p;
    (void)worker;
    for (size_t j = block * MISS_BLOCK; j < (block + 1) * MISS_BLOCK && j < MISS_ROUND; j++)
        c->keep[j] = miss_candidate(c->w, c->base + j, &c->cand[j]);
}

lanes_status acc_world_misses(acc_world *w, size_t count, int threads, lanes_error *err)
{
    free(w->misses);
    w->misses = malloc((count + 1) * sizeof *w->misses);
    miss_ctx c = {.w = w, .cand = malloc(MISS_ROUND * sizeof(lanes_ray)), .keep = malloc(MISS_ROUND)};
    w->miss_count = w->miss_attempts = 0;
    if (!w->misses || !c.cand || !c.keep) {
        free(c.cand), free(c.keep);
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "out of memory for %zu rays", count);
    }
    /* Most candidates on a convex mesh are kept; on a concave one the ray
     * often meets another part. 32 tries per ray is plenty for both. */
    size_t limit = 32 * count + MISS_ROUND;
    while (w->miss_count < count && w->miss_attempts < limit) {
        c.base = w->miss_attempts;
        lanes_parallel_for(threads, MISS_ROUND / MISS_BLOCK, miss_block, &c);
        for (size_t j = 0; j < MISS_ROUND && w->miss_count < count; j++)
            if (c.keep[j]) w->misses[w->miss_count++] = c.cand[j];
        w->miss_attempts += MISS_ROUND;
    }
    free(c.cand), free(c.keep);
    return LANES_OK;
}

/* ---- measuring ------------------------------------------------------- */

const char *acc_via_name(acc_via v)
{
    static const char *const names[] = {"wide", "bvh2", "packet"};
    return (unsigned)v < ACC_VIA_COUNT ? names[v] : "?";
}

int acc_ulp_bin(uint64_t ulps)
{
    if (ulps < ACC_ULP_EXACT) return (int)ulps;
    int b = ACC_ULP_EXACT + (63 - __builtin_clzll(ulps)) - 6;
    return b < ACC_ULP_BINS ? b : ACC_ULP_BINS - 1;
}

uint64_t acc_ulp_bin_low(int bin)
{
    return bin < ACC_ULP_EXACT ? (uint64_t)bin : (uint64_t)1 << (bin - ACC_ULP_EXACT + 6);
}

double acc_ulp_percentile(const acc_counts *c, double p)
{
    if (c->t_samples == 0) return NAN;
    uint64_t want = (uint64_t)ceil(p * (double)c->t_samples), seen = 0;
    if (want < 1) want = 1;
    for (int b = 0; b < ACC_ULP_BINS; b++) {
        seen += c->t_hist[b];
        if (seen >= want) return (double)acc_ulp_bin_low(b);
    }
    return (double)acc_ulp_bin_low(ACC_ULP_BINS - 1);
}

/* Floats as integers that order like the floats: ulp distances are
 * differences of these. */
static int64_t float_key(float f)
{
    int32_t i;
    memcpy(&i, &f, sizeof i);
    return i >= 0 ? (int64_t)i : (int64_t)INT32_MIN - (int64_t)i;
}

enum { CHUNK = 16 * ACC_RAYS_PER_POINT };

typedef struct {
    lanes_ray rays[CHUNK];
    lanes_hit hits[CHUNK];
    lanes_ray sec[2 * CHUNK];
    lanes_hit sec_hits[2 * CHUNK];
    uint32_t sec_prim[2 * CHUNK];
    lanes_rays soa;
    uint32_t prim[ACC_RAYS_PER_POINT + LANES_MAX_W];
    float u[ACC_RAYS_PER_POINT + LANES_MAX_W], v[ACC_RAYS_PER_POINT + LANES_MAX_W];
    acc_counts counts;
} worker_state;

typedef struct {
    const acc_world *w;
    const acc_job *job;
    const lanes_wbvh *wide;
    lanes_precision prec;
    worker_state *ws[LANES_PARALLEL_MAX_THREADS];
    bool misses; /* this pass traces the world's misses, not the leak rays */
} measure_ctx;

/* Rays [0, n) of ws->rays, prepared, through the job's traversal. Packets
 * are runs of rays that share `group` (ACC_RAYS_PER_POINT consecutive ray
 * numbers starting at `first`). */
static void trace_chunk(const measure_ctx *c, worker_state *ws, lanes_ray *rays, lanes_hit *hits, size_t n,
                        acc_via via, uint64_t first)
{
    const lanes_kernels *k = c->job->k;
    lanes_accuracy mode = c->job->mode;
    if (via == ACC_VIA_WIDE) {
        k->trace_wide(c->wide, mode, rays, n, hits, NULL);
        return;
    }
    if (via == ACC_VIA_BVH2) {
        k->trace_bvh2(&c->w->bvh2, mode, rays, n, hits, NULL);
        return;
    }
    for (size_t j = 0; j < n;) {
        size_t end = j + 1;
        while (end < n && (first + end) / ACC_RAYS_PER_POINT == (first + j) / ACC_RAYS_PER_POINT) end++;
        lanes_rays *s = &ws->soa;
        s->count = end - j;
        for (size_t i = j; i < end; i++) {
            size_t g = i - j;
            s->ox[g] = rays[i].o[0], s->oy[g] = rays[i].o[1], s->oz[g] = rays[i].o[2];
            s->dx[g] = rays[i].d[0], s->dy[g] = rays[i].d[1], s->dz[g] = rays[i].d[2];
            s->tnear[g] = 0.0f, s->tfar[g] = INFINITY;
            ws->prim[g] = LANES_NO_HIT;
        }
        k->rays_prepare(s, c->prec.rcp);
        lanes_packet_options po = {LANES_PACKET_PARTITION, mode, NULL, false, false, false};
        k->trace_packet(&c->w->bvh2, &po, s, ws->prim, ws->u, ws->v, NULL, NULL);
        for (size_t i = j; i < end; i++) {
            size_t g = i - j;
            hits[i] = ws->prim[g] == LANES_NO_HIT ? (lanes_hit){INFINITY, 0.0f, 0.0f, LANES_NO_HIT}
                                                  : (lanes_hit){s->tfar[g], ws->u[g], ws->v[g], ws->prim[g]};
        }
        j = end;
    }
}

static void measure_chunk(void *p, size_t chunk, int worker)
{
    measure_ctx *c = p;
    const acc_job *job = c->job;
    const acc_world *w = c->w;
    worker_state *ws = c->ws[worker];
    acc_counts *out = &ws->counts;

    if (c->misses) {
        size_t first = chunk * CHUNK, n = w->miss_count - first < CHUNK ? w->miss_count - first : CHUNK;
        for (size_t i = 0; i < n; i++) {
            ws->rays[i] = w->misses[first + i];
            lanes_ray_prepare_rcp(&ws->rays[i], c->prec.rcp);
        }
        trace_chunk(c, ws, ws->rays, ws->hits, n, job->via, first);
        out->miss_rays += n;
        for (size_t i = 0; i < n; i++) out->false_hits += ws->hits[i].prim != LANES_NO_HIT;
        return;
    }

    uint64_t first = job->first + (uint64_t)chunk * CHUNK;
    uint64_t end = job->first + job->count;
    size_t n = end - first < CHUNK ? (size_t)(end - first) : CHUNK;
    for (size_t i = 0; i < n; i++) {
        if (job->aimed)
            acc_aimed_ray(w, first + i, &ws->rays[i]);
        else
            acc_leak_ray(w, first + i, &ws->rays[i]);
        lanes_ray_prepare_rcp(&ws->rays[i], c->prec.rcp);
    }
    trace_chunk(c, ws, ws->rays, ws->hits, n, job->via, first);
    if (job->aimed) {
        out->aimed_rays += n;
        for (size_t i = 0; i < n; i++) out->aimed_leaks += ws->hits[i].prim == LANES_NO_HIT;
        return;
    }
    out->rays += n;
    size_t nsec = 0;
    for (size_t i = 0; i < n; i++) {
        const lanes_hit *h = &ws->hits[i];
        const lanes_ray *r = &ws->rays[i];
        if (h->prim == LANES_NO_HIT) {
            out->leaks++;
            continue;
        }
        if (job->t_error) {
            acc_tri_result ref = acc_ref_tri(r->o, r->d, w->scene.verts + (size_t)h->prim * 9);
            if (isfinite(ref.t)) {
                int64_t dist = float_key(h->t) - float_key((float)ref.t);
                out->t_hist[acc_ulp_bin((uint64_t)(dist < 0 ? -dist : dist))]++;
                out->t_samples++;
            }
        }
        if (first + i < job->self_from) {
            /* leaving the surface both ways: back to the side the ray came
             * from (reflection), and on through it (transmission) */
            vec3 d = v3_load(r->d);
            lanes_surface sf = lanes_surface_at(&w->scene, h, d);
            vec3 o1 = lanes_offset_origin(&sf, sf.nf, job->mode, w->eps);
            vec3 o2 = lanes_offset_origin(&sf, v3_scale(sf.nf, -1.0f), job->mode, w->eps);
            vec3 d1 = lanes_reflect(d, sf.nf);
            ws->sec[nsec] = (lanes_ray){{o1.x, o1.y, o1.z}, {d1.x, d1.y, d1.z}, {0, 0, 0}, 0.0f, INFINITY};
            ws->sec[nsec + 1] = (lanes_ray){{o2.x, o2.y, o2.z}, {d.x, d.y, d.z}, {0, 0, 0}, 0.0f, INFINITY};
            ws->sec_prim[nsec] = ws->sec_prim[nsec + 1] = h->prim;
            nsec += 2;
        }
    }
    if (nsec) {
        for (size_t i = 0; i < nsec; i++) lanes_ray_prepare_rcp(&ws->sec[i], c->prec.rcp);
        /* secondary rays do not share origins: never as packets */
        trace_chunk(c, ws, ws->sec, ws->sec_hits, nsec, job->via == ACC_VIA_BVH2 ? ACC_VIA_BVH2 : ACC_VIA_WIDE, 0);
        out->self_rays += nsec;
        for (size_t i = 0; i < nsec; i++) out->self_hits += ws->sec_hits[i].prim == ws->sec_prim[i];
    }
}

static void merge(acc_counts *into, const acc_counts *c)
{
    into->rays += c->rays, into->leaks += c->leaks;
    into->aimed_rays += c->aimed_rays, into->aimed_leaks += c->aimed_leaks;
    into->t_samples += c->t_samples;
    for (int b = 0; b < ACC_ULP_BINS; b++) into->t_hist[b] += c->t_hist[b];
    into->self_rays += c->self_rays, into->self_hits += c->self_hits;
    into->miss_rays += c->miss_rays, into->false_hits += c->false_hits;
}

lanes_status acc_measure(const acc_world *w, const acc_job *job, acc_counts *out, lanes_error *err)
{
    measure_ctx c = {.w = w, .job = job, .prec = lanes_accuracy_precision(job->mode)};
    bool needs_wide =
        job->via == ACC_VIA_WIDE || (job->via == ACC_VIA_PACKET && !job->aimed && job->self_from > job->first);
    c.wide = acc_world_wide(w, job->k->wide_width);
    if (needs_wide && !c.wide) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: no wide BVH of width %d was built", w->name,
                               job->k->wide_width);
    }
    if (job->count > 0 && w->point_count == 0) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s at %g: no interior points", w->name,
                               w->translation);
    }
    int threads = lanes_parallel_threads(job->threads);
    bool ok = true;
    for (int t = 0; t < threads; t++) {
        c.ws[t] = calloc(1, sizeof *c.ws[t]);
        if (!c.ws[t] || !lanes_rays_alloc(&c.ws[t]->soa, ACC_RAYS_PER_POINT)) {
            if (c.ws[t]) free(c.ws[t]);
            c.ws[t] = NULL;
            ok = false;
        }
    }
    if (ok) {
        c.misses = false;
        lanes_parallel_for(threads, (size_t)((job->count + CHUNK - 1) / CHUNK), measure_chunk, &c);
        if (job->false_hits && w->miss_count > 0) {
            c.misses = true;
            lanes_parallel_for(threads, (w->miss_count + CHUNK - 1) / CHUNK, measure_chunk, &c);
        }
    }
    for (int t = 0; t < threads; t++) {
        if (!c.ws[t]) continue;
        merge(out, &c.ws[t]->counts);
        lanes_rays_free(&c.ws[t]->soa);
        free(c.ws[t]);
    }
    return ok ? LANES_OK : lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "out of memory");
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double acc_time_wide(const acc_world *w, const lanes_kernels *k, lanes_accuracy mode, size_t rays, int reps)
{
    const lanes_wbvh *wide = acc_world_wide(w, k->wide_width);
    if (w->point_count == 0 || rays == 0 || !wide) return NAN;
    lanes_ray *r = malloc(rays * sizeof *r);
    lanes_hit *h = malloc(rays * sizeof *h);
    double t[16];
    if (reps > 16) reps = 16;
    if (reps < 1) reps = 1;
    if (!r || !h) {
        free(r), free(h);
        return NAN;
    }
    lanes_rcp_mode rcp = lanes_accuracy_precision(mode).rcp;
    for (size_t i = 0; i < rays; i++) {
        acc_leak_ray(w, i, &r[i]);
        lanes_ray_prepare_rcp(&r[i], rcp);
    }
    for (int i = 0; i < reps; i++) {
        double t0 = now_seconds();
        k->trace_wide(wide, mode, r, rays, h, NULL);
        t[i] = now_seconds() - t0;
    }
    qsort(t, (size_t)reps, sizeof t[0], cmp_double);
    free(r), free(h);
    double med = reps % 2 ? t[reps / 2] : 0.5 * (t[reps / 2 - 1] + t[reps / 2]);
    return med > 0.0 ? (double)rays / med * 1e-6 : NAN;
}
