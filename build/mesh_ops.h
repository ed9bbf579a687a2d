/* Operations on indexed meshes: Loop subdivision, decimation by vertex
 * clustering, and the transform that normalizes a mesh's placement.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BUILD_MESH_OPS_H
#define LANES_BUILD_MESH_OPS_H

#include "build/scene.h"

/* One step of Loop subdivision (each triangle becomes four, positions
 * smoothed; boundary and non-manifold edges are kept sharp). */
lanes_status lanes_mesh_subdivide(const lanes_mesh *in, lanes_mesh *out, lanes_error *err);
/* Vertex clustering on a grid of `cells` cells along the longest axis:
 * a coarse version of a dense mesh (degenerate triangles are dropped). */
lanes_status lanes_mesh_decimate(const lanes_mesh *in, int cells, lanes_mesh *out, lanes_error *err);
/* The transform that maps the mesh's bounds to the built-in objects'
 * placement (lanes_builtin_object: centered in x and z, min y = 0, largest
 * extent 1). */
void lanes_mesh_normalizing_xform(const lanes_mesh *m, lanes_xform *out);

#endif
