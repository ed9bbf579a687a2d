/* The generated materials of build/material_assign.c on the default scene:
 * the lights keep theirs and every other triangle gets a generated one;
 * triangles of one object (cluster cell) share it; at random, the draws
 * spread over all of them; refusals of 0 and too many. */
#include <stdlib.h>
#include <string.h>

#include "build/material_assign.h"
#include "build/scenes_builtin.h"
#include "harness.h"

static bool load(lanes_scene *s)
{
    lanes_error err;
    return CHECK(lanes_builtin_scene("default", s, &err) == LANES_OK, "default scene: %s", err.message);
}

int main(void)
{
    for (int mode = 0; mode < LANES_ASSIGN_COUNT; mode++) {
        lanes_scene s;
        if (!load(&s)) continue;
        size_t own = s.material_count;
        uint32_t *before = malloc(s.triangle_count * sizeof *before);
        if (!before) return 2;
        memcpy(before, s.material_of, s.triangle_count * sizeof *before);
        lanes_error err;
        const int n = 36;
        if (!CHECK(lanes_scene_assign_materials(&s, n, (lanes_material_assign)mode, &err) == LANES_OK, "%s: %s",
                   lanes_material_assign_name((lanes_material_assign)mode), err.message))
            continue;
        CHECK(s.material_count == own + (size_t)n && strcmp(s.materials[own].name, "@mat0000") == 0,
              "%zu materials after adding %d to %zu", s.material_count, n, own);
        long kept = 0, wrong = 0, split = 0;
        int used[36] = {0};
        for (size_t t = 0; t < s.triangle_count; t++) {
            bool light = s.materials[before[t]].kind == LANES_MAT_EMISSIVE;
            if (light) {
                kept += s.material_of[t] == before[t];
                wrong += s.material_of[t] != before[t];
                continue;
            }
            if (s.material_of[t] < own) {
                wrong++;
                continue;
            }
            used[s.material_of[t] - own] = 1;
            /* within an object (a run of one original material), the same */
            if (mode == LANES_ASSIGN_OBJECT && t > 0 && before[t] == before[t - 1] &&
                s.materials[before[t - 1]].kind != LANES_MAT_EMISSIVE)
                split += s.material_of[t] != s.material_of[t - 1];
        }
        int distinct = 0;
        for (int i = 0; i < n; i++) distinct += used[i];
        CHECK(wrong == 0 && kept > 0, "%s: %ld triangles wrong (lights must keep theirs: %ld kept)",
              lanes_material_assign_name((lanes_material_assign)mode), wrong, kept);
        CHECK(split == 0, "object: %ld triangles of one object with another material", split);
        printf("  %s: %d of %d materials used over %zu triangles\n", lanes_material_assign_name((lanes_material_assign)mode),
               distinct, n, s.triangle_count);
        if (mode == LANES_ASSIGN_RANDOM)
            CHECK(distinct == n, "random: only %d of %d materials drawn over %zu triangles", distinct, n, s.triangle_count);
        else
            CHECK(distinct > 1 && distinct <= n, "%s: %d materials used", lanes_material_assign_name((lanes_material_assign)mode),
                  distinct);
        free(before);
        lanes_scene_free(&s);
    }
    lanes_scene s;
    if (load(&s)) {
        lanes_error err;
        CHECK(lanes_scene_assign_materials(&s, 0, LANES_ASSIGN_RANDOM, &err) == LANES_ERR_BAD_INPUT &&
                  strstr(err.message, "0 generated"),
              "0 materials: %s", err.message);
        CHECK(lanes_scene_assign_materials(&s, 70000, LANES_ASSIGN_RANDOM, &err) == LANES_ERR_BAD_INPUT,
              "70000 materials: %s", err.message);
        lanes_scene_free(&s);
    }
    return harness_summary("test_material_assign");
}
