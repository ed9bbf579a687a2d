/* The mesh builder and the primitives (mesh_builder.h).
 *
 * Compiled for the x86-64 baseline. */
#include "build/mesh_builder.h"

#include "build/mesh_ops.h"

#include <stdlib.h>
#include <string.h>

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

uint32_t builder_vertex(mesh_builder *b, double x, double y, double z)
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

void builder_triangle(mesh_builder *b, uint32_t i, uint32_t j, uint32_t k)
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
void builder_quad(mesh_builder *b, uint32_t a, uint32_t c1, uint32_t c2, uint32_t d)
{
    builder_triangle(b, a, c1, c2);
    builder_triangle(b, a, c2, d);
}

/* Moves the mesh out of the builder (which is left empty either way, so
 * freeing every builder on an error path is always safe). */
lanes_status builder_finish(mesh_builder *b, lanes_mesh *out, const char *what, lanes_error *err)
{
    bool ok = !b->failed;
    if (ok)
        *out = b->m;
    else
        lanes_mesh_free(&b->m);
    memset(b, 0, sizeof *b);
    return ok ? LANES_OK
              : lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "%s: out of memory generating geometry", what);
}

/* ---- primitives ---- */

lanes_status mesh_icosphere(int level, lanes_mesh *out, lanes_error *err)
{
    lanes_status status;
    mesh_builder b = {0};
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
        builder_vertex(&b, p[0], p[1], p[2]);
    }
    for (int i = 0; i < 20; i++)
        builder_triangle(&b, f[i][0], f[i][1], f[i][2]);
    if ((status = builder_finish(&b, out, "sphere", err)) != LANES_OK) return status;
    for (int l = 0; l < level; l++) {
        /* Midpoint split pushed back onto the sphere. */
        lanes_mesh fine;
        if ((status = lanes_mesh_subdivide(out, &fine, err)) != LANES_OK) {
            lanes_mesh_free(out);
            return status;
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
    return LANES_OK;
}

/* Axis-aligned box [lo, hi], faces outward. */
void builder_box(mesh_builder *b, const double lo[3], const double hi[3])
{
    uint32_t v[8];
    for (int i = 0; i < 8; i++)
        v[i] = builder_vertex(b, i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]);
    builder_quad(b, v[0], v[4], v[6], v[2]); /* -x */
    builder_quad(b, v[1], v[3], v[7], v[5]); /* +x */
    builder_quad(b, v[0], v[1], v[5], v[4]); /* -y */
    builder_quad(b, v[2], v[6], v[7], v[3]); /* +y */
    builder_quad(b, v[0], v[2], v[3], v[1]); /* -z */
    builder_quad(b, v[4], v[5], v[7], v[6]); /* +z */
}

/* Grid over [x0, x1] x [z0, z1] (x0 < x1, z0 < z1) at height y, facing +y. */
void builder_grid(mesh_builder *b, double x0, double z0, double x1, double z1, double y, int nx, int nz)
{
    uint32_t base = (uint32_t)b->m.vertex_count;
    for (int j = 0; j <= nz; j++)
        for (int i = 0; i <= nx; i++)
            builder_vertex(b, x0 + (x1 - x0) * i / nx, y, z0 + (z1 - z0) * j / nz);
    for (int j = 0; j < nz; j++)
        for (int i = 0; i < nx; i++) {
            uint32_t a = base + (uint32_t)(j * (nx + 1) + i);
            builder_quad(b, a, a + (uint32_t)(nx + 1), a + (uint32_t)(nx + 2), a + 1);
        }
}

/* Surface of revolution about the y axis through (cx, cz): profile points
 * (radius, y) from bottom to top, `seg` segments around, open ends. */
void builder_lathe(mesh_builder *b, double cx, double cz, const double (*prof)[2], int np, int seg)
{
    uint32_t base = (uint32_t)b->m.vertex_count;
    for (int j = 0; j < np; j++)
        for (int i = 0; i < seg; i++) {
            double a = 2.0 * PI * i / seg;
            builder_vertex(b, cx + prof[j][0] * cos(a), prof[j][1], cz - prof[j][0] * sin(a));
        }
    for (int j = 0; j + 1 < np; j++)
        for (int i = 0; i < seg; i++) {
            uint32_t a = base + (uint32_t)(j * seg + i),
                     c = base + (uint32_t)(j * seg + (i + 1) % seg);
            builder_quad(b, a, c, c + (uint32_t)seg, a + (uint32_t)seg);
        }
}

void builder_cylinder(mesh_builder *b, int seg)
{
    const double prof[2][2] = {{1.0, -1.0}, {1.0, 1.0}};
    uint32_t base = (uint32_t)b->m.vertex_count;
    builder_lathe(b, 0.0, 0.0, prof, 2, seg);
    uint32_t bot = builder_vertex(b, 0, -1, 0), top = builder_vertex(b, 0, 1, 0);
    for (int i = 0; i < seg; i++) {
        uint32_t a = base + (uint32_t)i, c = base + (uint32_t)((i + 1) % seg);
        builder_triangle(b, bot, c, a);
        builder_triangle(b, top, a + (uint32_t)seg, c + (uint32_t)seg);
    }
}
