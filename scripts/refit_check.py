"""Does rigtwin's re-fit of the declared model reach the least-squares minimum of its own cost?
(issue 32, item 6)

For survey records (scripts/survey.py), the declared paper rig (variant V1, no effects) is
simulated here on its own — the open differential's four states [twist, ω_M2, ω_cage, ω_M3]
stepped exactly with the torque held between samples (scipy's matrix exponential), high-passed as
rigtwin's cost is (a second-order Butterworth biquad run forward and backward, each pass started at
rest at its first value) — and scipy's `least_squares` minimises the same cost over the same two
parameters (ln of j_drive and c_short relative to the declared values, c_long keeping its ratio).

Three numbers per record:
- the cost of the declared model here over rigtwin's `error_before`² (the two costs are the same
  cost: 1 up to the integrators' rounding);
- rigtwin's re-fit (its `none` candidate) evaluated with this cost, over the lowest cost scipy
  reaches (from the declared values and from rigtwin's answer): at most 1.01 when rigtwin's fit
  reaches the minimum;
- both fits' parameters.

    python scripts/refit_check.py --rigtwin target/release/rigtwin --seeds 17,31,38 --out /tmp/refit
"""

import reproducible  # noqa: F401  (first: the records alike on every machine)
import argparse
import json
import os
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from scipy.linalg import expm
from scipy.optimize import least_squares
from scipy.signal import lfilter, lfilter_zi

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import survey  # noqa: E402  (the records and the declared model)


def high_pass(x, dt, fc):
    """rigtwin's zero-phase high-pass: the biquad forward then backward, each from rest at its
    first value."""
    k = np.tan(np.pi * fc * dt)
    q = 1 / np.sqrt(2)
    norm = 1 / (1 + k / q + k * k)
    b = np.array([norm, -2 * norm, norm])
    a = np.array([1.0, 2 * (k * k - 1) * norm, (1 - k / q + k * k) * norm])

    def one_pass(v):
        out = np.empty_like(v)
        x1 = x2 = v[0]
        y1 = y2 = 0.0
        for i, xi in enumerate(v):
            y = b[0] * xi + b[1] * x1 + b[2] * x2 - a[1] * y1 - a[2] * y2
            x2, x1, y2, y1 = x1, xi, y1, y
            out[i] = y
        return out

    # the same recursion in C: at rest at v[0] is lfilter's steady state for a constant v[0]
    # (a high-pass's output to a constant is 0)
    def fast(v):
        return lfilter(b, a, v, zi=lfilter_zi(b, a) * v[0])[0]

    # (lfilter's start differs by rounding: 1e-10 of the signal)
    assert np.allclose(fast(x[:50]), one_pass(x[:50]), rtol=1e-8, atol=1e-8 * np.max(np.abs(x[:50])))
    return fast(fast(x)[::-1])[::-1]


def lti_outputs(ad, bd, c, u, x0, block=64):
    """The outputs y_k = C x_k of x_(k+1) = A x_k + B u_k from x_0 = `x0` (scipy's `dlsim` without
    a feed-through, 20–50 times faster): the record cut into blocks of `block` samples, each
    block's state at its start carried on by A^block, inside a block the free response
    C A^j x_start and the forced one Σ_(i<j) C A^(j-1-i) B u_i as matrix products."""
    u = np.asarray(u, dtype=float).reshape(len(u), -1)
    steps, m = u.shape
    ns, p, big = ad.shape[0], c.shape[0], block
    ca = np.empty((big, p, ns))  # C A^j
    ca[0] = c
    for j in range(1, big):
        ca[j] = ca[j - 1] @ ad
    markov = np.zeros((big, p, m))  # C A^(j-1) B
    markov[1:] = ca[:-1] @ bd
    # lower-triangular block Toeplitz: toeplitz[j, :, i, :] = C A^(j-1-i) B for i < j
    toeplitz = np.zeros((big, p, big, m))
    for j in range(1, big):
        toeplitz[j, :, :j, :] = markov[j:0:-1].transpose(1, 0, 2)
    blocks = -(-steps // big)
    padded = np.zeros((blocks * big, m))
    padded[:steps] = u
    ub = padded.reshape(blocks, big * m)
    # the state at each block's start
    a_pow = np.eye(ns)
    gathered = np.empty((ns, big, m))  # A^(big-1-i) B
    for i in range(big - 1, -1, -1):
        gathered[:, i, :] = a_pow @ bd
        a_pow = a_pow @ ad
    pushed = ub @ gathered.reshape(ns, big * m).T  # Σ_i A^(big-1-i) B u_i per block
    starts = np.empty((blocks, ns))
    starts[0] = x0
    for k in range(1, blocks):
        starts[k] = a_pow @ starts[k - 1] + pushed[k - 1]
    y = starts @ ca.reshape(big * p, ns).T + ub @ toeplitz.reshape(big * p, big * m).T
    return y.reshape(blocks * big, p)[:steps]


class Record:
    def __init__(self, csv, dt, declared):
        data = np.loadtxt(csv, delimiter=",", skiprows=1)
        self.u, m2, m3 = data[:, 1], data[:, 2], data[:, 3]
        self.dt, self.d = dt, declared
        n = self.u.size
        # rigtwin's corner: max(3 / record length, 0.05 Hz)
        self.fc = max(3.0 / (n * dt), 0.05)
        self.measured = [high_pass(m2, dt, self.fc), high_pass(m3, dt, self.fc)]
        self.norm = np.sqrt(sum(np.sum(m * m) for m in self.measured))
        self.speed0 = 0.5 * (m2[0] + m3[0])

    def simulate(self, x):
        d = self.d
        jd = d["j_drive"] * np.exp(x[0])
        cl, cr = d["c_short"] * np.exp(x[1]), d["c_long"] * np.exp(x[1])
        cs = cl * cr / (cl + cr)
        ds = d["d_short"] * (cr / (cl + cr)) ** 2 + d["d_long"] * (cl / (cl + cr)) ** 2
        j2, j3, drag = d["j_m2"], d["j_m3"], d["load_drag"]
        # states [s, ω2, ωc, ω3]: s = 2φc − φ2 − φ3, shaft torque cs s + ds ṡ on each load,
        # −2× on the cage (eq. (A1))
        a = np.array([
            [0, -1, 2, -1],
            [cs / j2, (-ds - drag) / j2, 2 * ds / j2, -ds / j2],
            [-2 * cs / jd, 2 * ds / jd, -4 * ds / jd, 2 * ds / jd],
            [cs / j3, -ds / j3, 2 * ds / j3, (-ds - drag) / j3],
        ])
        bvec = np.array([0, 0, 1 / jd, 0])
        big = np.zeros((5, 5))
        big[:4, :4], big[:4, 4] = a, bvec
        e = expm(big * self.dt)
        ad, bd = e[:4, :4], e[:4, 4]
        xk = np.array([self.u[0] / 2 / cs, self.speed0, self.speed0, self.speed0])
        y = lti_outputs(ad, bd.reshape(4, 1), np.eye(4)[[1, 3]], self.u, xk)
        return high_pass(y[:, 0], self.dt, self.fc), high_pass(y[:, 1], self.dt, self.fc)

    def residual(self, x):
        w2, w3 = self.simulate(x)
        return np.concatenate([self.measured[0] - w2, self.measured[1] - w3]) / self.norm

    def cost(self, x):
        r = self.residual(x)
        return float(r @ r)


def diagnosed(rigtwin, bundle):
    """rigtwin's report of `bundle` (beside it, `.json`) and its `none` candidate: the declared
    model re-fitted."""
    report_path = bundle.replace(".toml", ".json")
    p = subprocess.run([rigtwin, "diagnose", bundle, "--json", report_path], capture_output=True, text=True)
    if p.returncode not in (0, 3):
        raise RuntimeError(f"{bundle}: rigtwin failed: {p.stderr}")
    report = json.load(open(report_path))
    return report, next(c for c in report["candidates"] if c["effect"] == "none")


def check(seed, rigtwin, out):
    t = survey.truth_of(seed)
    bundle = survey.write_bundle(out, t)
    report, none = diagnosed(rigtwin, bundle)
    declared = survey.DECLARED
    x_rig = [np.log(none["parameters"]["j_drive_kgm2"] / declared["j_drive"]),
             np.log(none["parameters"]["c_short_Nm_per_rad"] / declared["c_short"])]
    rec = Record(bundle.replace(".toml", ".csv"), survey.DT, declared)
    same_cost = rec.cost([0.0, 0.0]) / report["error_before"] ** 2
    fits = [least_squares(rec.residual, x0, method="lm", xtol=1e-12, ftol=1e-12, gtol=1e-12)
            for x0 in ([0.0, 0.0], x_rig)]
    best = min(fits, key=lambda f: 2 * f.cost)
    ratio = rec.cost(x_rig) / (2 * best.cost)
    return dict(seed=seed, effect=t["effect"], same_cost=same_cost, rigtwin_cost=rec.cost(x_rig),
                rigtwin_error=none["error_after"], scipy_cost=2 * best.cost, ratio=ratio,
                rigtwin_j_drive=float(declared["j_drive"] * np.exp(x_rig[0])),
                rigtwin_c_short=float(declared["c_short"] * np.exp(x_rig[1])),
                scipy_j_drive=float(declared["j_drive"] * np.exp(best.x[0])),
                scipy_c_short=float(declared["c_short"] * np.exp(best.x[1])))


def checks_main(doc, check, default_seeds, header, row):
    """Runs `check(seed, rigtwin, out)` on the seeds of the command line, each record in its own
    process, and prints the rows (`header`, then `row(r)` each) as markdown."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--rigtwin", required=True)
    ap.add_argument("--seeds", default=default_seeds)
    ap.add_argument("--out", required=True)
    ap.add_argument("--json", help="write the rows here")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="records checked at once")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    seeds = survey.parse_seeds(args.seeds)
    # the records are independent: each is written, diagnosed and re-fitted in its own process
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        rows = list(pool.map(check, seeds, [args.rigtwin] * len(seeds), [args.out] * len(seeds)))
    print(header)
    print("|" + " --- |" * header.count(" | ") + " --- |")
    for r in rows:
        print(row(r))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)


def main():
    checks_main(
        __doc__, check, "17,31,38",
        "| seed | truth | declared cost here / rigtwin's | rigtwin's re-fit: j_drive, c_short | its cost here "
        "| scipy's least_squares: j_drive, c_short | its cost | ratio |",
        lambda r: f"| {r['seed']} | {r['effect']} | {r['same_cost']:.5f} | {r['rigtwin_j_drive']:.4f} kg·m², "
                  f"{r['rigtwin_c_short']:.1f} N·m/rad | {r['rigtwin_cost']:.6f} | {r['scipy_j_drive']:.4f} kg·m², "
                  f"{r['scipy_c_short']:.1f} N·m/rad | {r['scipy_cost']:.6f} | {r['ratio']:.4f} |")


if __name__ == "__main__":
    main()
