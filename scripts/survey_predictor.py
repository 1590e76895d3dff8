"""Does a cost that restarts from the measurement measure a play where the error of a simulation
over the whole record does not (docs/validation.md, steps 13 and 14)? For each `drive_test`
record of `survey_lines.py`, the survey's own simulator (its play, a dead zone with contact
damping) with the truth's play scaled by each factor — or, in a record without play, a play at
the first coupling of that many times its elastic twist under the excitation's torque — and the
truth's or the declared inertias and stiffnesses, is run on the recorded inputs two ways:

- simulated over the whole record (`--gains 0`), as rigtwin's diagnosis scores a model today;
- as a one-step-ahead predictor: after each sample the state is corrected by the steady-state
  Kalman gain of the line's linear part (twists and speeds; the play closed) toward the measured
  outputs, with the input noise the survey puts on the torques (times `--gains`) as process
  noise and the encoders' and torque sensors' noise as measurement noise (the prediction-error
  method, Ljung, System Identification, ch. 7).

Both errors are rigtwin's (each output high-passed as `diagnose` does and weighted by its own
norm) on the predicted outputs. The states are stepped by RK4 at an eighth of the sample.

    python scripts/survey_predictor.py --records /tmp/lines --seeds 3,17,24,31 --factors 0,0.5,1,2

`--records` holds the bundles `survey_lines.py` wrote for these seeds.
"""

import reproducible  # noqa: F401  (first: the records alike on every machine)
import argparse
import os
import sys
from multiprocessing import Pool

import numpy as np
from scipy.linalg import expm, solve_discrete_are

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import survey_lines as S  # noqa: E402
from refit_check import high_pass  # noqa: E402
from refit_check_lines import HIGH_PASS_MIN_HZ  # noqa: E402

# measurement noise of an encoder's speed (survey.py's `measured`): white and coloured 2 mrad/s
# each, 1 mrad/s quantisation, (rad/s)^2
ENCODER_VARIANCE = 2 * 0.002 ** 2 + 0.001 ** 2 / 12
# RK4 steps per sample
SUBSTEPS = 8


def kalman_gain(t, line, dt, gain_scale):
    """The steady-state Kalman gain (filter form) of the line's linear part in twist coordinates
    [s (n-1), w (n)] for the record's outputs."""
    n, ln, e = line.n, t["line"], line.e
    jinv = np.diag(1 / ln["inertia"])
    a = np.zeros((2 * n - 1, 2 * n - 1))
    a[:n - 1, n - 1:] = e
    a[n - 1:, :n - 1] = -jinv @ e.T @ np.diag(ln["stiffness"])
    a[n - 1:, n - 1:] = -jinv @ (np.diag(ln["drag"]) + e.T @ np.diag(ln["damping"]) @ e)
    m = len(t["inputs"])
    b = np.zeros((2 * n - 1, m))
    for k, body in enumerate(t["inputs"]):
        b[n - 1 + body, k] = 1 / ln["inertia"][body]
    rows, variances = [], []
    for quantity, at in t["outputs"]:
        row = np.zeros(2 * n - 1)
        if quantity == "speed":
            row[n - 1 + at] = 1.0
            variances.append(ENCODER_VARIANCE)
        else:
            row[at] = ln["stiffness"][at]
            row[n - 1:] = ln["damping"][at] * e[at]
            variances.append((0.002 * t["amplitude"]) ** 2)
        rows.append(row)
    c, r = np.array(rows), np.diag(variances)
    big = expm(np.block([[a, b], [np.zeros((m, 2 * n - 1 + m))]]) * dt)
    ad, bd = big[:2 * n - 1, :2 * n - 1], big[:2 * n - 1, 2 * n - 1:]
    q = gain_scale * (0.002 * t["amplitude"]) ** 2 * bd @ bd.T + 1e-12 * np.eye(2 * n - 1)
    p = solve_discrete_are(ad.T, c.T, q, r)
    return p @ c.T @ np.linalg.inv(c @ p @ c.T + r)


def error_of(args):
    """(seed, factor, mechanics, gain scale, error)."""
    folder, seed, factor, mechanics, gain_scale = args
    t = S.truth_of(seed)
    if mechanics == "declared":
        t = dict(t, line=dict(t["line"], inertia=t["declared"]["inertia"], stiffness=t["declared"]["stiffness"]))
    line = S.Line(t)
    n = line.n
    if any(e["effect"] == "backlash" for e in t["effects"]):
        line.half = line.half * factor
    elif n > 1:
        line.half[0] = factor * t["amplitude"] * S.torque_scale(t["line"], 1) / t["line"]["stiffness"][0] / 2
    data = np.genfromtxt(os.path.join(folder, f"line_{seed:04d}.csv"), delimiter=",", names=True)
    cols = data.dtype.names
    dt, steps = float(data["time_s"][1] - data["time_s"][0]), len(data)
    line.u = np.column_stack([data[c] for c in cols if c.startswith("torque_in")])
    y = np.column_stack([data[c] for c in cols[1 + line.u.shape[1]:]])
    gain = kalman_gain(t, line, dt, gain_scale) if gain_scale > 0 else None
    twists_to_angles = np.linalg.pinv(line.e)

    def outputs(x):
        q, w = x[:n], x[n:2 * n]
        torques = line.coupling_torques(q, w) if n > 1 else []
        return np.array([w[at] if quantity == "speed" else torques[at] for quantity, at in t["outputs"]])

    x = line.start(line.u[0])
    args = line.args()  # once: the line and its recorded inputs stay as they are while it runs

    def rhs(tt, x):
        return S.line_rhs(tt, x, *args)

    predicted = np.zeros_like(y)
    h = dt / SUBSTEPS
    for k in range(steps):
        predicted[k] = outputs(x)
        if gain is not None:
            dz = gain @ (y[k] - predicted[k])
            x = x.copy()
            x[:n] += twists_to_angles @ dz[:n - 1]
            x[n:2 * n] += dz[n - 1:]
        for j in range(SUBSTEPS):
            tt = k * dt + j * h
            k1 = rhs(tt, x)
            k2 = rhs(tt + h / 2, x + h / 2 * k1)
            k3 = rhs(tt + h / 2, x + h / 2 * k2)
            k4 = rhs(tt + h, x + h * k3)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if not np.all(np.isfinite(x)):
            return seed, factor, mechanics, gain_scale, float("nan")
    fc = max(3.0 / (steps * dt), HIGH_PASS_MIN_HZ)
    measured = [high_pass(y[:, i], dt, fc) for i in range(y.shape[1])]
    weights = [1.0 / (np.sqrt(m @ m) * np.sqrt(len(measured))) for m in measured]
    error = np.sqrt(sum((w * np.linalg.norm(high_pass(predicted[:, i], dt, fc) - m)) ** 2
                        for i, (w, m) in enumerate(zip(weights, measured))))
    return seed, factor, mechanics, gain_scale, float(error)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--records", required=True)
    ap.add_argument("--seeds", required=True, help="comma-separated")
    ap.add_argument("--factors", default="0,0.5,1,2")
    ap.add_argument("--mechanics", default="declared", help="truth, declared or both comma-separated")
    ap.add_argument("--gains", default="0,1", help="process noise scales; 0 is the simulation")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    args = ap.parse_args()
    split = lambda s, f: [f(v) for v in s.split(",")]  # noqa: E731
    factors = split(args.factors, float)
    jobs = [(args.records, s, f, m, g) for s in split(args.seeds, int) for m in split(args.mechanics, str)
            for g in split(args.gains, float) for f in factors]
    with Pool(args.jobs) as pool:
        results = pool.map(error_of, jobs)
    print("| seed | truth | mechanics | cost | " + " | ".join(f"play × {f:g}" for f in factors) + " |")
    print("| --- | --- | --- | --- |" + " --- |" * len(factors))
    rows = {}
    for seed, factor, mechanics, gain, error in results:
        rows.setdefault((seed, mechanics, gain), {})[factor] = error
    for (seed, mechanics, gain), errors in rows.items():
        t = S.truth_of(seed)
        what = "+".join(e["effect"] for e in t["effects"]) or "none"
        cost = "simulation" if gain == 0 else f"predictor (Q × {gain:g})"
        best = min(errors, key=lambda f: errors[f])
        cells = [f"**{errors[f]:.3f}**" if f == best else f"{errors[f]:.3f}" for f in factors]
        print(f"| {seed} | {what}, {t['excitation']} | {mechanics} | {cost} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
