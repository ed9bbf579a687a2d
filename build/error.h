/* The one error convention inside lanes, the public API's: a function that can
 * fail returns a lanes_status (LANES_OK = 0) and, when it fails, fills the
 * caller's lanes_error with the same status and a message naming the file, the
 * line where there is one, and the problem. err may be NULL for callers that
 * want the status only. The public calls hand status and message on as they
 * are (lanes_api.c), so a build that ran out of memory deep inside the BVH
 * builder reaches the user as LANES_ERR_OUT_OF_MEMORY, not as bad input.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BUILD_ERROR_H
#define LANES_BUILD_ERROR_H

#include "lanes/lanes.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct lanes_error {
    lanes_status status;
    char message[512];
} lanes_error;

/* Records status and a printf-formatted message (truncated to fit) in err and
 * returns status, so that a failure reads `return lanes_error_set(err, ...)`. */
lanes_status lanes_error_set(lanes_error *err, lanes_status status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

#ifdef __cplusplus
}
#endif

#endif
