/*
 * The smallest program that runs rigtwin's controller from C: the embedded paper rig, a
 * drive-torque reference step of 40 N.m at 50 ms while the load machines hold 10 rad/s, for
 * 100 ms. The "plant" here is the measurement held at the operating point (a real program reads
 * its encoders); what it shows is the call sequence and the status handling.
 *
 * Build (from the repository root, after `cargo build --release -p rigtwin-mpc`):
 *   static: cc -std=c99 -I capi/include capi/examples/minimal.c \
 *              target/release/librigtwin_mpc.a -lm -lpthread -ldl -o minimal
 *   shared: cc -std=c99 -I capi/include capi/examples/minimal.c \
 *              -L target/release -lrigtwin_mpc -Wl,-rpath,$PWD/target/release -lm -o minimal
 */
#include <stdio.h>

#include "rigtwin_mpc.h"

int main(void) {
    rigtwin_mpc_options options;
    rigtwin_mpc_default_options(&options);
    /* Offline (a replay, a test) the wall-clock time limit makes results depend on the
       machine's load: give the solver all the time it needs. On the rig keep the default
       (60 % of the 1 ms period). */
    options.time_limit_s = 1.0;

    char error[512];
    rigtwin_mpc *c = rigtwin_mpc_create(NULL, &options, error, sizeof error);
    if (c == NULL) {
        fprintf(stderr, "rigtwin_mpc_create: %s\n", error);
        return 1;
    }
    const double speed = 10.0;
    if (rigtwin_mpc_reset(c, speed) != RIGTWIN_MPC_OK) {
        rigtwin_mpc_free(c);
        return 1;
    }
    double torques[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < 100; k++) {
        const double measured[3] = {speed, speed, speed};
        const double reference[3] = {speed, speed, k >= 50 ? 40.0 : 0.0};
        rigtwin_mpc_status s = rigtwin_mpc_step(c, measured, reference, torques);
        if (s != RIGTWIN_MPC_OK) {
            fprintf(stderr, "step %d: status %d\n", k, (int)s);
            rigtwin_mpc_free(c);
            return 1;
        }
    }
    printf("after 100 ms: M_m2 = %.3f N.m, M_drive = %.3f N.m, M_m3 = %.3f N.m\n", torques[0], torques[1],
           torques[2]);
    rigtwin_mpc_free(c);
    return 0;
}
