/* lanes_error: see error.h. */
#include "build/error.h"

#include <stdarg.h>
#include <stdio.h>

lanes_status lanes_error_set(lanes_error *err, lanes_status status, const char *fmt, ...)
{
    if (!err) return status;
    err->status = status;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->message, sizeof err->message, fmt, ap);
    va_end(ap);
    return status;
}
