/* libFuzzer target: GLB mesh files through lanes_mesh_read and lanes_scene_load
 * (see fuzz_mesh.h for the contract; seeds in corpus/fuzz_mesh_glb/). */
#include "tests/fuzz/fuzz_mesh.h"

LANES_FUZZ_MESH_TARGET("glb")
