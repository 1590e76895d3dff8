/* Replays a closed-loop record through the C API: reads the operating speed and then, per
   line, the measured speeds and the references a Rust closed loop gave its controller; steps
   a controller created from the same parameter file with them and prints its torques and
   status, one line per step. Also exercises the API's refusals. Exit code 0 on success. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "rigtwin_mpc.h"

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: %s PARAMS RECORD\n", argv[0]);
        return 2;
    }
    char error[512];

    /* refusals: a missing file names itself, NULL pointers are refused, not crashed on */
    rigtwin_mpc *none = rigtwin_mpc_create("/nonexistent/rig.toml", NULL, error, sizeof error);
    if (none != NULL || strstr(error, "/nonexistent/rig.toml") == NULL) {
        fprintf(stderr, "missing file not refused by name: %s\n", error);
        return 3;
    }
    double m[3] = {0, 0, 0}, r[3] = {0, 0, 0}, t[3];
    if (rigtwin_mpc_step(NULL, m, r, t) != RIGTWIN_MPC_INVALID) return 4;
    rigtwin_mpc_free(NULL);

    rigtwin_mpc_options options;
    rigtwin_mpc_default_options(&options);
    options.time_limit_s = 1.0; /* the same solves as the Rust loop, whatever the clock */
    rigtwin_mpc *c = rigtwin_mpc_create(argv[1], &options, error, sizeof error);
    if (c == NULL) {
        fprintf(stderr, "create: %s\n", error);
        return 5;
    }
    FILE *f = fopen(argv[2], "r");
    if (f == NULL) return 6;
    double speed;
    if (fscanf(f, "%lf", &speed) != 1) return 7;
    if (rigtwin_mpc_reset(c, speed) != RIGTWIN_MPC_OK) return 8;
    while (fscanf(f, "%lf %lf %lf %lf %lf %lf", &m[0], &m[1], &m[2], &r[0], &r[1], &r[2]) == 6) {
        rigtwin_mpc_status s = rigtwin_mpc_step(c, m, r, t);
        printf("%.17g %.17g %.17g %d\n", t[0], t[1], t[2], (int)s);
    }
    fclose(f);

    /* a NaN measurement is refused and the previous command repeated */
    double last[3] = {t[0], t[1], t[2]};
    m[0] = NAN;
    if (rigtwin_mpc_step(c, m, r, t) != RIGTWIN_MPC_BAD_INPUT) return 9;
    if (t[0] != last[0] || t[1] != last[1] || t[2] != last[2]) return 10;
    rigtwin_mpc_free(c);
    return 0;
}
