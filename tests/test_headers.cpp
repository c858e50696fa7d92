// test_headers.cpp - compiled, not run: the public headers are usable from C++.
#include "lfio/lfio.h"
#include "lfio/lightfield.h"
#include "lfio/partition.h"
#include "lfio/radmap.h"
#include "relight/job.h"
#include "relight/engine.h"
#include "relight/raycast.h"
#include "relight/reference.h"
#include "relight/relight.h"
#include "relight/scene.h"

int header_probe_cxx();
int header_probe_cxx()
{
    lfio_slab_desc d;
    lfio_slab_desc_init(&d);
    return static_cast<int>(lfio_part_count(d.n));
}
