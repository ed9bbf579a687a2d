/* libFuzzer target: JSON scene files (build/SCENES.md) through
 * lanes_scene_file_parse, the in-memory entry point lanes_scene_file_load
 * reads files into.
 *
 * Contract (fuzz_common.h): a valid scene, or a message naming the file.
 *
 * Scene files name mesh files and built-in objects, which this target must
 * keep small and local:
 *  - relative mesh paths resolve against a scratch directory holding a few
 *    tiny meshes (good and bad), written at start-up; an input whose "mesh"
 *    names anything outside it (a '/' or a dot-only name) is skipped, so
 *    the fuzzer never reads /dev/zero or a system library;
 *  - LANES_MESH_DIR points at the same directory, where a tetrahedron
 *    stands in for each CGAL mesh (bunny, dragon, ...);
 *  - an input whose objects would add up to more than FUZZ_MAX_TRIANGLES
 *    is skipped. A scene file may legitimately ask for a 33-million-
 *    triangle plane ("detail": 4096) and get 1.2 GB of triangles; that is a
 *    valid request, not a parser bug, but it would trip -malloc_limit_mb.
 *    The estimate reads the input with the same cJSON the parser uses. */
#include "tests/fuzz/fuzz_common.h"

#include "build/scene_file.h"

#include <cjson/cJSON.h>

#define FUZZ_MAX_TRIANGLES 4000000.0

static const struct {
    const char *name, *text;
} fuzz_meshes[] = {
    {"tet.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"},
    {"quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"},
    {"tet.off", "OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"},
    {"tet.ply", "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                "property float z\nelement face 4\nproperty list uchar int vertex_indices\n"
                "end_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"},
    {"tri.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                "vertex 0 1 0\nendloop\nendfacet\nendsolid t\n"},
    {"flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"},
    {"huge.obj", "v 1e38 1e38 1e38\nv -1e38 0 0\nv 0 -1e38 0\nf 1 2 3\n"},
    {"bad.obj", "v 0 0 0\nf 1 2 3\n"},
    {"bad.off", "OFF\n4000000000 1 0\n"},
    {"empty.obj", ""},
    /* Stand-ins for the CGAL meshes of the built-in objects. */
    {"bunny00.off", "OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"},
    {"ChineseDragon-10kv.off", "OFF\n3 1 3\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
    {"armadillo.off", "OFF\n3 1 3\n0 0 0\n0 0 1\n0 1 0\n3 0 1 2\n"},
    {"elephant.off", "OFF\n4 2 5\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n1 0\n"},
};

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    char path[512];
    for (size_t i = 0; i < sizeof fuzz_meshes / sizeof fuzz_meshes[0]; i++)
        fuzz_write(path, sizeof path, fuzz_meshes[i].name, fuzz_meshes[i].text,
                   strlen(fuzz_meshes[i].text));
    setenv("LANES_MESH_DIR", fuzz_dir(), 1);
    return 0;
}

/* The detail the parser would accept, else -1 (the default: the parser
 * then fails or uses the default, never something larger). */
static int detail_of(const cJSON *o)
{
    const cJSON *d = cJSON_GetObjectItemCaseSensitive(o, "detail");
    if (!cJSON_IsNumber(d) || !(d->valuedouble >= 0 && d->valuedouble <= 4096) ||
        d->valuedouble != (double)(int)d->valuedouble)
        return -1;
    return (int)d->valuedouble;
}

/* Upper bound on the triangles of one object; <0: skip the input. */
static double object_cost(const cJSON *o)
{
    int d = detail_of(o);
    const cJSON *mesh = cJSON_GetObjectItemCaseSensitive(o, "mesh");
    const cJSON *builtin = cJSON_GetObjectItemCaseSensitive(o, "builtin");
    if (cJSON_IsString(mesh)) {
        const char *p = mesh->valuestring;
        if (strchr(p, '/') || strspn(p, ".") == strlen(p))
            return -1.0;
    }
    /* The scratch meshes and stand-ins have at most 4 triangles; mesh
     * files and CGAL meshes take up to 4 Loop steps (x4 each). */
    double loop = d > 4 ? 0.0 : 4.0 * pow(4.0, d < 0 ? 0 : d);
    if (cJSON_IsString(mesh))
        return loop;
    if (!cJSON_IsString(builtin))
        return 0.0;
    const char *b = builtin->valuestring;
    if (strcmp(b, "sphere") == 0)
        return d > 8 ? 0.0 : 20.0 * pow(4.0, d < 0 ? 3 : d);
    if (strcmp(b, "plane") == 0) {
        double n = d < 1 ? 1 : d;
        return 2.0 * n * n;
    }
    if (strcmp(b, "cylinder") == 0)
        return 4.0 * (d < 3 ? 32 : d);
    if (strcmp(b, "box") == 0)
        return 12.0;
    return loop;
}

static bool affordable(const uint8_t *data, size_t size)
{
    size_t skip = size >= 3 && memcmp(data, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0;
    cJSON *root = cJSON_ParseWithLength((const char *)data + skip, size - skip);
    if (!root)
        return true; /* a syntax error: nothing gets built */
    double total = 0.0;
    const cJSON *o;
    /* Every "objects" key, not only the first: the parser rejects
     * duplicates, but only after this point would matter. */
    for (const cJSON *k = root->child; k; k = k->next) {
        if (!k->string || strcmp(k->string, "objects") != 0)
            continue;
        cJSON_ArrayForEach(o, k)
        {
            double c = object_cost(o);
            if (c < 0.0) {
                cJSON_Delete(root);
                return false;
            }
            total += c;
        }
    }
    cJSON_Delete(root);
    return total <= FUZZ_MAX_TRIANGLES;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!affordable(data, size))
        return 0;
    static const char name[] = "fuzz.json";
    lanes_scene s;
    lanes_error err = {0};
    if (lanes_scene_file_parse((const char *)data, size, name, fuzz_dir(), &s, &err) == LANES_OK) {
        fuzz_check_scene(&s, name);
        lanes_scene_free(&s);
    } else {
        fuzz_check_failure(&err, name);
        if (strncmp(err.message, "fuzz.json: ", 11) != 0)
            fuzz_violation("the message does not start with the file: \"%s\"", err.message);
        if (s.triangle_count != 0 || s.verts || s.materials)
            fuzz_violation("failure left a non-empty scene");
    }
    return 0;
}
