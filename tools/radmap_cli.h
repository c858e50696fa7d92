/*
 * radmap_cli.h - what the `ilf` commands share about radiance-map files
 * (radiance.h5 of `ilf relight`, lfio/radmap.h): telling one from a light
 * field, reading one with the command's messages, and describing it for
 * `ilf info`.
 *
 * Invariants: radiance maps are read only through lfio's public readers
 * (lfio_radmap_read, lfio_radmap_headers_open), so a change of their storage stays inside lfio.
 */
#ifndef ILF_RADMAP_CLI_H
#define ILF_RADMAP_CLI_H

#include "lfio/radmap.h"

/**
 * Reads path whole as a radiance map after lfio's light field reader refused
 * it with LFIO_ERR_FORMAT and message lf_msg: a file that is not a radiance
 * map either keeps the light field's message; one that is a radiance map but
 * damaged (the radiance-map reader fails otherwise than on the format, or
 * the light field reader quotes the radiance-map format name) gets the
 * radiance-map reader's.
 * @return LFIO_OK and *out; else the status, with the message to report in
 * msg (msg_size bytes).
 */
lfio_status ilf_radmap_try(const char *path, const char *lf_msg, lfio_radmap **out, char *msg, size_t msg_size);

/** As ilf_radmap_try(), opening path's headers (lfio_radmap_headers_open()) instead of reading it whole. */
lfio_status ilf_radmap_try_headers(const char *path, const char *lf_msg, lfio_radmap_headers **out, char *msg,
                                   size_t msg_size);

/**
 * Reads path as a radiance map for command sub, reporting a failure
 * (cli_lfio_failure's form and codes).
 * @return an exit code (0 and *out on success).
 */
int ilf_radmap_open(const char *sub, const char *path, lfio_radmap **out);

/** What `ilf info` describes of a radiance map, and how. */
typedef struct ilf_radmap_info {
    const char *path;
    const char *lf_msg;            /**< the light field reader's message on path, for failures (ilf_radmap_try()) */
    const lfio_radmap *map;        /**< the file read whole (for --stats), or NULL */
    lfio_radmap_headers *headers;  /**< else its headers, read a block at a time */
    int json;                      /**< JSON (every map) instead of text */
    int stats;                     /**< area-weighted statistics (when map holds its cells) */
    int all_maps;                  /**< text: every map's details (--maps), not only the first few */
} ilf_radmap_info;

/** `ilf info` on a radiance map: the summary, then maps one at a time, so that memory stays bounded with
 * headers whatever the number of maps. @return an exit code. */
int ilf_info_radmap(const ilf_radmap_info *in);

#endif /* ILF_RADMAP_CLI_H */
