/* Mesh operations (mesh_ops.h) and the edge table they share.
 *
 * Compiled for the x86-64 baseline. */
#include "build/mesh_ops.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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

lanes_status lanes_mesh_subdivide(const lanes_mesh *in, lanes_mesh *out, lanes_error *err)
{
    memset(out, 0, sizeof *out);
    size_t nt = in->triangle_count, nv = in->vertex_count;
    if (nt > LANES_SCENE_MAX_TRIANGLES / 4 || nv + 3 * nt > UINT32_MAX) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "subdivision: %zu triangles would exceed the limit",
                               nt);
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
        lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "subdivision: out of memory");
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
    /* every way to !ok (out of memory) set err above */
    return ok ? LANES_OK : LANES_ERR_OUT_OF_MEMORY;
}

lanes_status lanes_mesh_decimate(const lanes_mesh *in, int cells, lanes_mesh *out, lanes_error *err)
{
    memset(out, 0, sizeof *out);
    if (cells < 1 || cells > 4096) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "decimation: %d cells out of range [1, 4096]",
                               cells);
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
        lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "decimation: out of memory");
    }
    free(cluster);
    free(acc);
    edges_free(&cells_of);
    return ok ? LANES_OK : LANES_ERR_OUT_OF_MEMORY; /* err set above */
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
