/*
 * rigtwin_mpc.h — rigtwin's model-predictive controller for C and real-time targets (a static
 * library librigtwin_mpc.a and a shared library librigtwin_mpc.so / .dylib / .dll, built by
 * `cargo build --release -p rigtwin-mpc`); the link lines and a minimal program are in
 * capi/examples/minimal.c and docs/c-api.md.
 *
 * The controller is the one `rigtwin mpc` runs, on the model file it is created from: the paper
 * rig (its [model] and [effects]) or any drive model (a drive_model file or a drive_test
 * bundle, with its [mpc] section: tracked and penalised signals, input bounds). Clarabel QP on
 * the model's linearisation (dead times as input-delay states, an actuator lag and a drive
 * compliance as states; backlash and friction left out: the prediction is linear, in contact),
 * a steady-state Kalman filter with input disturbances, sample time 1 ms.
 *
 * Signals (SI units; rigtwin_mpc_count and rigtwin_mpc_name give each list of a controller):
 *   measured[]   the plant outputs the controller reads (speeds: rad/s, m/s)
 *   reference[]  the tracked outputs' references, then the tracked inputs'
 *   commands[]   the plant's inputs to apply (N.m, N)
 * The paper rig's lists are fixed:
 *   measured[3]  = { w_m2, w_drive, w_m3 }        speeds of load machine M2, drive, M3, rad/s
 *   reference[3] = { w_m2, w_m3, M_drive }        load speeds rad/s, drive torque N.m
 *   commands[3]  = { M_m2, M_drive, M_m3 }        torque commands, N.m
 *
 * Real-time use: create and reset outside the loop (they allocate); step allocates nothing in
 * rigtwin's code (Clarabel 0.11's solve makes one small allocation per call, its timer), never
 * unwinds a Rust panic into C, and never returns a non-finite command. Not thread-safe per
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
    /* The QP was solved; commands[] is the first move of its plan. */
    RIGTWIN_MPC_OK = 0,
    /* The solve failed or ran past its time limit: commands[] is the shifted previous plan. */
    RIGTWIN_MPC_FALLBACK = 1,
    /* A measurement or reference was not finite: commands[] repeats the previous commands and
       the controller's state is unchanged. */
    RIGTWIN_MPC_BAD_INPUT = -1,
    /* A NULL pointer, or the controller failed internally (it then refuses every further step
       and repeats the last finite commands until rigtwin_mpc_reset). */
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

/* Which of a controller's signal lists. */
typedef enum rigtwin_mpc_signals {
    RIGTWIN_MPC_MEASURED = 0,
    RIGTWIN_MPC_REFERENCES = 1,
    RIGTWIN_MPC_COMMANDS = 2
} rigtwin_mpc_signals;

/*
 * Creates a controller for the model file model_path: a rig file (TOML, as rigs/paper.toml, or a
 * model written by `rigtwin diagnose --write-model`), a drive_model file or a drive_test bundle
 * (its data are not read; a drive model needs [mpc] input_max); NULL: the embedded paper rig.
 * options NULL: the defaults. The controller starts at rest (rigtwin_mpc_reset sets the
 * operating point). On failure returns NULL and writes a NUL-terminated message naming the file
 * and key into error (error_len bytes, may be 0 with error NULL).
 */
rigtwin_mpc *rigtwin_mpc_create(const char *model_path, const rigtwin_mpc_options *options, char *error,
                                size_t error_len);

/* Number of entries of the list `which` (a rigtwin_mpc_signals value); 0 for NULL or an unknown
   list. */
size_t rigtwin_mpc_count(const rigtwin_mpc *controller, int which);

/* The name of entry `index` of the list `which` (NUL-terminated, owned by the controller, valid
   until it is freed), or NULL past the end. */
const char *rigtwin_mpc_name(const rigtwin_mpc *controller, int which, size_t index);

/* Restarts from steady motion: the first body of the model at `speed` (rad/s or m/s; the paper
   rig: every machine), the others as the gear stages turn them, the couplings twisted as the
   drag behind them needs, the inputs holding it; 0: at rest. Returns RIGTWIN_MPC_OK, or
   RIGTWIN_MPC_BAD_INPUT for a non-finite speed or one the model cannot move at (a spring to
   ground holds it: only 0), RIGTWIN_MPC_INVALID for NULL. */
rigtwin_mpc_status rigtwin_mpc_reset(rigtwin_mpc *controller, double speed);

/* One control step: the measurements now and the references in (rigtwin_mpc_count entries
   each, in the order rigtwin_mpc_name gives), the commands to apply until the next step out. */
rigtwin_mpc_status rigtwin_mpc_step(rigtwin_mpc *controller, const double *measured, const double *reference,
                                    double *commands);

/* Frees a controller (NULL is ignored). */
void rigtwin_mpc_free(rigtwin_mpc *controller);

#ifdef __cplusplus
}
#endif

#endif /* RIGTWIN_MPC_H */
