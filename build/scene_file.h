/* The JSON scene format (documented in build/SCENES.md), read with cJSON.
 *
 * Strict: unknown keys, duplicate keys, wrong types, missing required
 * fields, out-of-range values and references to undefined materials are
 * errors. Every message names the file, the line where it can be found and
 * the JSON path, e.g.
 *   scene.json: line 12: materials.red: unknown key 'colour' (valid: type, color)
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BUILD_SCENE_FILE_H
#define LANES_BUILD_SCENE_FILE_H

#include <stdbool.h>
#include <stddef.h>

#include "build/scene.h"

/* Reads the file; relative mesh paths are resolved against its directory.
 * *out is initialized by the call and empty on failure. */
lanes_status lanes_scene_file_load(const char *path, lanes_scene *out, lanes_error *err);

/* The same from text in memory (need not be NUL-terminated). `name` is
 * used in messages; base_dir resolves relative mesh paths (NULL: the
 * current directory). */
lanes_status lanes_scene_file_parse(const char *text, size_t len, const char *name, const char *base_dir,
                                    lanes_scene *out, lanes_error *err);

#endif
