/*
 * h5stream.c - an HDF5 file driver that writes a new file straight to a file
 * descriptor the caller owns (the atomic writer's temporary), so that no file
 * is ever whole in memory: a write holds HDF5's caches, not its output.
 *
 * HDF5 1.10 cannot survive a write that fails inside H5Dclose or H5Fclose: a
 * freed file stays registered and the process crashes at exit (HDFFV-11052,
 * fixed in 1.14.1). So this driver never reports a failed write to HDF5. It
 * keeps the first error for the caller (lfio__h5_stream_error()) and from
 * then on keeps the file's bytes in memory instead: HDF5 reads back what it
 * wrote and finishes normally, and the caller, seeing the error, discards the
 * temporary. Should memory run out for that copy too, later writes are
 * dropped and reads give zeros ("dead"): still no failure for HDF5 to meet,
 * and the file is discarded all the same. Invariants:
 *   - eof is the file's size as written so far; reads past it are zeros (a
 *     chunk of a new file is read only after it was written).
 *   - Before a failure every byte is on the descriptor; after it, image holds
 *     the whole file (what could be read back of the descriptor, then every
 *     later write), and the descriptor is no longer written.
 *   - The driver writes through its own duplicate of the caller's
 *     descriptor, and its error cell (stream_info.err) is the caller's to
 *     free only once HDF5 has closed the file: a file HDF5 failed to close
 *     may still be flushed at exit, and must then touch nothing freed.
 */
#define _XOPEN_SOURCE 700

#include <errno.h>
#include <sys/stat.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "h5util.h"

/* What the driver needs from the file access property list: the descriptor, and where to record the
 * first error (shared by every copy of the property list). */
typedef struct stream_info {
    int fd;
    int *err;
} stream_info;

typedef struct stream_file {
    H5FD_t pub; /* first: HDF5 sees the driver's files through it */
    stream_info info;
    haddr_t eoa, eof;
    unsigned char *image; /* after a failed write: the whole file, image_size bytes */
    size_t image_size;
    int dead; /* no memory for image either: writes dropped, reads zeros */
} stream_file;

/* Records err as the first failure of f's writes. */
static void stream_fail(stream_file *f, int err)
{
    if (*f->info.err == 0)
        *f->info.err = err != 0 ? err : EIO;
}

/* Reads size bytes at offset of f's descriptor into buf, zeros where it ends. @return 0, or errno. */
static int read_fd(int fd, unsigned char *buf, size_t size, off_t offset)
{
    while (size > 0) {
        ssize_t got = pread(fd, buf, size, offset);
        if (got < 0 && errno == EINTR)
            continue;
        if (got < 0)
            return errno;
        if (got == 0) {
            memset(buf, 0, size);
            return 0;
        }
        buf += got, size -= (size_t)got, offset += got;
    }
    return 0;
}

/* Writes size bytes at offset to fd. @return 0, or errno. */
static int write_fd(int fd, const unsigned char *buf, size_t size, off_t offset)
{
    while (size > 0) {
        ssize_t put = pwrite(fd, buf, size, offset);
        if (put < 0 && errno == EINTR)
            continue;
        if (put <= 0)
            return put < 0 ? errno : EIO;
        buf += put, size -= (size_t)put, offset += put;
    }
    return 0;
}

/* Grows f's image to hold end bytes (zeros past what it held). @return 0, or -1 without memory. */
static int image_reserve(stream_file *f, size_t end)
{
    if (end <= f->image_size)
        return 0;
    size_t cap = f->image_size > end / 2 ? 2 * f->image_size : end;
    unsigned char *grown = realloc(f->image, cap ? cap : 1);
    if (grown == NULL)
        return -1;
    memset(grown + f->image_size, 0, cap - f->image_size);
    f->image = grown;
    f->image_size = cap;
    return 0;
}

/* Moves f to memory after a failed write: the image takes what the descriptor holds (zeros where it
 * cannot be read); without memory for it, f is dead. */
static void switch_to_image(stream_file *f)
{
    if (image_reserve(f, f->eof > 0 ? (size_t)f->eof : 1) != 0) {
        f->dead = 1;
        return;
    }
    if (f->eof > 0 && read_fd(f->info.fd, f->image, (size_t)f->eof, 0) != 0)
        memset(f->image, 0, (size_t)f->eof);
}

static H5FD_t *stream_open(const char *name, unsigned flags, hid_t fapl, haddr_t maxaddr)
{
    (void)name, (void)flags, (void)maxaddr;
    const stream_info *info = H5Pget_driver_info(fapl);
    if (info == NULL || info->fd < 0 || info->err == NULL)
        return NULL;
    stream_file *f = calloc(1, sizeof *f);
    struct stat st;
    /* the caller's file is new and empty (flags' H5F_ACC_TRUNC holds): its size is the end of file */
    int fd = f != NULL && fstat(info->fd, &st) == 0 ? dup(info->fd) : -1;
    if (fd < 0) {
        if (*info->err == 0)
            *info->err = f == NULL ? ENOMEM : errno; /* HDF5 would say only that opening failed */
        free(f);
        return NULL;
    }
    f->info = *info;
    f->info.fd = fd;
    f->eof = st.st_size > 0 ? (haddr_t)st.st_size : 0;
    return &f->pub;
}

static herr_t stream_close(H5FD_t *file)
{
    stream_file *f = (stream_file *)file;
    close(f->info.fd); /* its duplicate: the caller's descriptor stays open */
    free(f->image);
    free(f);
    return 0;
}

static herr_t stream_query(const H5FD_t *file, unsigned long *flags)
{
    (void)file;
    /* as HDF5's own POSIX driver: small metadata and raw data gathered into larger writes */
    *flags = H5FD_FEAT_AGGREGATE_METADATA | H5FD_FEAT_ACCUMULATE_METADATA | H5FD_FEAT_DATA_SIEVE
             | H5FD_FEAT_AGGREGATE_SMALLDATA;
    return 0;
}

static haddr_t stream_get_eoa(const H5FD_t *file, H5FD_mem_t type)
{
    (void)type;
    return ((const stream_file *)file)->eoa;
}

static herr_t stream_set_eoa(H5FD_t *file, H5FD_mem_t type, haddr_t addr)
{
    (void)type;
    ((stream_file *)file)->eoa = addr;
    return 0;
}

static haddr_t stream_get_eof(const H5FD_t *file, H5FD_mem_t type)
{
    (void)type;
    return ((const stream_file *)file)->eof;
}

static herr_t stream_read(H5FD_t *file, H5FD_mem_t type, hid_t dxpl, haddr_t addr, size_t size, void *buf)
{
    (void)type, (void)dxpl;
    stream_file *f = (stream_file *)file;
    if (addr > (haddr_t)INT64_MAX - size)
        return -1;
    if (f->dead) {
        memset(buf, 0, size);
        return 0;
    }
    if (f->image == NULL) {
        int err = read_fd(f->info.fd, buf, size, (off_t)addr);
        if (err != 0)
            stream_fail(f, err); /* HDF5 reports its own failure; the caller learns why */
        return err == 0 ? 0 : -1;
    }
    size_t have = addr < f->image_size ? f->image_size - (size_t)addr : 0, take = have < size ? have : size;
    if (take)
        memcpy(buf, f->image + addr, take);
    memset((unsigned char *)buf + take, 0, size - take);
    return 0;
}

static herr_t stream_write(H5FD_t *file, H5FD_mem_t type, hid_t dxpl, haddr_t addr, size_t size, const void *buf)
{
    (void)type, (void)dxpl;
    stream_file *f = (stream_file *)file;
    if (addr > (haddr_t)INT64_MAX - size)
        return -1;
    if (f->image == NULL && !f->dead) {
        int err = write_fd(f->info.fd, buf, size, (off_t)addr);
        if (err == 0) {
            f->eof = addr + size > f->eof ? addr + size : f->eof;
            return 0;
        }
        /* never a failure HDF5 sees (see the top): keep the error, and the file in memory from now on */
        stream_fail(f, err);
        switch_to_image(f);
    }
    if (!f->dead && image_reserve(f, (size_t)(addr + size)) != 0)
        f->dead = 1;
    if (!f->dead)
        memcpy(f->image + addr, buf, size);
    f->eof = addr + size > f->eof ? addr + size : f->eof;
    return 0;
}

static herr_t stream_truncate(H5FD_t *file, hid_t dxpl, hbool_t closing)
{
    (void)dxpl, (void)closing;
    stream_file *f = (stream_file *)file;
    if (f->eoa == f->eof)
        return 0;
    if (f->image == NULL && !f->dead && ftruncate(f->info.fd, (off_t)f->eoa) != 0)
        stream_fail(f, errno);
    if (f->image != NULL && f->eoa < f->image_size) /* what lies past the end reads as zeros again */
        memset(f->image + f->eoa, 0, f->image_size - (size_t)f->eoa);
    f->eof = f->eoa;
    return 0;
}

/* Every callback not named is HDF5's default: no superblock data or transfer properties of the
 * driver's own, HDF5's allocation at the end of the address space, no locking (the temporary is the
 * writer's alone), no flush (every write is already on the descriptor). HDF5 copies and frees the
 * driver's information (fapl_size bytes) itself. */
static const H5FD_class_t stream_class = {
    .name = "lfio_stream",
    .maxaddr = (haddr_t)INT64_MAX,
    .fc_degree = H5F_CLOSE_WEAK,
    .fapl_size = sizeof(stream_info),
    .open = stream_open,
    .close = stream_close,
    .query = stream_query,
    .get_eoa = stream_get_eoa,
    .set_eoa = stream_set_eoa,
    .get_eof = stream_get_eof,
    .read = stream_read,
    .write = stream_write,
    .truncate = stream_truncate,
    .fl_map = H5FD_FLMAP_DICHOTOMY,
};

hid_t lfio__h5_stream_register(void)
{
    return H5FDregister(&stream_class);
}

int lfio__h5_stream_fapl(hid_t fapl, hid_t driver, int fd, int *err)
{
    stream_info info = {fd, err};
    return H5Pset_driver(fapl, driver, &info) >= 0 ? 0 : -1;
}
