/* Generated materials for the shading-coherence measurements (see
 * material_assign.h). */
#include "build/material_assign.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "simd/counter_random.h"

static const char *const assign_names[LANES_ASSIGN_COUNT] = {"object", "cluster", "random"};

const char *lanes_material_assign_name(lanes_material_assign a)
{
    return (unsigned)a < LANES_ASSIGN_COUNT ? assign_names[a] : "?";
}

int lanes_material_assign_from_name(const char *name)
{
    for (int i = 0; i < LANES_ASSIGN_COUNT; i++)
        if (strcmp(name, assign_names[i]) == 0) return i;
    return -1;
}

/* The grid cell of a triangle's centroid, 64 cells a side over the bounds. */
static uint32_t cell_of(const float *v, const float lo[3], const float hi[3])
{
    uint32_t key = 0;
    for (int a = 0; a < 3; a++) {
        float c = (v[a] + v[3 + a] + v[6 + a]) / 3.0f, ext = hi[a] - lo[a];
        int k = ext > 0.0f ? (int)((c - lo[a]) / ext * 64.0f) : 0;
        k = k < 0 ? 0 : k > 63 ? 63 : k;
        key = key * 64u + (uint32_t)k;
    }
    return key;
}

/* Material i of the generator: by i mod 8 diffuse, plastic, textured
 * diffuse, conductor, diffuse, textured plastic, diffuse, mirror (so one
 * material is plain diffuse); colors, roughness and textures from a hash
 * of i; textures of a size 1/16 of the scene's diagonal. */
static void generated_material(int i, float diagonal, lanes_material *m)
{
    static const lanes_material_kind kinds[8] = {LANES_MAT_DIFFUSE, LANES_MAT_PLASTIC, LANES_MAT_DIFFUSE, LANES_MAT_CONDUCTOR,
                                                 LANES_MAT_DIFFUSE, LANES_MAT_PLASTIC, LANES_MAT_DIFFUSE, LANES_MAT_MIRROR};
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "@mat%04d", i);
    m->kind = kinds[i % 8];
    uint32_t h = lanes_hash32((uint32_t)i * 3u + 1u), g = lanes_hash32(h);
    for (int c = 0; c < 3; c++) {
        m->color[c] = 0.15f + 0.7f * (float)((h >> (8 * c)) & 255u) / 255.0f;
        m->f0[c] = m->color[c];
    }
    m->ior = 1.5f;
    m->roughness = 0.1f + 0.5f * (float)(h >> 24) / 255.0f;
    if (i % 8 == 2 || i % 8 == 5) {
        m->texture = (lanes_material_texture)(LANES_MAT_TEXTURE_CHECKER + (i / 8) % 4);
        m->texture_scale = diagonal > 0.0f ? diagonal / 16.0f : 1.0f;
        for (int c = 0; c < 3; c++) {
            m->texture_colors[0][c] = m->color[c];
            m->texture_colors[1][c] = 0.1f + 0.8f * (float)((g >> (8 * c)) & 255u) / 255.0f;
            m->color[c] = 0.5f * (m->texture_colors[0][c] + m->texture_colors[1][c]);
        }
    }
}

lanes_status lanes_scene_assign_materials(lanes_scene *scene, int n, lanes_material_assign mode, lanes_error *err)
{
    if (n < 1 || n > LANES_ASSIGN_MAX_MATERIALS)
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "materials: %d generated materials (1..%d)", n,
                               LANES_ASSIGN_MAX_MATERIALS);
    if ((unsigned)mode >= LANES_ASSIGN_COUNT)
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "materials: assignment %d unknown", (int)mode);
    if (scene->material_count + (size_t)n > LANES_SCENE_MAX_MATERIALS)
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "materials: %d generated with the scene's %zu is more than the 65536 the stream sort takes",
                               n, scene->material_count);
    uint32_t first = (uint32_t)scene->material_count;
    float lo[3], hi[3];
    lanes_scene_bounds(scene, lo, hi);
    float diagonal = sqrtf((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                           (hi[2] - lo[2]) * (hi[2] - lo[2]));
    for (int i = 0; i < n; i++) {
        lanes_material m;
        generated_material(i, diagonal, &m);
        lanes_status st = lanes_scene_add_material(scene, &m, NULL, err);
        if (st != LANES_OK) return st;
    }
    uint32_t run = 0, previous = 0;
    for (size_t t = 0; t < scene->triangle_count; t++) {
        uint32_t own = scene->material_of[t];
        if (t > 0 && own != previous) run++;
        previous = own;
        if (own < first && scene->materials[own].kind == LANES_MAT_EMISSIVE) continue;
        uint32_t key = mode == LANES_ASSIGN_OBJECT    ? lanes_hash32(run * 2654435761u + 17u)
                       : mode == LANES_ASSIGN_CLUSTER ? lanes_hash32(cell_of(scene->verts + 9 * t, lo, hi) + 0x9e3779b9u)
                                                      : lanes_hash32((uint32_t)t * 2246822519u + 3u);
        scene->material_of[t] = first + key % (uint32_t)n;
    }
    return LANES_OK;
}
