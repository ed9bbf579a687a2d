/* How much memory this process may use: the machine's physical memory, or
 * less where a cgroup limits it (a container's, a CI runner's, a systemd
 * slice's), or what the user sets in LANES_MEMORY_LIMIT. Linux overcommits,
 * so an allocation beyond the real limit may succeed and the OOM killer end
 * the process later, with no message; callers compare what they will need
 * with this before they start.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BUILD_MEMORY_LIMIT_H
#define LANES_BUILD_MEMORY_LIMIT_H

#include <stdbool.h>
#include <stddef.h>

#include "build/scene.h"

typedef enum lanes_memory_source {
    LANES_MEMORY_PHYSICAL, /* the machine's memory */
    LANES_MEMORY_CGROUP,   /* a cgroup limit below it */
    LANES_MEMORY_ENV,      /* LANES_MEMORY_LIMIT */
} lanes_memory_source;

typedef struct lanes_memory_limit {
    double bytes; /* INFINITY when nothing could be read */
    lanes_memory_source source;
    const char *bad_env; /* LANES_MEMORY_LIMIT's text when it is not a size; else NULL */
} lanes_memory_limit;

/* For this process. LANES_MEMORY_LIMIT, when set, overrides the rest: a byte
 * count, or a number followed by K, M or G (powers of 1024). Otherwise the
 * smaller of physical memory and the memory limits of this process's cgroup
 * and every ancestor (cgroup v2 memory.max, v1 memory.limit_in_bytes), read
 * from /proc/self/cgroup and /sys/fs/cgroup. */
lanes_memory_limit lanes_memory_limit_read(void);

/* The cgroup part from given files (tests point them at a tree of their
 * own): proc_cgroup in the format of /proc/self/cgroup, cgroup_root where
 * the hierarchies are mounted, physical the machine's memory in bytes. */
lanes_memory_limit lanes_memory_limit_from(const char *proc_cgroup, const char *cgroup_root, double physical);

/* LANES_ERR_OUT_OF_MEMORY, with "<what> needs about X GiB; this machine has Y GiB of memory"
 * (or what limits it instead: a cgroup, LANES_MEMORY_LIMIT), when bytes
 * exceed what lanes_memory_limit_read says this process may use:
 * allocations that large may succeed (Linux overcommits) and end in the OOM
 * killer instead. LANES_ERR_BAD_INPUT, with a message, when
 * LANES_MEMORY_LIMIT is set to something that is not a size. */
lanes_status lanes_memory_fits(const char *what, double bytes, lanes_error *err);

/* The loaders' policy for a scene they are about to fill, which is loaded
 * to be traced: a triangle budget (scene->triangle_budget, budget_note)
 * from what the scene and its BVHs need per triangle and what this process
 * may use, read once here rather than on every append. LANES_ERR_BAD_INPUT,
 * with a message, when LANES_MEMORY_LIMIT is not a size. */
lanes_status lanes_scene_limit_to_memory(lanes_scene *scene, lanes_error *err);

/* "29.2 GiB", "9.4 MiB": one decimal in the largest unit that keeps a
 * leading digit. Returns buf. */
const char *lanes_memory_size_text(char *buf, size_t size, double bytes);

/* A size as LANES_MEMORY_LIMIT takes it; false for anything else (empty,
 * negative, trailing text, zero). */
bool lanes_memory_size_parse(const char *text, double *bytes);

#endif
