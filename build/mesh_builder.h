/* Indexed meshes generated in double precision: a growing builder, and the
 * primitives the built-in objects and scenes are made of (an icosphere,
 * boxes, grids, lathes, cylinders). Internal to build/.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BUILD_MESH_BUILDER_H
#define LANES_BUILD_MESH_BUILDER_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "build/scene.h"

#define PI 3.14159265358979323846

/* Small vector helpers (double: generation precision is free). */
static inline double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline void cross3(const double a[3], const double b[3], double o[3])
{
    double r[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    memcpy(o, r, sizeof r);
}

static inline void normalize3(double v[3])
{
    double l = sqrt(dot3(v, v));
    if (l > 0.0)
        for (int a = 0; a < 3; a++)
            v[a] /= l;
}

/* A mesh growing one vertex and one triangle at a time. Start from
 * `mesh_builder b = {0}`; out of memory makes every later call a no-op and
 * builder_finish the error. */
typedef struct mesh_builder {
    lanes_mesh m;
    size_t vcap, tcap;
    bool failed; /* out of memory or too large; every later call is a no-op */
} mesh_builder;

/* The new vertex's index. */
uint32_t builder_vertex(mesh_builder *b, double x, double y, double z);
/* Triangle i j k, counter-clockwise seen from its front. */
void builder_triangle(mesh_builder *b, uint32_t i, uint32_t j, uint32_t k);
/* Quad a b c d, counter-clockwise seen from its front. */
void builder_quad(mesh_builder *b, uint32_t a, uint32_t c1, uint32_t c2, uint32_t d);
/* Moves the mesh out of the builder (which is left empty either way, so
 * freeing every builder on an error path is always safe). */
lanes_status builder_finish(mesh_builder *b, lanes_mesh *out, const char *what, lanes_error *err);

/* The unit sphere: an icosahedron subdivided `level` times, 20 * 4^level
 * triangles. */
lanes_status mesh_icosphere(int level, lanes_mesh *out, lanes_error *err);
/* The box lo..hi, faces outward. */
void builder_box(mesh_builder *b, const double lo[3], const double hi[3]);
/* The rectangle x0..x1 by z0..z1 at height y, facing +y, in nx by nz quads. */
void builder_grid(mesh_builder *b, double x0, double z0, double x1, double z1, double y, int nx, int nz);
/* A surface of revolution about the vertical axis through (cx, cz): the
 * profile's np (radius, y) points turned in seg steps. */
void builder_lathe(mesh_builder *b, double cx, double cz, const double (*prof)[2], int np, int seg);
/* The cylinder of radius 1 along y from -1 to 1, with caps. */
void builder_cylinder(mesh_builder *b, int seg);

#endif
