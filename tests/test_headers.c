/*
 * test_headers.c - compiled, not run: every public header must stand alone
 * and be valid pedantic C99 and C17 (tests/CMakeLists.txt builds this file
 * once per standard with -Werror). Included twice to check the guards.
 */
#include "lfio/lfio.h"
#include "lfio/partition.h"
#include "lfio/radmap.h"
#include "relight/job.h"
#include "relight/engine.h"
#include "relight/raycast.h"
#include "relight/reference.h"
#include "relight/relight.h"
#include "relight/scene.h"
#include "lfio/lightfield.h"
#include "lfio/lightfield.h"

/* Uses one declaration of each header so the compile is not vacuous. */
int header_probe(void);
int header_probe(void)
{
    lfio_slab_desc d;
    lfio_slab_desc_init(&d);
    return (int)lfio_part_count(d.n) + (int)LFIO_OK + (int)LFIO_UNITS_RELATIVE;
}
