/*
 * ilf/limits.h - every user-facing limit of ilfkit in one place, each with the
 * reason for its value (after SQLite's sqliteLimit.h).
 *
 * A limit here bounds what an input may ask for: a reader refuses anything
 * beyond it with an error naming the file and the limit, so a hostile or
 * mistaken input costs time and memory in proportion to its size, never more
 * (docs/robustness.md). Public headers that promise a limit to library users
 * (lfio's LFIO_SLAB_MAX_N, ...) keep their own names; where one of those is the
 * same quantity, it is defined from the value here or checked against it.
 *
 * Units: bytes unless a name says otherwise; counts are plain numbers.
 */
#ifndef ILF_LIMITS_H
#define ILF_LIMITS_H

/* Worker threads in one team. "0 = every core" asks for the online cores; no machine that runs a
 * 2026 build has more, and each thread costs a stack (8 MiB of address space) and a scratch buffer. */
#define ILF_MAX_THREADS 1024u

/* Bytes of one error message a library owns (per thread). A message names one file and one problem;
 * a longer one is cut at this length, never overrun. */
#define ILF_MESSAGE_BYTES 1024u

/* Pixels along either side of an image read or written (image/image.h). Far beyond any light probe or
 * view ilf makes, small enough that width * height * 4 channels of float stays addressable. */
#define ILF_IMAGE_MAX_SIDE 65536

/* Samples (width * height * channels) of one image read: 8 GiB of float. A corrupt or hostile header
 * cannot make the reader allocate more than this, whatever sides it claims. */
#define ILF_IMAGE_MAX_SAMPLES (1LL << 31)

#endif /* ILF_LIMITS_H */
