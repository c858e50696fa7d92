/*
 * cli_limits.h - the limits on what an `ilf` command's own options may ask
 * for, each with the reason for its value. They bound options of the command
 * line alone, not any library's input, so they live with the tools; limits on
 * files and on what the libraries read stay in base's ilf/limits.h.
 */
#ifndef ILF_CLI_LIMITS_H
#define ILF_CLI_LIMITS_H

#include <stdint.h>

/* Pixels along either side of an `ilf slice` image: a slice shows one direction per pixel, and a
 * partition finer than 8192^2 directions is not stored. */
#define ILF_SLICE_MAX_SIDE 8192u

/* Spot lights one `ilf synth` call may place (each is a command-line option). */
#define ILF_SYNTH_MAX_SPOTS 64

/* Positions along either side of a synthesised slab (`ilf synth --grid`); lfio's slab size limit
 * usually binds first. */
#define ILF_SYNTH_MAX_GRID 65536u

/* Supersamples per axis when synthesising one radiance value (`ilf synth --supersample`). */
#define ILF_SYNTH_MAX_SUPERSAMPLE 64u

/* Evaluations one `ilf synth` makes (radiance values times supersample^2 times spots, at least one): 2^40.
 * Each option is bounded above, but together they could ask for years of work; checked before any. */
#define ILF_SYNTH_MAX_EVALUATIONS ((uint64_t)1 << 40)

#endif /* ILF_CLI_LIMITS_H */
