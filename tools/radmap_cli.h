/*
 * radmap_cli.h - what the `ilf` commands share about radiance-map files
 * (radiance.h5 of `ilf relight`, lfio/radmap.h): telling one from a light
 * field, reading one with the command's messages, and describing it for
 * `ilf info`.
 *
 * Invariants: radiance maps are read only through lfio's public readers
 * (lfio_radmap_read, lfio_radmap_read_headers), so a change of their storage stays inside lfio.
 */
#ifndef ILF_RADMAP_CLI_H
#define ILF_RADMAP_CLI_H

#include "lfio/radmap.h"

/**
 * Reads path as a radiance map (whole, or its headers only when whole is 0)
 * after lfio's light field reader refused it
 * with LFIO_ERR_FORMAT and message lf_msg: a file that is not a radiance map
 * either keeps the light field's message; one that is a radiance map but
 * damaged (the radiance-map reader fails otherwise than on the format, or
 * the light field reader quotes the radiance-map format name) gets the
 * radiance-map reader's.
 * @return LFIO_OK and *out; else the status, with the message to report in
 * msg (msg_size bytes).
 */
lfio_status ilf_radmap_try(const char *path, const char *lf_msg, int whole, lfio_radmap **out, char *msg,
                           size_t msg_size);

/**
 * Reads path as a radiance map for command sub, reporting a failure
 * (cli_lfio_failure's form and codes).
 * @return an exit code (0 and *out on success).
 */
int ilf_radmap_open(const char *sub, const char *path, lfio_radmap **out);

/** `ilf info` on a radiance map: text or JSON, area-weighted statistics with stats when map holds its cells.
 * @return an exit code. */
int ilf_info_radmap(const char *path, const lfio_radmap *map, int json, int stats);

#endif /* ILF_RADMAP_CLI_H */
