/* libFuzzer target: binary PLY (little- and big-endian) mesh files; the
 * same loader as fuzz_mesh_ply, with seeds of its own in
 * corpus/fuzz_mesh_ply_binary/ (see fuzz_mesh_ply.c for why two targets). */
#include "tests/fuzz/fuzz_mesh.h"

LANES_FUZZ_MESH_TARGET("ply")
