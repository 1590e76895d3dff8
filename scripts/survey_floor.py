"""How well the truth itself fits each `drive_test` record of `survey_lines.py`: the record's
noise floor (the truth simulated from the commanded input, against the measurement) and the
truth simulated from the recorded input (the command plus the torque sensor's noise), as rigtwin
must simulate it. Both errors are rigtwin's (each output high-passed as `diagnose` does and
weighted by its own norm). Where the second is far above the first, no model is judged well by
the error of a simulation over the whole record (a play that rattles: docs/validation.md, step
13).

    python scripts/survey_floor.py --records /tmp/lines --seeds 0-34

`--records` holds the bundles `survey_lines.py` wrote for these seeds.
"""

import reproducible  # noqa: F401  (first: the records alike on every machine)
import argparse
import os
import sys
from multiprocessing import Pool

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import survey_lines as S  # noqa: E402
from refit_check import high_pass  # noqa: E402
from refit_check_lines import HIGH_PASS_MIN_HZ  # noqa: E402


def floors(args):
    """(seed, truth's description, noise floor, error from the recorded input)."""
    folder, seed = args
    t = S.truth_of(seed)
    data = np.genfromtxt(os.path.join(folder, f"line_{seed:04d}.csv"), delimiter=",", names=True)
    cols = data.dtype.names
    dt, steps = float(data["time_s"][1] - data["time_s"][0]), len(data)
    recorded = np.column_stack([data[c] for c in cols if c.startswith("torque_in")])
    fc = max(3.0 / (steps * dt), HIGH_PASS_MIN_HZ)
    measured = [high_pass(np.asarray(data[c]), dt, fc) for c in cols[1 + recorded.shape[1]:]]
    weights = [1.0 / (np.sqrt(m @ m) * np.sqrt(len(measured))) for m in measured]

    def error(outputs):
        return float(np.sqrt(sum((w * np.linalg.norm(high_pass(o, dt, fc) - m)) ** 2
                                 for w, o, m in zip(weights, outputs, measured))))

    commanded, truth = S.simulate(t, np.random.default_rng(t["noise_seed"]))
    line = S.Line(t)
    line.u = recorded
    sol = solve_ivp(line.rhs, (0.0, steps * dt), line.start(commanded[0]), t_eval=np.arange(steps) * dt,
                    method="LSODA", max_step=dt / 2, rtol=1e-7, atol=1e-10)
    states, n = sol.y.T, line.n
    replayed = [states[:, n + at] if q == "speed"
                else np.array([line.coupling_torques(s[:n], s[n:2 * n]) for s in states])[:, at]
                for q, at in t["outputs"]]
    what = "+".join(e["effect"] for e in t["effects"]) or "none"
    return seed, f"{what} {t['excitation']} set point {t['set_point_nm'] / t['amplitude']:.1f}", error(truth), error(replayed)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--records", required=True)
    ap.add_argument("--seeds", default="0-34")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    args = ap.parse_args()
    a, b = map(int, args.seeds.split("-"))
    print("| seed | truth | noise floor | the truth from the recorded input |")
    print("| --- | --- | --- | --- |")
    with Pool(args.jobs) as pool:
        for seed, what, floor, replayed in pool.imap(floors, [(args.records, s) for s in range(a, b + 1)]):
            print(f"| {seed} | {what} | {floor:.4f} | {replayed:.4f} |", flush=True)


if __name__ == "__main__":
    main()
