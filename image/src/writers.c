/*
 * writers.c - the encoders of image/image.h's output formats, without
 * OpenImageIO: OpenEXR through OpenEXR's C core library (OpenEXRCore, which
 * needs only zlib), PNG through libpng, Radiance .hdr (RGBE with run-length
 * encoded scanlines, a format of a page) here. The only files of ilfkit that include
 * openexr.h and png.h (test_image_writers_contained).
 *
 * Why not the image module: Debian's OpenImageIO maps a reader for every
 * format it knows (OpenVDB, GDAL, DICOM, FFmpeg, ...), about 115 MiB of
 * resident libraries and 0.4 s of loading, which a relight that writes its
 * view paid for two small images. Reading stays with the module.
 *
 * Conventions kept from the module they replace, so that files read back
 * the same through OpenImageIO: channels are named as OpenImageIO names
 * them (1: Y; 2 to 4: R, G, B, A in order); EXR is scanline, ZIP-compressed,
 * 32-bit float, values as given (NaN and infinities included), channels not
 * flagged perceptually linear (pLinear 0, OpenEXR's advice for colour); PNG is
 * 8 bits, gray, gray + alpha, RGB or RGBA, each value clamped to [0, 1] and
 * rounded to the nearest of 255 steps (NaN as 0), with sRGB, gAMA and cHRM
 * chunks.
 *
 * Invariants: nothing here prints, exits or keeps state between calls (every
 * call has its own context), so calls may run on several threads at once; a
 * failure returns a status and one line naming the image's final path; the
 * file given is the caller's temporary, which the caller removes on failure
 * (OpenEXR removes a file it failed to write itself: never pass a device).
 */
#include "writers.h"

#include <errno.h>
#include <math.h>
#include <openexr.h>
#include <png.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Formats a message into msg (msglen > 0). @return status. */
static img_status fail(img_status status, char *msg, size_t msglen, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static img_status fail(img_status status, char *msg, size_t msglen, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, msglen, fmt, ap);
    va_end(ap);
    return status;
}

/* @return OpenImageIO's name for channel c of n (1: Y; else R, G, B, A). */
static const char *channel_name(int c, int n)
{
    static const char *const rgba[4] = {"R", "G", "B", "A"};
    return n == 1 ? "Y" : rgba[c];
}

/* ------------------------------------------------------------ OpenEXR */

/* OpenEXR's last message during a write_exr() call on this thread. The handler cannot ask the context
 * for its user data: OpenEXR may report with the context's lock held, and exr_get_user_data() would wait
 * for it forever. OpenEXR's core reports on the calling thread, so a per-thread slot serves. */
static _Thread_local char *exr_message;
enum { EXR_MESSAGE_BYTES = 256 };

/* exr_error_handler_cb_t: keeps the library's message instead of printing it. */
static void exr_note(exr_const_context_t ctxt, exr_result_t code, const char *text)
{
    (void)ctxt;
    if (exr_message != NULL)
        snprintf(exr_message, EXR_MESSAGE_BYTES, "%s", text != NULL ? text : exr_get_default_error_message(code));
}

/* Defines the one scanline part of ctxt: its size, ZIP compression and float channels. @return OpenEXR's result. */
static exr_result_t exr_define(exr_context_t ctxt, int width, int height, int channels, int *part)
{
    exr_result_t rv = exr_add_part(ctxt, "", EXR_STORAGE_SCANLINE, part);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_initialize_required_attr_simple(ctxt, *part, width, height, EXR_COMPRESSION_ZIP);
    for (int c = 0; c < channels && rv == EXR_ERR_SUCCESS; c++)
        rv = exr_add_channel(ctxt, *part, channel_name(c, channels), EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC,
                             1, 1);
    return rv == EXR_ERR_SUCCESS ? exr_write_header(ctxt) : rv;
}

/* Encodes every chunk of ctxt's part from pixels [y][x][channel]. @return OpenEXR's result. */
static exr_result_t exr_encode_all(exr_context_t ctxt, int part, int width, int height, int channels,
                                   const float *pixels)
{
    int32_t lines = 1;
    exr_result_t rv = exr_get_scanlines_per_chunk(ctxt, part, &lines);
    exr_encode_pipeline_t encoder = EXR_ENCODE_PIPELINE_INITIALIZER;
    int started = 0;
    for (int y = 0; rv == EXR_ERR_SUCCESS && y < height; y += lines) {
        exr_chunk_info_t chunk;
        rv = exr_write_scanline_chunk_info(ctxt, part, y, &chunk);
        if (rv == EXR_ERR_SUCCESS)
            rv = started ? exr_encoding_update(ctxt, part, &chunk, &encoder)
                         : exr_encoding_initialize(ctxt, part, &chunk, &encoder);
        started |= rv == EXR_ERR_SUCCESS;
        /* the file's channels are sorted by name: find each one's place in the caller's pixels */
        for (int k = 0; rv == EXR_ERR_SUCCESS && k < encoder.channel_count; k++) {
            exr_coding_channel_info_t *ch = &encoder.channels[k];
            int c = 0;
            while (c < channels && strcmp(ch->channel_name, channel_name(c, channels)) != 0)
                c++;
            if (c == channels) {
                rv = EXR_ERR_INVALID_ARGUMENT;
                break;
            }
            ch->user_bytes_per_element = sizeof(float);
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->user_pixel_stride = (int32_t)(channels * sizeof(float));
            ch->user_line_stride = (int32_t)((size_t)width * channels * sizeof(float));
            ch->encode_from_ptr = (const uint8_t *)(pixels + ((size_t)chunk.start_y * width * channels + c));
        }
        if (rv == EXR_ERR_SUCCESS && y == 0)
            rv = exr_encoding_choose_default_routines(ctxt, part, &encoder);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_encoding_run(ctxt, part, &encoder);
    }
    if (started)
        exr_encoding_destroy(ctxt, &encoder);
    return rv;
}

/* Writes an EXR into file. @return IMG_OK, or IMG_ERR_OUTPUT / IMG_ERR_NOMEM with a message naming path. */
static img_status write_exr(const char *file, const char *path, int width, int height, int channels,
                            const float *pixels, char *msg, size_t msglen)
{
    char report[EXR_MESSAGE_BYTES] = "";
    exr_message = report;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_note;
    exr_context_t ctxt = NULL;
    int part = 0;
    exr_result_t rv = exr_start_write(&ctxt, file, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_define(ctxt, width, height, channels, &part);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_encode_all(ctxt, part, width, height, channels, pixels);
    /* finishing closes the file (and removes it after a failure); its result counts too */
    exr_result_t finished = ctxt != NULL ? exr_finish(&ctxt) : EXR_ERR_SUCCESS;
    exr_message = NULL;
    if (rv == EXR_ERR_SUCCESS)
        rv = finished;
    if (rv == EXR_ERR_SUCCESS)
        return IMG_OK;
    return fail(rv == EXR_ERR_OUT_OF_MEMORY ? IMG_ERR_NOMEM : IMG_ERR_OUTPUT, msg, msglen,
                "%s: cannot write image: %s", path, report[0] != '\0' ? report : exr_get_default_error_message(rv));
}

/* ------------------------------------------------------------ PNG */

/* What libpng's handlers share with write_png(): where to put the message, and where to jump. */
typedef struct png_report {
    jmp_buf jump;
    char text[256];
} png_report;

/* png_error_ptr: keeps the message, with the system's reason when a write set errno (libpng's own text is
 * only "Write Error"), and returns to write_png()'s setjmp (libpng's contract: never return). */
static void png_failed(png_structp png, png_const_charp text)
{
    png_report *r = png_get_error_ptr(png);
    int code = errno;
    snprintf(r->text, sizeof r->text, "%s%s%s", text != NULL ? text : "libpng error", code != 0 ? ": " : "",
             code != 0 ? strerror(code) : "");
    longjmp(r->jump, 1);
}

/* png_error_ptr for warnings: ignored (nothing prints). */
static void png_warned(png_structp png, png_const_charp text)
{
    (void)png;
    (void)text;
}

/* @return v clamped to [0, 1] and rounded to 8 bits, halves up (NaN as 0). */
static png_byte quantise(float v)
{
    if (!(v > 0.0f))
        return 0;
    return v >= 1.0f ? 255 : (png_byte)(v * 255.0f + 0.5f);
}

/* Encodes into out (opened) with png and info made. The caller's setjmp catches libpng's errors. */
static void png_encode(png_structp png, png_infop info, FILE *out, int width, int height, int channels,
                       const float *pixels, png_bytep row)
{
    static const int types[4] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                 PNG_COLOR_TYPE_RGB_ALPHA};
    png_init_io(png, out);
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, 8, types[channels - 1], PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    const size_t n = (size_t)width * channels;
    for (int y = 0; y < height; y++) {
        const float *src = pixels + (size_t)y * n;
        for (size_t k = 0; k < n; k++)
            row[k] = quantise(src[k]);
        png_write_row(png, row);
    }
    png_write_end(png, info);
}

/* Writes a PNG into file. @return IMG_OK, or IMG_ERR_OUTPUT / IMG_ERR_NOMEM with a message naming path. */
static img_status write_png(const char *file, const char *path, int width, int height, int channels,
                            const float *pixels, char *msg, size_t msglen)
{
    /* volatile: changed between setjmp and a longjmp back to it (report is changed only through the
     * pointer libpng holds) */
    png_report report = {.text = ""};
    FILE *volatile out = NULL;
    png_bytep volatile row = NULL;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &report, png_failed, png_warned);
    png_infop info = png != NULL ? png_create_info_struct(png) : NULL;
    img_status status = IMG_OK;
    if (png == NULL || info == NULL) {
        status = fail(IMG_ERR_NOMEM, msg, msglen, "%s: out of memory for the PNG writer", path);
    } else if (setjmp(report.jump) != 0) {
        status = fail(IMG_ERR_OUTPUT, msg, msglen, "%s: cannot write image: %s", path, report.text);
    } else if ((row = malloc((size_t)width * channels)) == NULL) {
        status = fail(IMG_ERR_NOMEM, msg, msglen, "%s: out of memory for a row of %d pixels", path, width);
    } else if ((out = fopen(file, "wbe")) == NULL) {
        status = fail(IMG_ERR_OUTPUT, msg, msglen, "%s: cannot write image: %s", path, strerror(errno));
    } else {
        errno = 0; /* so that png_failed() gives a write's own reason, not an older one */
        png_encode(png, info, out, width, height, channels, pixels, row);
    }
    png_destroy_write_struct(png != NULL ? &png : NULL, info != NULL ? &info : NULL);
    free(row);
    if (out != NULL && (fclose(out) != 0) && status == IMG_OK)
        status = fail(IMG_ERR_OUTPUT, msg, msglen, "%s: cannot write image: %s", path, strerror(errno));
    return status;
}

/* ------------------------------------------------------------ Radiance HDR */

/* Radiance's RGBE of one linear colour: a shared exponent e, each channel mantissa * 2^(e - 136). Negative,
 * NaN and tiny values are 0; a value too large for the exponent saturates. */
static void rgbe_encode(const float *px, int channels, unsigned char out[4])
{
    double rgb[3];
    for (int c = 0; c < 3; c++) {
        double v = channels >= 3 ? px[c] : px[0];
        rgb[c] = v > 0.0 ? v : 0.0; /* also NaN */
    }
    double top = rgb[0] > rgb[1] ? rgb[0] : rgb[1];
    top = rgb[2] > top ? rgb[2] : top;
    if (top < 1e-32) {
        out[0] = out[1] = out[2] = out[3] = 0;
        return;
    }
    int e;
    double m = frexp(top > 1.7e38 ? 1.7e38 : top, &e) * 256.0 / top;
    for (int c = 0; c < 3; c++) {
        double v = rgb[c] * m;
        out[c] = (unsigned char)(v >= 255.0 ? 255 : v);
    }
    out[3] = (unsigned char)(e + 128);
}

/* Appends to out the run-length encoding of n bytes of one component (runs of 3 or more: 128 + count, value;
 * the rest as literals: count, bytes). @return the bytes written (at most n + n / 128 + 1). */
static size_t rle_component(const unsigned char *v, size_t n, unsigned char *out)
{
    size_t at = 0, k = 0;
    while (k < n) {
        size_t run = 1;
        while (k + run < n && run < 127 && v[k + run] == v[k])
            run++;
        if (run >= 3) {
            out[at++] = (unsigned char)(128 + run);
            out[at++] = v[k];
            k += run;
            continue;
        }
        size_t lit = 0; /* literals up to the next run of 3 */
        while (k + lit < n && lit < 128 &&
               !(k + lit + 2 < n && v[k + lit] == v[k + lit + 1] && v[k + lit] == v[k + lit + 2]))
            lit++;
        out[at++] = (unsigned char)lit;
        memcpy(out + at, v + k, lit);
        at += lit;
        k += lit;
    }
    return at;
}

/* Encodes one row into out (scan: width * 4 bytes, planes component by component). @return its length. Rows
 * 8 to 32767 wide are run-length encoded (new-style, starting 2, 2); others flat, as Radiance does. */
static size_t hdr_row(const float *row, int width, int channels, unsigned char *scan, unsigned char *out)
{
    size_t w = (size_t)width;
    for (size_t x = 0; x < w; x++) {
        unsigned char rgbe[4];
        rgbe_encode(row + x * channels, channels, rgbe);
        for (int c = 0; c < 4; c++)
            scan[c * w + x] = rgbe[c];
    }
    if (width < 8 || width > 32767) {
        for (size_t x = 0; x < w; x++)
            for (int c = 0; c < 4; c++)
                out[4 * x + c] = scan[c * w + x];
        return 4 * w;
    }
    size_t at = 0;
    out[at++] = 2;
    out[at++] = 2;
    out[at++] = (unsigned char)(width >> 8);
    out[at++] = (unsigned char)(width & 255);
    for (int c = 0; c < 4; c++)
        at += rle_component(scan + c * w, w, out + at);
    return at;
}

/* Writes a Radiance .hdr into file. @return IMG_OK, or IMG_ERR_OUTPUT / IMG_ERR_NOMEM with a message naming path. */
static img_status write_hdr(const char *file, const char *path, int width, int height, int channels,
                            const float *pixels, char *msg, size_t msglen)
{
    size_t w = (size_t)width;
    unsigned char *scan = malloc(4 * w), *out = malloc(4 + 4 * w + 4 * (w / 128 + 1));
    FILE *f = NULL;
    img_status status = IMG_OK;
    if (scan == NULL || out == NULL) {
        status = fail(IMG_ERR_NOMEM, msg, msglen, "%s: out of memory for a row of %d pixels", path, width);
    } else if ((f = fopen(file, "wbe")) == NULL) {
        status = fail(IMG_ERR_OUTPUT, msg, msglen, "%s: cannot write image: %s", path, strerror(errno));
    } else {
        int ok = fprintf(f, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n", height, width) > 0;
        for (int y = 0; ok && y < height; y++) {
            size_t len = hdr_row(pixels + (size_t)y * w * channels, width, channels, scan, out);
            ok = fwrite(out, 1, len, f) == len;
        }
        if (!ok)
            status = fail(IMG_ERR_OUTPUT, msg, msglen, "%s: cannot write image: %s", path, strerror(errno));
    }
    if (f != NULL && fclose(f) != 0 && status == IMG_OK)
        status = fail(IMG_ERR_OUTPUT, msg, msglen, "%s: cannot write image: %s", path, strerror(errno));
    free(scan);
    free(out);
    return status;
}

/* ------------------------------------------------------------ every format */

img_status img__write_pixels(const char *file, const char *path, img_format format, int width, int height,
                             int channels, const float *pixels, char *msg, size_t msglen)
{
    if (format == IMG_FORMAT_EXR)
        return write_exr(file, path, width, height, channels, pixels, msg, msglen);
    if (format == IMG_FORMAT_HDR)
        return write_hdr(file, path, width, height, channels, pixels, msg, msglen);
    return write_png(file, path, width, height, channels, pixels, msg, msglen);
}
