/* Mesh files through Assimp (OBJ, PLY, OFF, STL, glTF/GLB and whatever
 * else the installed Assimp reads).
 *
 * Assimp is lenient: it silently repairs out-of-range OFF indices, reads
 * past truncated PLY bodies, and allocates whatever a header claims before
 * looking at the data (a 40-byte OFF file declaring 2e9 faces makes it
 * allocate tens of gigabytes). So OBJ, OFF, PLY and STL files are first
 * checked by a streaming validator of our own that uses constant memory
 * and reports the line (or byte offset, for binary data) of the first
 * problem; then Assimp imports; then what Assimp returns is checked again
 * (finite coordinates, indices < vertex count, sane counts) for every
 * format. Other formats get only the last check. Where Assimp's reader and
 * the validator would read a file differently (line structure, signs,
 * numbers Assimp stops inside), the file is refused: the fuzzers in
 * tests/fuzz/ found crashes and leaks in Assimp behind each such case.
 *
 * A mesh must be a regular file whose extension Assimp knows: for any
 * other, Assimp tries every importer on the content, and so would bypass
 * these checks. Assimp opens only regular files (the mesh, and the
 * material or buffer files it names).
 *
 * Not thread-safe: Assimp's C API keeps its last error in a global.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BUILD_MESH_IMPORT_H
#define LANES_BUILD_MESH_IMPORT_H

#include <stdbool.h>

#include "build/scene.h"

/* Reads every triangle of the file into one indexed mesh, with the node
 * hierarchy's transforms applied (a mesh used by several nodes appears once
 * per use). Polygons are triangulated; points and lines are dropped.
 * Vertices at the same position are joined, so the result has
 * connectivity whatever the format stored per corner. */
lanes_status lanes_mesh_read(const char *path, lanes_mesh *out, lanes_error *err);

/* lanes_mesh_read, then lanes_scene_add_mesh with the extra transform xf
 * (NULL: none) and the given material. */
lanes_status lanes_mesh_import(lanes_scene *scene, const char *path, const lanes_xform *xf, uint32_t material,
                               lanes_error *err);

/* Only the streaming validator (no Assimp). LANES_OK for formats it
 * does not know. Exposed for tests. */
lanes_status lanes_mesh_precheck(const char *path, lanes_error *err);
/* The pre-check, and the faces the file declares (each becomes at least
 * one triangle; 0 for formats it does not know), for the scene loader's
 * estimate before it reads anything. */
lanes_status lanes_mesh_declared_faces(const char *path, double *faces, lanes_error *err);

#endif
