// Image files through OpenImageIO (see image_io.h).
#include "bench/image_io.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace {

lanes_status fail(lanes_error *err, const std::string &text)
{
    return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s", text.c_str());
}

float srgb_encode(float x)
{
    if (!(x > 0.0f)) return 0.0f;
    if (x >= 1.0f) return 1.0f;
    return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

bool holds_floats(const std::string &format)
{
    return format == "openexr" || format == "hdr" || format == "tiff" || format == "fits";
}

} // namespace

extern "C" lanes_status lanes_image_write(const char *path, int width, int height, const float *rgb,
                                          lanes_error *err)
{
    auto out = OIIO::ImageOutput::create(path);
    if (!out) {
        return fail(err, std::string(path) + ": cannot write this image format: " + OIIO::geterror());
    }
    // OpenImageIO's message for a file it cannot open leaves out the OS's
    // reason; opening it first (it is written next anyway) gives that.
    if (std::FILE *probe = std::fopen(path, "wb")) {
        std::fclose(probe);
    } else {
        return fail(err, std::string(path) + ": cannot write: " + std::strerror(errno));
    }
    bool linear = holds_floats(out->format_name());
    OIIO::ImageSpec spec(width, height, 3, linear ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    if (!linear) spec.attribute("oiio:ColorSpace", "sRGB");
    std::vector<float> pixels(rgb, rgb + static_cast<size_t>(width) * static_cast<size_t>(height) * 3);
    if (!linear)
        for (float &v : pixels) v = srgb_encode(v);
    if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) ||
        !out->close()) {
        return fail(err, std::string(path) + ": " + out->geterror());
    }
    return LANES_OK;
}

extern "C" lanes_status lanes_image_compare(const char *path_a, const char *path_b, double threshold,
                                            lanes_image_diff *diff, lanes_error *err)
{
    OIIO::ImageBuf a(path_a), b(path_b);
    if (!a.read(0, 0, true, OIIO::TypeDesc::FLOAT)) {
        return fail(err, std::string(path_a) + ": " + a.geterror());
    }
    if (!b.read(0, 0, true, OIIO::TypeDesc::FLOAT)) {
        return fail(err, std::string(path_b) + ": " + b.geterror());
    }
    if (a.spec().width != b.spec().width || a.spec().height != b.spec().height ||
        a.spec().nchannels != b.spec().nchannels) {
        return fail(err, std::string("images differ in size: ") + path_a + " and " + path_b);
    }
    auto r = OIIO::ImageBufAlgo::compare(a, b, static_cast<float>(threshold), static_cast<float>(threshold));
    diff->mean_error = r.meanerror;
    diff->max_error = r.maxerror;
    diff->pixels_over = static_cast<long long>(r.nfail);
    diff->pixels = static_cast<long long>(a.spec().width) * a.spec().height;
    return LANES_OK;
}
