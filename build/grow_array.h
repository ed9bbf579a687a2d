/* Room for one more element, and then some: the append helpers' growth. */
#ifndef LANES_BUILD_GROW_ARRAY_H
#define LANES_BUILD_GROW_ARRAY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

/* Grows *array (of *cap elements of `size` bytes, from malloc or NULL) to
 * hold `need`. Growth is geometric so repeated appends stay linear overall;
 * every size is checked against SIZE_MAX before multiplying. On failure the
 * array and *cap are unchanged. */
static inline bool lanes_grow_array(void **array, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap) return true;
    size_t new_cap = *cap < 16 ? 16 : *cap;
    while (new_cap < need) {
        if (new_cap > SIZE_MAX / 2) {
            new_cap = need;
            break;
        }
        new_cap *= 2;
    }
    if (new_cap > SIZE_MAX / size) return false;
    void *p = realloc(*array, new_cap * size);
    if (!p) return false;
    *array = p;
    *cap = new_cap;
    return true;
}

#endif
