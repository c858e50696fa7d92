/* consumer_capture.c - a program against an installed capture: it captures the probe images of a
 * manifest into a light field (cap_capture_run()), writes it (lfio) and checks that every position
 * was captured and the irradiance at the first slab's centre is finite and positive. */
#include <math.h>
#include <stdio.h>

#include <capture/capture.h>
#include <lfio/lightfield.h>

int main(int argc, char **argv)
{
    cap_manifest *m = NULL;
    lfio_lightfield *lf = NULL;
    cap_report report;
    if (argc != 3) {
        fprintf(stderr, "usage: consumer_capture MANIFEST.json OUT.h5\n");
        return 2;
    }
    if (cap_manifest_load(argv[1], &m) != CAP_OK || cap_capture_run(m, NULL, &lf, &report) != CAP_OK) {
        fprintf(stderr, "consumer_capture: %s\n", cap_error_message());
        cap_manifest_destroy(m);
        return 1;
    }
    const lfio_slab_desc *d = cap_manifest_get_desc(m, 0);
    double e[3];
    lfio_slab_irradiance(lfio_lightfield_slab(lf, 0), 0.5, 0.5, e);
    int ok = report.positions == (uint64_t)d->nu * d->nv && isfinite(e[0]) && e[0] > 0;
    if (lfio_lightfield_write(lf, argv[2]) != LFIO_OK) {
        fprintf(stderr, "consumer_capture: %s\n", lfio_errmsg());
        ok = 0;
    }
    printf("consumer_capture: %llu positions, %llu images, irradiance %g %g %g W m^-2 %s\n",
           (unsigned long long)report.positions, (unsigned long long)report.images, e[0], e[1], e[2],
           ok ? "ok" : "WRONG");
    cap_report_free(&report);
    lfio_lightfield_destroy(lf);
    cap_manifest_destroy(m);
    return ok ? 0 : 1;
}
