/*
 * test_image.c - the image library (image/image.h) on its own, linked
 * without capture: what test_capture does not already cover of it.
 *
 * What is checked:
 *   - nothing of the module is mapped before the first read, and the calls
 *     that never load it (status names, formats, sRGB, writes) do not;
 *   - the sRGB curve: fixed points, both segments, clamping, and decode
 *     undoing encode;
 *   - writes: a PNG read back as 8-bit integers quantised as given (opaque:
 *     OpenImageIO's PNG reader multiplies colours by alpha), an EXR
 *     replacing an existing file atomically, keeping its mode and leaving no
 *     temporary (base's naming rule) behind; a missing folder, bad sizes and
 *     channel counts refused with their status and a message naming the file;
 *   - the writers (writers.c, no OpenImageIO): EXR of 1 to 4 channels over
 *     several chunks read back bit for bit through OpenImageIO, NaN, infinities
 *     and negative values included, in the channel order given; PNG of 1 to 3
 *     channels quantised, clamped, NaN as 0; a file
 *     that cannot be opened or filled (a missing folder, a file size limit)
 *     refused as IMG_ERR_OUTPUT with a message naming the image;
 *   - reads: missing files, folders and non-images refused as bad input with
 *     the image zeroed; NULL err and a short err buffer are safe;
 *   - header reads: EXR, HDR and PNG written here described as img_read()
 *     describes them; a Radiance header claiming 32768 x 16384 with no pixel
 *     data behind it described (no pixel decoded) where img_read() fails on
 *     its data; a size img_read() refuses, a FIFO, a missing file and NULLs
 *     refused with *hdr zeroed.
 * Scratch files go to $ILF_TEST_TMP/image. The last line is "N passed, M failed".
 */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "ilf/atomic_file.h"
#include "image/image.h"
#include "writers.h"

#define PATH_BYTES 1024

static char tmp_dir[PATH_BYTES - 64];

/* @return tmp_dir/name in a static rotating buffer (4 live at a time). */
static const char *tmp_path(const char *name)
{
    static char bufs[4][PATH_BYTES];
    static int next;
    char *b = bufs[next++ % 4];
    snprintf(b, PATH_BYTES, "%s/%s", tmp_dir, name);
    return b;
}

/* @return how many entries of tmp_dir are temporaries under base's atomic-writer rule. */
static int temporaries_left(void)
{
    DIR *d = opendir(tmp_dir);
    int count = 0;
    for (struct dirent *e; d != NULL && (e = readdir(d)) != NULL;)
        count += ilf_atomic_is_temporary(e->d_name);
    if (d != NULL)
        closedir(d);
    return count;
}

/* Must run before this process's first read or write. */
static void test_nothing_loaded(void)
{
    CHECK(strcmp(img_status_name(IMG_OK), "ok") == 0 && strcmp(img_status_name(IMG_ERR_OUTPUT), "cannot write") == 0 &&
              strcmp(img_status_name((img_status)99), "unknown status") == 0,
          "status names");
    CHECK(img_guess_format(NULL) == IMG_FORMAT_UNKNOWN && img_guess_format("x.png.tif") == IMG_FORMAT_UNKNOWN &&
              img_guess_format("dir.exr/x") == IMG_FORMAT_UNKNOWN && img_guess_format(".EXR") == IMG_FORMAT_EXR,
          "formats by the last component's extension");
    img_free(NULL);
    char err[256] = "";
    const float px[3] = {0, 0, 0};
    CHECK(img_write(tmp_path("a.tif"), 1, 1, 3, px, err, sizeof err) == IMG_ERR_ARG && strstr(err, "a.tif") != NULL,
          "unknown extension: %s", err);
    CHECK(img_write(tmp_path("a.png"), 0, 1, 3, px, err, sizeof err) == IMG_ERR_ARG &&
              img_write(tmp_path("a.png"), IMG_MAX_SIDE + 1, 1, 3, px, err, sizeof err) == IMG_ERR_ARG &&
              img_write(tmp_path("a.png"), 1, 1, 5, px, err, sizeof err) == IMG_ERR_ARG &&
              img_write(NULL, 1, 1, 3, px, NULL, 0) == IMG_ERR_ARG && img_write(tmp_path("a.png"), 1, 1, 3, NULL, err, 0) == IMG_ERR_ARG,
          "bad sizes, channel counts and NULLs are bad arguments");
    img_image img;
    CHECK(img_read(NULL, &img, err, sizeof err) == IMG_ERR_ARG && img.pixels == NULL &&
              img_read(tmp_path("x.exr"), NULL, err, sizeof err) == IMG_ERR_ARG,
          "NULL path or image");
    CHECK(img_srgb_encode(0.5) > 0.0f, "sRGB needs no module");
    CHECK(check_mapped("libilfkit_oiio") == 0 && check_mapped("libOpenImageIO") == 0,
          "argument errors, names, formats and sRGB load nothing");
}

static void test_srgb(void)
{
    CHECK(img_srgb_encode(0.0) == 0.0f && img_srgb_encode(1.0) == 1.0f && img_srgb_decode(0.0f) == 0.0f &&
              fabsf(img_srgb_decode(1.0f) - 1.0f) < 1e-6f,
          "0 and 1 are fixed points");
    CHECK(img_srgb_encode(-3.0) == 0.0f && img_srgb_encode(7.0) == 1.0f && isnan(img_srgb_encode(NAN)),
          "encoding clamps to [0, 1] (NaN stays NaN)");
    CHECK(fabs(img_srgb_encode(0.001) - 0.01292) < 1e-7 && fabs(img_srgb_encode(0.18) - 0.46135) < 1e-4,
          "linear segment and the power segment (mid grey 0.18 -> %g)", (double)img_srgb_encode(0.18));
    double worst = 0.0;
    for (int k = 0; k <= 1000; k++) {
        double v = k / 1000.0;
        worst = fmax(worst, fabs(img_srgb_decode(img_srgb_encode(v)) - v));
    }
    CHECK(worst < 1e-6, "decode undoes encode within 1e-6 (worst %g)", worst);
}

static void test_writes(void)
{
    char err[512] = "";
    const float rgba[2 * 1 * 4] = {0.0f, 0.6f, 1.0f, 1.0f, 0.25f, 2.0f, -1.0f, 1.0f};
    const char *png = tmp_path("two.png");
    remove(png);
    CHECK(img_write(png, 2, 1, 4, rgba, err, sizeof err) == IMG_OK, "%s", err);
    CHECK(check_mapped("libilfkit_oiio") == 0, "a write needs no module");
    img_image img;
    CHECK(img_read(png, &img, err, sizeof err) == IMG_OK, "%s", err);
    CHECK(check_mapped("libilfkit_oiio") == 1, "the module is mapped after the first read");
    if (img.pixels != NULL) {
        CHECK(img.width == 2 && img.height == 1 && img.channels == 4 && img.integer == 1 && img.bits == 8,
              "PNG: 2x1x4, 8-bit integers (%dx%dx%d, %d bits)", img.width, img.height, img.channels, img.bits);
        const float want[8] = {0.0f, 153.0f / 255, 1.0f, 1.0f, 64.0f / 255, 1.0f, 0.0f, 1.0f};
        float worst = 0.0f;
        for (int k = 0; k < 8; k++)
            worst = fmaxf(worst, fabsf(img.pixels[k] - want[k]));
        CHECK(worst < 1e-6f, "PNG values quantised as given and clamped (worst %g)", (double)worst);
    }
    img_free(&img);
    CHECK(img.pixels == NULL && img.width == 0, "img_free zeroes");

    const char *exr = tmp_path("over.exr");
    const float a[3] = {1, 2, 3}, b[3] = {4, 5, 6};
    CHECK(img_write(exr, 1, 1, 3, a, err, sizeof err) == IMG_OK, "%s", err);
    CHECK(chmod(exr, 0640) == 0, "chmod");
    CHECK(img_write(exr, 1, 1, 3, b, err, sizeof err) == IMG_OK, "%s", err);
    struct stat st;
    CHECK(stat(exr, &st) == 0 && (st.st_mode & 0777) == 0640, "a replaced image keeps its mode (%o)",
          (unsigned)(st.st_mode & 0777));
    CHECK(img_read(exr, &img, err, sizeof err) == IMG_OK && img.pixels != NULL && memcmp(img.pixels, b, sizeof b) == 0,
          "the EXR holds the second write: %s", err);
    img_free(&img);
    CHECK(temporaries_left() == 0, "no temporary left behind");

    const char *nowhere = tmp_path("no-such-folder/x.exr");
    CHECK(img_write(nowhere, 1, 1, 3, a, err, sizeof err) == IMG_ERR_OUTPUT && strstr(err, nowhere) != NULL &&
              strstr(err, "cannot create a file there") != NULL,
          "a missing folder: %s", err);
    char tiny[8];
    CHECK(img_write(nowhere, 1, 1, 3, a, tiny, sizeof tiny) == IMG_ERR_OUTPUT && strlen(tiny) == sizeof tiny - 1,
          "a short err buffer gets a terminated prefix");
    CHECK(img_write(nowhere, 1, 1, 3, a, NULL, 0) == IMG_ERR_OUTPUT, "NULL err is safe");
}

/* @return a test value for sample k: varied, signed, with a NaN, infinities and a denormal among them. */
static float sample_value(size_t k)
{
    static const float odd[5] = {NAN, INFINITY, -INFINITY, 1e-42f, -0.0f};
    return k % 97 < 5 ? odd[k % 97] : (float)((double)k * 0.37 - 40.0) * (k % 3 ? 1.0f : 1e6f);
}

/* @return whether a and b hold the same n floats bit for bit (NaN equal to itself). */
static int same_bits(const float *a, const float *b, size_t n)
{
    return memcmp(a, b, n * sizeof *a) == 0;
}

static void test_writers(void)
{
    char err[512] = "";
    /* 37 x 53 spans four ZIP chunks of 16 lines, the last partial */
    enum { W = 37, H = 53 };
    static float px[W * H * 4];
    for (int channels = 1; channels <= 4; channels++) {
        size_t n = (size_t)W * H * channels;
        for (size_t k = 0; k < n; k++)
            px[k] = sample_value(k);
        char name[32];
        snprintf(name, sizeof name, "writer%d.exr", channels);
        const char *path = tmp_path(name);
        CHECK(img_write(path, W, H, channels, px, err, sizeof err) == IMG_OK, "%s", err);
        img_image img;
        CHECK(img_read(path, &img, err, sizeof err) == IMG_OK, "%s", err);
        CHECK(img.pixels != NULL && img.width == W && img.height == H && img.channels == channels && !img.integer &&
                  img.bits == 32 && same_bits(img.pixels, px, n),
              "EXR of %d channel(s) read back bit for bit (%dx%dx%d, %d bits)", channels, img.width, img.height,
              img.channels, img.bits);
        img_free(&img);
    }
    /* PNG: gray, gray + alpha (opaque: OpenImageIO's reader multiplies colours by alpha), RGB;
     * [0, 1] in 255 steps, halves up, clamped, NaN as 0 */
    const float gray[6] = {0.5f / 255, 1.5f / 255, -3.0f, 7.0f, NAN, 0.6f};
    const float gray_alpha[6] = {0.5f / 255, 1.0f, 7.0f, 1.0f, 0.6f, 1.0f};
    const float want[6] = {1.0f / 255, 2.0f / 255, 0.0f, 1.0f, 0.0f, 153.0f / 255};
    const float want_alpha[6] = {1.0f / 255, 1.0f, 1.0f, 1.0f, 153.0f / 255, 1.0f};
    for (int channels = 1; channels <= 3; channels++) {
        const float *in = channels == 2 ? gray_alpha : gray, *expect = channels == 2 ? want_alpha : want;
        char name[32];
        snprintf(name, sizeof name, "writer%d.png", channels);
        const char *path = tmp_path(name);
        CHECK(img_write(path, 6 / channels, 1, channels, in, err, sizeof err) == IMG_OK, "%s", err);
        img_image img;
        CHECK(img_read(path, &img, err, sizeof err) == IMG_OK && img.pixels != NULL && img.integer && img.bits == 8 &&
                  img.channels == channels && img.width == 6 / channels,
              "PNG of %d channel(s): %s", channels, err);
        float worst = 0.0f;
        for (int k = 0; img.pixels != NULL && k < 6 / channels * channels; k++)
            worst = fmaxf(worst, fabsf(img.pixels[k] - expect[k]));
        CHECK(worst < 1e-6f, "PNG of %d channel(s) quantised as documented (worst %g)", channels, (double)worst);
        img_free(&img);
    }
    /* Radiance .hdr: RGBE keeps each value within 1% of the pixel's largest channel (8-bit mantissas); rows
     * wider than 7 are run-length encoded (a constant stretch, then varied values), narrower ones flat;
     * negative and NaN values come back 0, gray as r = g = b */
    static float hpx[W * H * 3]; /* px keeps its values for the failures below */
    for (int wide = 0; wide <= 1; wide++) {
        int w = wide ? W : 5;
        for (size_t k = 0; k < (size_t)w * H * 3; k++)
            hpx[k] = k % 97 < 40 ? 2.5f : (float)(sample_value(k) * 100.0);
        hpx[3] = -1.0f;
        hpx[4] = NAN;
        const char *path = tmp_path(wide ? "writer-wide.hdr" : "writer-narrow.hdr");
        CHECK(img_guess_format(path) == IMG_FORMAT_HDR, "the .hdr extension names Radiance's format");
        CHECK(img_write(path, w, H, 3, hpx, err, sizeof err) == IMG_OK, "%s", err);
        img_image img;
        CHECK(img_read(path, &img, err, sizeof err) == IMG_OK && img.pixels != NULL && img.width == w &&
                  img.height == H && img.channels == 3,
              "HDR read back (%dx%d): %s", w, H, err);
        double worst = 0.0;
        for (size_t p = 0; img.pixels != NULL && p < (size_t)w * H; p++) {
            double top = 0.0;
            for (int c = 0; c < 3; c++)
                top = fmax(top, hpx[3 * p + c] > 0 ? hpx[3 * p + c] : 0.0);
            for (int c = 0; c < 3; c++) {
                double want_v = hpx[3 * p + c] > 0 ? hpx[3 * p + c] : 0.0; /* NaN compares false: 0 */
                worst = fmax(worst, fabs(img.pixels[3 * p + c] - want_v) / (top > 0 ? top : 1.0));
            }
        }
        CHECK(worst < 0.01, "HDR %d wide within 1%% of each pixel's largest channel (worst %g)", w, worst);
        img_free(&img);
    }
    /* The encoders' own failures: a file that cannot be opened, or that cannot take the bytes (a file
     * size limit, SIGXFSZ ignored so that writes fail with EFBIG: 64 bytes stop the header, 16 KiB an
     * EXR chunk in the middle). Not /dev/full: OpenEXR removes the file it failed to write. */
    struct rlimit was;
    int limited = getrlimit(RLIMIT_FSIZE, &was) == 0;
    void (*was_handler)(int) = signal(SIGXFSZ, SIG_IGN);
    for (int f = IMG_FORMAT_EXR; f <= IMG_FORMAT_PNG; f++) {
        const char *kind = f == IMG_FORMAT_EXR ? "EXR" : "PNG";
        CHECK(img__write_pixels(tmp_path("no-such-folder/y"), "final.img", (img_format)f, W, H, 3, px, err,
                                sizeof err) == IMG_ERR_OUTPUT &&
                  strstr(err, "final.img: cannot write image") == err && strchr(err, '\n') == NULL,
              "%s into a missing folder: %s", kind, err);
        /* the PNG of these values (mostly clamped) takes under 16 KiB: only the header's limit stops it */
        for (rlim_t limit = 64; limit <= (f == IMG_FORMAT_EXR ? 16384u : 64u); limit *= 256) {
            struct rlimit small = {limit, limited ? was.rlim_max : limit};
            if (!limited || setrlimit(RLIMIT_FSIZE, &small) != 0)
                continue;
            img_status st = img__write_pixels(tmp_path("too-big"), "big.img", (img_format)f, W, H, 3, px, err,
                                              sizeof err);
            CHECK(setrlimit(RLIMIT_FSIZE, &was) == 0, "the file size limit restored");
            CHECK(st == IMG_ERR_OUTPUT && strstr(err, "big.img: cannot write image") == err &&
                      strstr(err, "too large") != NULL,
                  "%s past a file size limit of %lu bytes: %s", kind, (unsigned long)limit, err);
            remove(tmp_path("too-big")); /* OpenEXR removes its own; libpng leaves the part written */
        }
    }
    signal(SIGXFSZ, was_handler);
}

static void test_reads(void)
{
    char err[512] = "";
    img_image img;
    const char *missing = tmp_path("missing.exr");
    CHECK(img_read(missing, &img, err, sizeof err) == IMG_ERR_INPUT && strstr(err, missing) != NULL &&
              img.pixels == NULL && img.width == 0,
          "a missing file: %s", err);
    CHECK(img_read(tmp_dir, &img, err, sizeof err) == IMG_ERR_INPUT && strstr(err, "is a folder") != NULL,
          "a folder: %s", err);
    const char *text = tmp_path("text.exr");
    FILE *f = fopen(text, "w");
    if (f != NULL) {
        fputs("not an image\n", f);
        fclose(f);
    }
    CHECK(img_read(text, &img, NULL, 0) == IMG_ERR_INPUT && img.pixels == NULL, "not an image, NULL err");
    CHECK(img_read(text, &img, err, sizeof err) == IMG_ERR_INPUT && strstr(err, "not a readable image") != NULL &&
              strchr(err, '\n') == NULL,
          "one line naming the problem: %s", err);
}

/* Writes text to path. @return 1 on success. */
static int write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (f == NULL)
        return 0;
    int ok = fputs(text, f) >= 0;
    return fclose(f) == 0 && ok;
}

static void test_headers(void)
{
    char err[512] = "";
    static const float px[7 * 4 * 3] = {0.25f};
    static const struct { const char *name; int w, h, channels; } files[] = {
        {"head.exr", 5, 3, 2}, {"head.hdr", 7, 4, 3}, {"head.png", 4, 2, 3}};
    for (size_t k = 0; k < sizeof files / sizeof files[0]; k++) {
        const char *path = tmp_path(files[k].name);
        CHECK(img_write(path, files[k].w, files[k].h, files[k].channels, px, err, sizeof err) == IMG_OK, "%s", err);
        img_header hdr;
        img_image img;
        CHECK(img_header_read(path, &hdr, err, sizeof err) == IMG_OK, "%s", err);
        CHECK(img_read(path, &img, err, sizeof err) == IMG_OK, "%s", err);
        CHECK(hdr.width == files[k].w && hdr.height == files[k].h && hdr.width == img.width &&
                  hdr.height == img.height && hdr.channels == img.channels && hdr.integer == img.integer &&
                  hdr.bits == img.bits,
              "%s: header %dx%dx%d (integer %d, %d bits) as read %dx%dx%d (integer %d, %d bits)", files[k].name,
              hdr.width, hdr.height, hdr.channels, hdr.integer, hdr.bits, img.width, img.height, img.channels,
              img.integer, img.bits);
        CHECK(hdr.integer == (k == 2) && hdr.bits == (k == 2 ? 8 : 32), "%s: %s", files[k].name,
              k == 2 ? "8-bit integers" : "32-bit floats");
        img_free(&img);
    }
    /* a header with no data behind it: only a header read can succeed, so none decodes a pixel */
    const char *lying = tmp_path("lying.hdr");
    CHECK(write_text(lying, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 16384 +X 32768\n"), "write %s", lying);
    img_header hdr;
    CHECK(img_header_read(lying, &hdr, err, sizeof err) == IMG_OK && hdr.width == 32768 && hdr.height == 16384 &&
              hdr.channels == 3,
          "a header alone is described (%dx%dx%d): %s", hdr.width, hdr.height, hdr.channels, err);
    img_image img;
    CHECK(img_read(lying, &img, err, sizeof err) == IMG_ERR_INPUT && strstr(err, "cannot read image data") != NULL,
          "while reading its pixels fails: %s", err);
    const char *absurd = tmp_path("absurd.hdr");
    CHECK(write_text(absurd, "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1000000 +X 1000000\n"), "write %s", absurd);
    CHECK(img_header_read(absurd, &hdr, err, sizeof err) == IMG_ERR_INPUT && hdr.width == 0 &&
              strstr(err, "unsupported image size 1000000x1000000") != NULL,
          "a size img_read refuses, refused alike: %s", err);
    const char *fifo = tmp_path("fifo.exr");
    remove(fifo);
    CHECK(mkfifo(fifo, 0600) == 0 && img_header_read(fifo, &hdr, err, sizeof err) == IMG_ERR_INPUT &&
              strstr(err, "not a regular file") != NULL,
          "a FIFO refused, not waited on: %s", err);
    remove(fifo);
    CHECK(img_header_read(tmp_path("missing.exr"), &hdr, err, sizeof err) == IMG_ERR_INPUT &&
              strstr(err, "missing.exr") != NULL && hdr.width == 0,
          "a missing file: %s", err);
    CHECK(img_header_read(NULL, &hdr, err, sizeof err) == IMG_ERR_ARG && img_header_read(lying, NULL, NULL, 0) ==
              IMG_ERR_ARG, "NULL path or header");
}

int main(void)
{
    const char *base = getenv("ILF_TEST_TMP");
    snprintf(tmp_dir, sizeof tmp_dir, "%s/image", base != NULL ? base : "/tmp");
    mkdir(base != NULL ? base : "/tmp", 0777);
    mkdir(tmp_dir, 0777);
    test_nothing_loaded();
    test_srgb();
    test_writes();
    test_writers();
    test_reads();
    test_headers();
    return check_report();
}
