/* Whether a name is in a comma-separated list, for the tests' --isa a,b,...
 * and --family options; apart from harness.h so that the tests with their
 * own check machinery (test_kernels, test_simd_ops) take it alone. */
#ifndef LANES_TESTS_NAME_LIST_H
#define LANES_TESTS_NAME_LIST_H

#include <stdbool.h>
#include <string.h>

/* name is in list (NULL: every name). */
static inline bool harness_in_list(const char *list, const char *name)
{
    if (!list) return true;
    size_t len = strlen(name);
    for (const char *p = list; *p;) {
        const char *e = strchr(p, ',');
        size_t l = e ? (size_t)(e - p) : strlen(p);
        if (l == len && strncmp(p, name, len) == 0) return true;
        if (!e) break;
        p = e + 1;
    }
    return false;
}

#endif
