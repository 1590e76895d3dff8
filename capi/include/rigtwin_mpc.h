/*
 * rigtwin_mpc.h — rigtwin's model-predictive controller of the open-differential rig for C and
 * real-time targets (a static library librigtwin_mpc.a and a shared library
 * librigtwin_mpc.so / .dylib / .dll, built by `cargo build --release -p rigtwin-mpc`); the link
 * lines and a minimal program are in capi/examples/minimal.c and docs/c-api.md.
 *
 * The controller is the one `rigtwin mpc` runs: Clarabel QP on the rig's prediction model
 * (the rig file's [model] and [effects]: a dead time as input-delay states, an actuator lag and
 * a drive compliance as states; backlash left out, the prediction is linear in contact),
 * a steady-state Kalman filter with input disturbances, sample time 1 ms.
 *
 * Signals (SI units, fixed order):
 *   measured[3]  = { w_m2, w_drive, w_m3 }        speeds of load machine M2, drive, M3, rad/s
 *   reference[3] = { w_m2_ref, w_m3_ref, M_drive_ref }   load speeds rad/s, drive torque N.m
 *   torques[3]   = { M_m2, M_drive, M_m3 }        torque commands, N.m
 *
 * Real-time use: create and reset outside the loop (they allocate); step allocates nothing in
 * rigtwin's code (Clarabel 0.11's solve makes one small allocation per call, its timer), never
 * unwinds a Rust panic into C, and never returns a non-finite torque. Not thread-safe per
 * controller; separate controllers are independent.
 */
#ifndef RIGTWIN_MPC_H
#define RIGTWIN_MPC_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* An opaque controller. */
typedef struct rigtwin_mpc rigtwin_mpc;

/* What a step did. */
typedef enum rigtwin_mpc_status {
    /* The QP was solved; torques[] is the first move of its plan. */
    RIGTWIN_MPC_OK = 0,
    /* The solve failed or ran past its time limit: torques[] is the shifted previous plan. */
    RIGTWIN_MPC_FALLBACK = 1,
    /* A measurement or reference was not finite: torques[] repeats the previous command and the
       controller's state is unchanged. */
    RIGTWIN_MPC_BAD_INPUT = -1,
    /* A NULL pointer, or the controller failed internally (it then refuses every further step;
       free it and create another). */
    RIGTWIN_MPC_INVALID = -2
} rigtwin_mpc_status;

/* Construction options; rigtwin_mpc_default_options fills in the defaults. */
typedef struct rigtwin_mpc_options {
    /* Prediction horizon, steps of 1 ms (1..200; default 50). */
    int horizon;
    /* Move blocks 1, 2, 4, ... with the last taking the rest (0: every step free; default 4). */
    int move_blocks;
    /* Wall-clock limit of one QP solve, s (default 6e-4: 60 % of the 1 ms period). */
    double time_limit_s;
} rigtwin_mpc_options;

/* Fills *options with the defaults. */
void rigtwin_mpc_default_options(rigtwin_mpc_options *options);

/*
 * Creates a controller for the parameter set in params_path: a rig file (TOML, as
 * rigs/paper.toml, or a model written by `rigtwin diagnose --write-model`) or a params.json from
 * an FMU's resources; NULL: the embedded paper rig. options NULL: the defaults. The controller
 * starts at rest (rigtwin_mpc_reset sets the operating point). On failure returns NULL and
 * writes a NUL-terminated message naming the file and field into error (error_len bytes, may
 * be 0 with error NULL).
 */
rigtwin_mpc *rigtwin_mpc_create(const char *params_path, const rigtwin_mpc_options *options, char *error,
                                size_t error_len);

/* Restarts from steady spinning at speed_radps (every machine at that speed, the load machines
   holding it against their drag, no drive torque). Returns RIGTWIN_MPC_OK, or
   RIGTWIN_MPC_BAD_INPUT for a non-finite speed, RIGTWIN_MPC_INVALID for NULL. */
rigtwin_mpc_status rigtwin_mpc_reset(rigtwin_mpc *controller, double speed_radps);

/* One 1 ms control step: the measurements now and the references in, the torques to apply
   until the next step out. */
rigtwin_mpc_status rigtwin_mpc_step(rigtwin_mpc *controller, const double measured[3], const double reference[3],
                                    double torques[3]);

/* Frees a controller (NULL is ignored). */
void rigtwin_mpc_free(rigtwin_mpc *controller);

#ifdef __cplusplus
}
#endif

#endif /* RIGTWIN_MPC_H */
