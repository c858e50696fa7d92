/*
 * oiio_module.cpp - the image module libilfkit_oiio.so: reading headers and
 * decoding pixels with OpenImageIO behind the entry table of module.h, which
 * image/src/image.c loads on the first image read (writes go through
 * writers.c, which needs no OpenImageIO). This is the
 * only file in ilfkit that includes OpenImageIO headers, and the only C++
 * source of the image library.
 *
 * Invariants:
 *   - The only exported symbol is the entry function; everything else has
 *     hidden visibility (the module is built with -fvisibility=hidden).
 *   - No exception leaves a table function: each body runs inside a try
 *     block and turns exceptions into a status and message.
 *   - Nothing here calls ilfkit's libraries: messages go to the caller's
 *     buffer, one line, naming the image's final path.
 */
#include "module.h"

#include <OpenImageIO/imageio.h>

#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <new>
#include <string>

namespace {

/* The reader's bounds (image/image.h; their reasons in ilf/limits.h). */
constexpr long long max_side = IMG_MAX_SIDE;
constexpr long long max_samples = IMG_MAX_SAMPLES;

/* Formats a message into msg. @return status. */
img_status fail(img_status status, char *msg, size_t msglen, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    std::vsnprintf(msg, msglen, fmt, ap);
    va_end(ap);
    return status;
}

/* OpenImageIO's messages may span lines; keep the first so errors stay one line. */
std::string first_line(std::string text)
{
    size_t nl = text.find('\n');
    if (nl != std::string::npos)
        text.erase(nl);
    return text.empty() ? std::string("unknown OpenImageIO error") : text;
}

/* @return whether t is an integer sample type, which OpenImageIO normalises to [0, 1] when converting to float. */
bool is_integer_type(OIIO::TypeDesc t)
{
    return t.basetype != OIIO::TypeDesc::HALF && t.basetype != OIIO::TypeDesc::FLOAT &&
           t.basetype != OIIO::TypeDesc::DOUBLE;
}

/* Opens path and checks the size its header gives against the reader's bounds. @return IMG_OK with *in open. */
img_status open_checked(const char *path, std::unique_ptr<OIIO::ImageInput> &in, char *msg, size_t msglen)
{
    in = OIIO::ImageInput::open(path);
    if (!in)
        return fail(IMG_ERR_INPUT, msg, msglen, "%s: not a readable image: %s", path,
                    first_line(OIIO::geterror()).c_str());
    const OIIO::ImageSpec &spec = in->spec();
    long long samples = static_cast<long long>(spec.width) * spec.height * spec.nchannels;
    if (spec.width < 1 || spec.height < 1 || spec.nchannels < 1 || spec.width > max_side ||
        spec.height > max_side || spec.depth > 1 || samples > max_samples)
        return fail(IMG_ERR_INPUT, msg, msglen, "%s: unsupported image size %dx%dx%d with %d channels", path,
                    spec.width, spec.height, spec.depth, spec.nchannels);
    return IMG_OK;
}

/* Fills hdr from spec, whose size open_checked() accepted. */
void describe(const OIIO::ImageSpec &spec, img_header *hdr)
{
    hdr->width = spec.width;
    hdr->height = spec.height;
    hdr->channels = spec.nchannels;
    hdr->integer = is_integer_type(spec.format) ? 1 : 0;
    hdr->bits = static_cast<int>(spec.format.size() * 8);
}

img_status read_header(const char *path, img_header *hdr, char *msg, size_t msglen)
{
    std::unique_ptr<OIIO::ImageInput> in;
    img_status status = open_checked(path, in, msg, msglen);
    if (status == IMG_OK)
        describe(in->spec(), hdr);
    return status;
}

img_status read_pixels(const char *path, img_image *img, char *msg, size_t msglen)
{
    std::unique_ptr<OIIO::ImageInput> in;
    img_status status = open_checked(path, in, msg, msglen);
    if (status != IMG_OK)
        return status;
    const OIIO::ImageSpec &spec = in->spec();
    long long samples = static_cast<long long>(spec.width) * spec.height * spec.nchannels;
    float *buf = static_cast<float *>(std::malloc(static_cast<size_t>(samples) * sizeof(float)));
    if (buf == nullptr)
        return fail(IMG_ERR_NOMEM, msg, msglen, "%s: out of memory for %lld samples", path, samples);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, buf)) {
        std::free(buf);
        return fail(IMG_ERR_INPUT, msg, msglen, "%s: cannot read image data: %s", path,
                    first_line(in->geterror()).c_str());
    }
    img_header hdr;
    describe(spec, &hdr);
    img->width = hdr.width;
    img->height = hdr.height;
    img->channels = hdr.channels;
    img->pixels = buf;
    img->integer = hdr.integer;
    img->bits = hdr.bits;
    return IMG_OK;
}

/* Runs body (a reader) with every exception turned into a status and message naming path. */
template <typename Body> img_status guarded(const char *path, char *msg, size_t msglen, Body body)
{
    try {
        return body();
    } catch (const std::bad_alloc &) {
        return fail(IMG_ERR_NOMEM, msg, msglen, "%s: out of memory while reading", path);
    } catch (const std::exception &e) {
        return fail(IMG_ERR_INPUT, msg, msglen, "%s: %s", path, e.what());
    } catch (...) {
        return fail(IMG_ERR_INPUT, msg, msglen, "%s: unexpected error while reading", path);
    }
}

/* Table entry: read_pixels, guarded. */
img_status module_read(const char *path, img_image *img, char *msg, size_t msglen)
{
    return guarded(path, msg, msglen, [&] { return read_pixels(path, img, msg, msglen); });
}

/* Table entry: read_header, guarded. */
img_status module_header(const char *path, img_header *hdr, char *msg, size_t msglen)
{
    return guarded(path, msg, msglen, [&] { return read_header(path, hdr, msg, msglen); });
}

const img__module table = {IMG__MODULE_VERSION, module_read, module_header};

} // namespace

/* The module's one exported symbol, named by IMG__MODULE_ENTRY. */
extern "C" __attribute__((visibility("default"))) const img__module *ilfkit_image_module(void)
{
    return &table;
}
