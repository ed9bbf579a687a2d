/* The memory a process may use: physical memory and cgroup limits.
 *
 * Compiled for the x86-64 baseline. */
#define _DEFAULT_SOURCE /* sysconf(_SC_PHYS_PAGES) */
#include "build/memory_limit.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* A limit file holds a byte count or "max" (v2: no limit); v1 writes its
 * "no limit" as a count near 2^63, which loses to physical memory anyway.
 * INFINITY for "max", for 0 and for anything unreadable. */
static double read_limit_file(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f) return INFINITY;
    char text[64];
    bool got = fgets(text, sizeof text, f) != NULL;
    fclose(f);
    if (!got || !isdigit((unsigned char)text[0])) return INFINITY;
    errno = 0;
    char *end;
    unsigned long long bytes = strtoull(text, &end, 10);
    while (isspace((unsigned char)*end)) end++;
    if (errno || *end || bytes == 0) return INFINITY;
    return (double)bytes;
}

/* The smallest limit in `file` of the cgroup `dir` + `path` and of every
 * ancestor up to `dir` itself: a parent's limit binds its children too. */
static double smallest_limit_up(const char *dir, const char *path, const char *file)
{
    char sub[4096];
    if (snprintf(sub, sizeof sub, "%s", path) >= (int)sizeof sub) return INFINITY;
    double smallest = INFINITY;
    for (;;) {
        size_t n = strlen(sub);
        while (n > 0 && sub[n - 1] == '/') sub[--n] = '\0';
        char full[8192];
        if (snprintf(full, sizeof full, "%s%s/%s", dir, sub, file) < (int)sizeof full)
            smallest = fmin(smallest, read_limit_file(full));
        char *slash = strrchr(sub, '/');
        if (!slash) break;
        *slash = '\0';
    }
    return smallest;
}

/* Whether the comma-separated controller list names the memory controller. */
static bool lists_memory(const char *controllers, size_t n)
{
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && controllers[j] != ',') j++;
        if (j - i == 6 && memcmp(controllers + i, "memory", 6) == 0) return true;
        i = j + 1;
    }
    return false;
}

lanes_memory_limit lanes_memory_limit_from(const char *proc_cgroup, const char *cgroup_root, double physical)
{
    lanes_memory_limit limit = {physical > 0 ? physical : INFINITY, LANES_MEMORY_PHYSICAL, NULL};
    FILE *f = fopen(proc_cgroup, "r");
    if (!f) return limit;
    char line[4096];
    while (fgets(line, sizeof line, f)) {
        line[strcspn(line, "\n")] = '\0';
        /* hierarchy-id:controllers:path */
        char *c1 = strchr(line, ':');
        char *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
        if (!c2) continue;
        const char *controllers = c1 + 1, *path = c2 + 1;
        size_t nc = (size_t)(c2 - controllers);
        double cg = INFINITY;
        if (nc == 0 && strncmp(line, "0:", 2) == 0) { /* v2: one unified hierarchy */
            cg = smallest_limit_up(cgroup_root, path, "memory.max");
        } else if (lists_memory(controllers, nc)) { /* v1: mounted under its controller list */
            char dir[4096];
            if (snprintf(dir, sizeof dir, "%s/%.*s", cgroup_root, (int)nc, controllers) < (int)sizeof dir)
                cg = smallest_limit_up(dir, path, "memory.limit_in_bytes");
        }
        if (cg < limit.bytes) limit = (lanes_memory_limit){cg, LANES_MEMORY_CGROUP, NULL};
    }
    fclose(f);
    return limit;
}

bool lanes_memory_size_parse(const char *text, double *bytes)
{
    if (!text || !isdigit((unsigned char)text[0])) return false;
    errno = 0;
    char *end;
    double x = strtod(text, &end);
    if (errno || end == text) return false;
    static const char units[] = "KMG";
    const char *unit = *end ? strchr(units, toupper((unsigned char)*end)) : NULL;
    if (unit) {
        x *= pow(1024.0, (double)(unit - units + 1));
        end++;
    }
    if (*end || !(x >= 1.0) || !isfinite(x)) return false;
    *bytes = x;
    return true;
}

lanes_memory_limit lanes_memory_limit_read(void)
{
    const char *env = getenv("LANES_MEMORY_LIMIT");
    if (env && *env) {
        double bytes;
        if (lanes_memory_size_parse(env, &bytes)) return (lanes_memory_limit){bytes, LANES_MEMORY_ENV, NULL};
        lanes_memory_limit bad = {INFINITY, LANES_MEMORY_ENV, env};
        return bad;
    }
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    double physical = pages > 0 && page > 0 ? (double)pages * (double)page : INFINITY;
    return lanes_memory_limit_from("/proc/self/cgroup", "/sys/fs/cgroup", physical);
}

const char *lanes_memory_size_text(char *buf, size_t size, double bytes)
{
    static const char *const units[] = {"bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
    int u = 0;
    while (bytes >= 1024.0 && u < 6) bytes /= 1024.0, u++;
    snprintf(buf, size, u ? "%.1f %s" : "%.0f %s", bytes, units[u]);
    return buf;
}

/* What `limit` allows, as "this machine has 23.4 GiB of memory"; an error,
 * with the message, when LANES_MEMORY_LIMIT is not a size. */
static lanes_status describe(const lanes_memory_limit *limit, char *note, size_t size, lanes_error *err)
{
    if (limit->bad_env) {
        return lanes_error_set(
            err, LANES_ERR_BAD_INPUT,
            "LANES_MEMORY_LIMIT '%s' is not a size (bytes, or a number followed by K, M or G)",
            limit->bad_env);
    }
    static const char *const has[] = {
        [LANES_MEMORY_PHYSICAL] = "this machine has",
        [LANES_MEMORY_CGROUP] = "this process's cgroup allows it",
        [LANES_MEMORY_ENV] = "LANES_MEMORY_LIMIT allows",
    };
    char have[32];
    snprintf(note, size, "%s %s of memory", has[limit->source], lanes_memory_size_text(have, sizeof have, limit->bytes));
    return LANES_OK;
}

lanes_status lanes_memory_fits(const char *what, double bytes, lanes_error *err)
{
    lanes_status status;
    lanes_memory_limit limit = lanes_memory_limit_read();
    char note[96], need[32];
    if ((status = describe(&limit, note, sizeof note, err)) != LANES_OK) return status;
    if (bytes <= limit.bytes) return LANES_OK;
    return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "%s needs about %s; %s", what,
                           lanes_memory_size_text(need, sizeof need, bytes), note);
}

lanes_status lanes_scene_limit_to_memory(lanes_scene *scene, lanes_error *err)
{
    lanes_status status;
    lanes_memory_limit limit = lanes_memory_limit_read();
    if ((status = describe(&limit, scene->budget_note, sizeof scene->budget_note, err)) != LANES_OK)
        return status;
    const double per_triangle = (double)(LANES_SCENE_BYTES_PER_TRIANGLE + LANES_ACCEL_BYTES_PER_TRIANGLE);
    scene->triangle_budget = (size_t)fmin(floor(limit.bytes / per_triangle), (double)LANES_SCENE_MAX_TRIANGLES);
    return LANES_OK;
}
