#!/usr/bin/env python3
"""Solve the MPC's QPs with OSQP and DAQP beside Clarabel (rigtwin's solver).

Input: the JSON written by `rigtwin mpc --export-qp FILE` — QPs of several controller steps
(P, q, A, b with the first n_eq rows equalities and the rest A z <= b, the map from z to the
first input u0 in Nm), each with the first input and solve time rigtwin's Clarabel got.

DAQP (dual active set) solves these dense QPs to machine precision and is the reference for
the first input; OSQP (ADMM) is run with eps 1e-6 and polishing. Prints a table and writes
JSON: per solver the median and p99 solve time (us) and the largest |u0 - u0_daqp| (Nm).
"""
import json
import sys
import time

import numpy as np
import osqp
import daqp
import scipy.sparse as sp


def timed(fn, repeats):
    best = []
    out = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best.append(time.perf_counter() - t0)
    return out, float(np.median(best))


def main():
    if len(sys.argv) < 2:
        sys.exit("usage: qp_compare.py QPS.json [OUT.json]")
    with open(sys.argv[1]) as f:
        data = json.load(f)
    qps = data["qps"]
    rows = {"clarabel": [], "osqp": [], "daqp": []}
    err = {"clarabel": 0.0, "osqp": 0.0}
    for qp in qps:
        P = np.array(qp["p"], dtype=float)
        q = np.array(qp["q"], dtype=float)
        A = np.array(qp["a"], dtype=float)
        b = np.array(qp["b"], dtype=float)
        neq = qp["n_eq"]
        U0 = np.array(qp["u0_map"], dtype=float)
        lower = np.full(len(b), -np.inf)
        lower[:neq] = b[:neq]
        sense = np.zeros(len(b), dtype=np.int32)
        sense[:neq] = 5

        def run_daqp():
            x, _, flag, _ = daqp.solve(P, q, A, b, lower, sense)
            if flag < 1:
                raise RuntimeError(f"DAQP exit flag {flag}")
            return x

        x_daqp, t_daqp = timed(run_daqp, 20)
        u0_ref = U0 @ x_daqp

        solver = osqp.OSQP()
        solver.setup(sp.csc_matrix(np.triu(P)), q, sp.csc_matrix(A), lower, b, verbose=False,
                     eps_abs=1e-6, eps_rel=1e-6, polishing=True, max_iter=20000)

        def run_osqp():
            r = solver.solve()
            return r.x

        x_osqp, t_osqp = timed(run_osqp, 20)
        rows["daqp"].append(t_daqp)
        rows["osqp"].append(t_osqp)
        rows["clarabel"].append(qp["clarabel_solve_time_us"] * 1e-6)
        err["osqp"] = max(err["osqp"], float(np.max(np.abs(U0 @ x_osqp - u0_ref))))
        err["clarabel"] = max(err["clarabel"], float(np.max(np.abs(np.array(qp["clarabel_u0_Nm"]) - u0_ref))))

    report = {}
    print(f"{len(qps)} QPs of {len(qps[0]['q'])} variables and {len(qps[0]['b'])} constraints")
    print(f"{'solver':10s} {'median_us':>10s} {'p99_us':>10s} {'max |u0 - u0_daqp| (Nm)':>26s}")
    for name, times in rows.items():
        t = np.array(times) * 1e6
        e = err.get(name, 0.0)
        report[name] = {"median_us": float(np.median(t)), "p99_us": float(np.percentile(t, 99)),
                        "u0_error_Nm": e}
        print(f"{name:10s} {np.median(t):10.1f} {np.percentile(t, 99):10.1f} {e:26.3e}")
    if len(sys.argv) > 2:
        with open(sys.argv[2], "w") as f:
            json.dump(report, f, indent=2)


if __name__ == "__main__":
    main()
