/* Replays a closed-loop record through the C API: reads the operating speed and then, per
   line, the measurements and the references a Rust closed loop gave its controller; steps a
   controller created from the same model file with them and prints its commands and status,
   one line per step. The first line of output names the controller's signals
   ("measured: ... | references: ... | commands: ..."). Also exercises the API's refusals.
   Exit code 0 on success. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "rigtwin_mpc.h"

#define MAX_SIGNALS 32

static void print_names(const rigtwin_mpc *c, int which) {
    size_t n = rigtwin_mpc_count(c, which);
    for (size_t i = 0; i < n; i++) printf(" %s", rigtwin_mpc_name(c, which, i));
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: %s MODEL RECORD\n", argv[0]);
        return 2;
    }
    char error[512];

    /* refusals: a missing file names itself, NULL pointers are refused, not crashed on */
    rigtwin_mpc *none = rigtwin_mpc_create("/nonexistent/rig.toml", NULL, error, sizeof error);
    if (none != NULL || strstr(error, "/nonexistent/rig.toml") == NULL) {
        fprintf(stderr, "missing file not refused by name: %s\n", error);
        return 3;
    }
    double m[MAX_SIGNALS] = {0}, r[MAX_SIGNALS] = {0}, t[MAX_SIGNALS] = {0};
    if (rigtwin_mpc_step(NULL, m, r, t) != RIGTWIN_MPC_INVALID) return 4;
    if (rigtwin_mpc_count(NULL, RIGTWIN_MPC_MEASURED) != 0) return 4;
    rigtwin_mpc_free(NULL);

    rigtwin_mpc_options options;
    rigtwin_mpc_default_options(&options);
    options.time_limit_s = 1.0; /* the same solves as the Rust loop, whatever the clock */
    rigtwin_mpc *c = rigtwin_mpc_create(argv[1], &options, error, sizeof error);
    if (c == NULL) {
        fprintf(stderr, "create: %s\n", error);
        return 5;
    }
    size_t nm = rigtwin_mpc_count(c, RIGTWIN_MPC_MEASURED), nr = rigtwin_mpc_count(c, RIGTWIN_MPC_REFERENCES),
           nc = rigtwin_mpc_count(c, RIGTWIN_MPC_COMMANDS);
    if (nm == 0 || nm > MAX_SIGNALS || nr > MAX_SIGNALS || nc == 0 || nc > MAX_SIGNALS) return 11;
    if (rigtwin_mpc_name(c, RIGTWIN_MPC_COMMANDS, nc) != NULL || rigtwin_mpc_count(c, 7) != 0) return 12;
    printf("measured:");
    print_names(c, RIGTWIN_MPC_MEASURED);
    printf(" | references:");
    print_names(c, RIGTWIN_MPC_REFERENCES);
    printf(" | commands:");
    print_names(c, RIGTWIN_MPC_COMMANDS);
    printf("\n");

    FILE *f = fopen(argv[2], "r");
    if (f == NULL) return 6;
    double speed;
    if (fscanf(f, "%lf", &speed) != 1) return 7;
    if (rigtwin_mpc_reset(c, speed) != RIGTWIN_MPC_OK) return 8;
    for (;;) {
        size_t got = 0;
        for (size_t i = 0; i < nm; i++) got += fscanf(f, "%lf", &m[i]) == 1;
        for (size_t i = 0; i < nr; i++) got += fscanf(f, "%lf", &r[i]) == 1;
        if (got != nm + nr) break;
        rigtwin_mpc_status s = rigtwin_mpc_step(c, m, r, t);
        for (size_t i = 0; i < nc; i++) printf("%.17g ", t[i]);
        printf("%d\n", (int)s);
    }
    fclose(f);

    /* a NaN measurement is refused and the previous commands repeated */
    double last[MAX_SIGNALS];
    memcpy(last, t, sizeof last);
    m[0] = NAN;
    if (rigtwin_mpc_step(c, m, r, t) != RIGTWIN_MPC_BAD_INPUT) return 9;
    if (memcmp(last, t, nc * sizeof(double)) != 0) return 10;
    rigtwin_mpc_free(c);
    return 0;
}
