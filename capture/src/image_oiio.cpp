/*
 * image_oiio.cpp - the C interface of capture/image.h implemented with
 * OpenImageIO. This is the only file in ilfkit that includes OpenImageIO
 * headers, and the only C++ source of the capture library.
 *
 * Invariants:
 *   - No exception leaves an extern "C" function: each body runs inside a
 *     try block and turns exceptions into a status and message.
 *   - EXR is written as 32-bit float, PNG as 8-bit; the format is chosen by
 *     the final path's extension, never guessed from content.
 *   - A write either leaves a complete image at the path (renamed from a
 *     flushed temporary in the same folder, so the rename is atomic) or
 *     leaves the path as it was and no temporary behind.
 */
#include "capture/image.h"
#include "internal.h"

#include <OpenImageIO/imageio.h>

#include <cctype>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <string>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace {

/* Largest accepted image side and sample count: far beyond what ilf writes,
 * small enough that a corrupt header cannot make us allocate without bound. */
constexpr long long max_side = CAP_IMAGE_MAX_SIDE;
constexpr long long max_samples = 1LL << 31;

/* Formats a message into err (when given) and the thread's capture message. @return status. */
cap_status fail(cap_status status, char *err, size_t errlen, const char *fmt, ...)
{
    char text[1024];
    va_list ap;
    va_start(ap, fmt);
    std::vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    if (err != nullptr && errlen > 0)
        std::snprintf(err, errlen, "%s", text);
    return cap__fail_text(status, text);
}

/* OpenImageIO's messages may span lines; keep the first so errors stay one line. */
std::string first_line(std::string text)
{
    size_t nl = text.find('\n');
    if (nl != std::string::npos)
        text.erase(nl);
    return text.empty() ? std::string("unknown OpenImageIO error") : text;
}

const char *extension_of(const char *path)
{
    const char *slash = std::strrchr(path, '/');
    const char *dot = std::strrchr(path, '.');
    return dot != nullptr && (slash == nullptr || dot > slash) ? dot + 1 : "";
}

bool equals_ignoring_case(const char *a, const char *b)
{
    for (; *a != '\0' && *b != '\0'; a++, b++)
        if (std::tolower(static_cast<unsigned char>(*a)) != std::tolower(static_cast<unsigned char>(*b)))
            return false;
    return *a == *b;
}

/* A temporary next to path, created exclusively, keeping the extension so
 * that nothing downstream mistakes its format. Returns "" on failure. */
std::string make_temporary(const char *path, const char *ext)
{
    std::string dir, base;
    const char *slash = std::strrchr(path, '/');
    if (slash != nullptr) {
        dir.assign(path, static_cast<size_t>(slash - path) + 1);
        base = slash + 1;
    } else {
        base = path;
    }
    std::string name = dir + "." + base + ".tmp-XXXXXX." + ext;
    int suffix = static_cast<int>(std::strlen(ext)) + 1;
    int fd = mkstemps(&name[0], suffix);
    if (fd < 0)
        return std::string();
    /* mkstemps creates mode 0600: a replaced image keeps its mode, a new one gets
     * the mode the user's umask gives new files. */
    struct stat old;
    mode_t mask = umask(0);
    umask(mask);
    mode_t mode = stat(path, &old) == 0 && S_ISREG(old.st_mode) ? (old.st_mode & 07777) : (0666 & ~mask);
    if (fchmod(fd, mode) != 0 || close(fd) != 0) {
        unlink(name.c_str());
        return std::string();
    }
    return name;
}

bool flush_to_disk(const std::string &name)
{
    int fd = open(name.c_str(), O_RDONLY);
    if (fd < 0)
        return false;
    bool ok = fsync(fd) == 0;
    return close(fd) == 0 && ok;
}

/* Fills spec for the format: 32-bit float linear EXR or 8-bit sRGB PNG. */
OIIO::ImageSpec make_spec(cap_image_format format, int width, int height, int channels)
{
    bool exr = format == CAP_IMAGE_FORMAT_EXR;
    OIIO::ImageSpec spec(width, height, channels, exr ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    if (exr) {
        spec.attribute("compression", "zip");
        spec.attribute("oiio:ColorSpace", "Linear");
    } else {
        spec.attribute("oiio:ColorSpace", "sRGB");
        /* Our alpha only marks pixels as in or out; do not let the writer
         * divide colours by it as if they were premultiplied. */
        spec.attribute("oiio:UnassociatedAlpha", 1);
    }
    return spec;
}

/* Writes the pixels to name (a fresh temporary) in the given format. */
cap_status write_pixels(const std::string &name, const char *path, cap_image_format format, int width,
                           int height, int channels, const float *pixels, char *err, size_t errlen)
{
    auto out = OIIO::ImageOutput::create(format == CAP_IMAGE_FORMAT_EXR ? "openexr" : "png");
    if (!out)
        return fail(CAP_ERR_OUTPUT, err, errlen, "%s: no OpenImageIO writer: %s", path,
                    first_line(OIIO::geterror()).c_str());
    OIIO::ImageSpec spec = make_spec(format, width, height, channels);
    bool ok = out->open(name, spec) && out->write_image(OIIO::TypeDesc::FLOAT, pixels);
    ok = out->close() && ok;
    if (!ok)
        return fail(CAP_ERR_OUTPUT, err, errlen, "%s: cannot write image: %s", path,
                    first_line(out->geterror()).c_str());
    if (!flush_to_disk(name))
        return fail(CAP_ERR_OUTPUT, err, errlen, "%s: cannot flush image: %s", path, std::strerror(errno));
    return CAP_OK;
}

cap_status check_write_args(const char *path, int width, int height, int channels, const float *pixels,
                               char *err, size_t errlen)
{
    if (path == nullptr || pixels == nullptr)
        return fail(CAP_ERR_ARG, err, errlen, "image path or pixels missing");
    if (cap_image_guess_format(path) == CAP_IMAGE_FORMAT_UNKNOWN)
        return fail(CAP_ERR_ARG, err, errlen, "%s: unsupported image type (use .exr or .png)", path);
    if (width < 1 || height < 1 || width > max_side || height > max_side)
        return fail(CAP_ERR_ARG, err, errlen, "%s: image size %dx%d out of range", path, width, height);
    if (channels < 1 || channels > 4)
        return fail(CAP_ERR_ARG, err, errlen, "%s: %d channels (1 to 4 supported)", path, channels);
    return CAP_OK;
}

cap_status write_atomically(const char *path, int width, int height, int channels, const float *pixels,
                               char *err, size_t errlen)
{
    cap_status status = check_write_args(path, width, height, channels, pixels, err, errlen);
    if (status != CAP_OK)
        return status;
    std::string name = make_temporary(path, extension_of(path));
    if (name.empty())
        return fail(CAP_ERR_OUTPUT, err, errlen, "%s: cannot create a file there: %s", path,
                    std::strerror(errno));
    status = write_pixels(name, path, cap_image_guess_format(path), width, height, channels, pixels, err, errlen);
    if (status == CAP_OK && std::rename(name.c_str(), path) != 0)
        status = fail(CAP_ERR_OUTPUT, err, errlen, "%s: cannot rename the finished image into place: %s",
                      path, std::strerror(errno));
    if (status != CAP_OK)
        unlink(name.c_str());
    return status;
}

cap_status check_readable(const char *path, char *err, size_t errlen)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return fail(CAP_ERR_INPUT, err, errlen, "%s: %s", path, std::strerror(errno));
    if (S_ISDIR(st.st_mode))
        return fail(CAP_ERR_INPUT, err, errlen, "%s: is a folder, not an image", path);
    return CAP_OK;
}

/* True for integer sample types, which OpenImageIO normalises to [0, 1] when converting to float. */
bool is_integer_type(OIIO::TypeDesc t)
{
    return t.basetype != OIIO::TypeDesc::HALF && t.basetype != OIIO::TypeDesc::FLOAT &&
           t.basetype != OIIO::TypeDesc::DOUBLE;
}

cap_status read_pixels(const char *path, cap_image *img, char *err, size_t errlen)
{
    cap_status status = check_readable(path, err, errlen);
    if (status != CAP_OK)
        return status;
    auto in = OIIO::ImageInput::open(path);
    if (!in)
        return fail(CAP_ERR_INPUT, err, errlen, "%s: not a readable image: %s", path,
                    first_line(OIIO::geterror()).c_str());
    const OIIO::ImageSpec &spec = in->spec();
    long long samples = static_cast<long long>(spec.width) * spec.height * spec.nchannels;
    if (spec.width < 1 || spec.height < 1 || spec.nchannels < 1 || spec.width > max_side ||
        spec.height > max_side || spec.depth > 1 || samples > max_samples)
        return fail(CAP_ERR_INPUT, err, errlen, "%s: unsupported image size %dx%dx%d with %d channels", path,
                    spec.width, spec.height, spec.depth, spec.nchannels);
    float *buf = static_cast<float *>(std::malloc(static_cast<size_t>(samples) * sizeof(float)));
    if (buf == nullptr)
        return fail(CAP_ERR_NOMEM, err, errlen, "%s: out of memory for %lld samples", path, samples);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, buf)) {
        std::free(buf);
        return fail(CAP_ERR_INPUT, err, errlen, "%s: cannot read image data: %s", path,
                    first_line(in->geterror()).c_str());
    }
    img->width = spec.width;
    img->height = spec.height;
    img->channels = spec.nchannels;
    img->pixels = buf;
    img->integer = is_integer_type(spec.format) ? 1 : 0;
    img->bits = static_cast<int>(spec.format.size() * 8);
    return CAP_OK;
}

} // namespace

extern "C" cap_image_format cap_image_guess_format(const char *path)
{
    if (path == nullptr)
        return CAP_IMAGE_FORMAT_UNKNOWN;
    const char *ext = extension_of(path);
    if (equals_ignoring_case(ext, "exr"))
        return CAP_IMAGE_FORMAT_EXR;
    if (equals_ignoring_case(ext, "png"))
        return CAP_IMAGE_FORMAT_PNG;
    return CAP_IMAGE_FORMAT_UNKNOWN;
}

extern "C" cap_status cap_image_write(const char *path, int width, int height, int channels,
                                       const float *pixels, char *err, size_t errlen)
{
    try {
        return write_atomically(path, width, height, channels, pixels, err, errlen);
    } catch (const std::bad_alloc &) {
        return fail(CAP_ERR_NOMEM, err, errlen, "%s: out of memory while writing", path ? path : "image");
    } catch (const std::exception &e) {
        return fail(CAP_ERR_OUTPUT, err, errlen, "%s: %s", path ? path : "image", e.what());
    } catch (...) {
        return fail(CAP_ERR_OUTPUT, err, errlen, "%s: unexpected error while writing", path ? path : "image");
    }
}

extern "C" cap_status cap_image_read(const char *path, cap_image *img, char *err, size_t errlen)
{
    if (img != nullptr)
        std::memset(img, 0, sizeof *img);
    if (path == nullptr || img == nullptr)
        return fail(CAP_ERR_ARG, err, errlen, "image path or output missing");
    try {
        return read_pixels(path, img, err, errlen);
    } catch (const std::bad_alloc &) {
        return fail(CAP_ERR_NOMEM, err, errlen, "%s: out of memory while reading", path);
    } catch (const std::exception &e) {
        return fail(CAP_ERR_INPUT, err, errlen, "%s: %s", path, e.what());
    } catch (...) {
        return fail(CAP_ERR_INPUT, err, errlen, "%s: unexpected error while reading", path);
    }
}

extern "C" void cap_image_free(cap_image *img)
{
    if (img == nullptr)
        return;
    std::free(img->pixels);
    std::memset(img, 0, sizeof *img);
}
