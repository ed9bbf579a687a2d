/* Image files through OpenImageIO, behind a C interface: the only C++ in
 * lanes is its implementation, image_io.cpp. */
#ifndef LANES_BENCH_IMAGE_IO_H
#define LANES_BENCH_IMAGE_IO_H

#include "build/error.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Writes linear RGB floats (width * height * 3). Formats that hold floats
 * (EXR, HDR, float TIFF) get linear values; 8-bit formats (PNG, JPEG, ...)
 * get sRGB-encoded values clamped to [0, 1]. The format follows the file
 * name's extension, as OpenImageIO decides it. */
lanes_status lanes_image_write(const char *path, int width, int height, const float *rgb, lanes_error *err);

/* Compares two image files pixel by pixel (OIIO's ImageBufAlgo::compare,
 * the engine behind idiff). Fails when they cannot be read or differ in
 * size. */
typedef struct lanes_image_diff {
    double mean_error, max_error;
    long long pixels_over;   /* pixels whose error exceeds the threshold */
    long long pixels;
} lanes_image_diff;
lanes_status lanes_image_compare(const char *path_a, const char *path_b, double threshold,
                                 lanes_image_diff *diff, lanes_error *err);

#ifdef __cplusplus
}
#endif

#endif
