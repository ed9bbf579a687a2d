/* libFuzzer target: ASCII PLY mesh files through lanes_mesh_read and
 * lanes_scene_load (see fuzz_mesh.h for the contract; seeds in
 * corpus/fuzz_mesh_ply/). Binary PLY goes through the same code with its
 * own seeds in fuzz_mesh_ply_binary: mutating ASCII seeds rarely produces a
 * well-formed binary body, and the other way round. */
#include "tests/fuzz/fuzz_mesh.h"

LANES_FUZZ_MESH_TARGET("ply")
