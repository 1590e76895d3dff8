"""Does rigtwin's re-fit of a declared drive line reach the least-squares minimum of its own
cost? (issue 32, item 6, for `drive_test` records)

For records of random drive lines (scripts/survey_lines.py), the declared line is simulated here
on its own — its angles and speeds stepped exactly with the torques held between samples (scipy's
matrix exponential), started as rigtwin starts a record (the line in rigid motion at the first
measured speed, the couplings wound up to carry the first torques while it accelerates as one
body), every output high-passed as rigtwin's cost is and weighted by its own spread — and scipy's
`least_squares` minimises the same cost over the same parameters: the logarithms of every inertia
and every coupling stiffness relative to the declared values, within rigtwin's bound (a factor
of 100 either way).

Three numbers per record:
- the cost of the declared line here over rigtwin's `error_before`² (1 up to the integrators'
  rounding: the same cost);
- rigtwin's re-fit (its `none` candidate) evaluated with this cost, over the lowest cost scipy
  reaches (from the declared values and from rigtwin's answer): at most 1.01 when rigtwin's fit
  reaches the minimum;
- how far apart the two fits' parameters are.

    python scripts/refit_check_lines.py --rigtwin target/release/rigtwin --seeds 0,7,14 --out /tmp/refit_lines
"""

import reproducible  # noqa: F401  (first: the records alike on every machine)
import os
import sys
import tomllib

import numpy as np
from scipy.linalg import expm
from scipy.optimize import least_squares

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import survey_lines  # noqa: E402  (the records)
from refit_check import checks_main, diagnosed, high_pass, lti_outputs  # noqa: E402  (rigtwin's zero-phase high-pass, written again)

# rigtwin's bound on a re-fitted inertia or stiffness, a factor either way (ident's MAX_REFIT_FACTOR)
MAX_FACTOR = 100.0
# the corner of the high-pass: max(3 / record length, 0.02 Hz) (ident's HIGH_PASS_MIN_HZ)
HIGH_PASS_MIN_HZ = 0.02


class Record:
    """A `drive_test` bundle of neighbour couplings with gear ratios, read as rigtwin reads it."""

    def __init__(self, bundle):
        spec = tomllib.load(open(bundle, "rb"))
        data = np.genfromtxt(os.path.join(os.path.dirname(bundle), spec["data"]), delimiter=",", names=True)
        self.dt = float(data["time_s"][1] - data["time_s"][0])
        body = {b["name"]: j for j, b in enumerate(spec["model"]["bodies"])}
        self.inertia = np.array([b["inertia"] for b in spec["model"]["bodies"]])
        self.drag = np.array([b.get("drag", 0.0) for b in spec["model"]["bodies"]])
        couplings = spec["model"]["couplings"]
        self.stiffness = np.array([c["stiffness"] for c in couplings])
        self.damping = np.array([c.get("damping", 0.0) for c in couplings])
        self.n, self.nc = self.inertia.size, len(couplings)
        # twist_i = q_i / r_i − q_(i+1)
        self.e = np.zeros((self.nc, self.n))
        for i, c in enumerate(couplings):
            self.e[i, i], self.e[i, i + 1] = 1.0 / c.get("ratio", 1.0), -1.0
        # speed of body j per speed of body 0
        self.gear = np.array([np.prod([1.0 / c.get("ratio", 1.0) for c in couplings[:j]]) for j in range(self.n)])
        self.input_body = [body[i["body"]] for i in spec["inputs"]]
        self.u = np.column_stack([data[i["column"]] for i in spec["inputs"]])
        self.outputs = [(o["quantity"], body[o["body"]] if "body" in o else o["coupling"] - 1) for o in spec["outputs"]]
        raw = [np.asarray(data[o["column"]], dtype=float) for o in spec["outputs"]]
        steps = self.u.shape[0]
        self.fc = max(3.0 / (steps * self.dt), HIGH_PASS_MIN_HZ)
        self.measured = [high_pass(y, self.dt, self.fc) for y in raw]
        self.weights = [1.0 / (np.sqrt(m @ m) * np.sqrt(len(raw))) for m in self.measured]
        # the first body's speed at the start: the first speed output's first 10 samples
        k0 = min(10, steps - 1)
        quantity, at = self.outputs[0]
        assert quantity == "speed", "the survey's first output is the first body's speed"
        self.speed0 = float(np.mean(raw[0][:k0]) / self.gear[at])

    def matrices(self, x):
        j = self.inertia * np.exp(x[: self.n])
        k = self.stiffness * np.exp(x[self.n:])
        kk = self.e.T @ np.diag(k) @ self.e
        dd = self.e.T @ np.diag(self.damping) @ self.e + np.diag(self.drag)
        return j, k, kk, dd

    def start(self, j, kk):
        """rigtwin's start: rigid motion at speed0 through the gears, the couplings twisted to
        carry the first torques while the line accelerates as one body (K q = f − M R α, q =
        K⁺(f − M R α), R the rigid-body modes: the null space of K)."""
        w = self.speed0 * self.gear
        f = -self.drag * w
        for k, b in enumerate(self.input_body):
            f[b] += self.u[0, k]
        # the coupling dampers carry nothing in rigid motion (e w = 0)
        _, s, vt = np.linalg.svd(kk)
        tol = 1e-9 * s.max()
        r = vt[s <= tol].T
        m = np.diag(j)
        g = f - m @ r @ np.linalg.solve(r.T @ m @ r, r.T @ f) if r.size else f
        q = np.linalg.pinv(kk, rcond=tol / s.max()) @ g
        return np.concatenate([q, w])

    def simulate(self, x):
        j, k, kk, dd = self.matrices(x)
        n = self.n
        a = np.zeros((2 * n, 2 * n))
        a[:n, n:] = np.eye(n)
        a[n:, :n] = -kk / j[:, None]
        a[n:, n:] = -dd / j[:, None]
        b = np.zeros((2 * n, len(self.input_body)))
        for col, body in enumerate(self.input_body):
            b[n + body, col] = 1.0 / j[body]
        c = []
        for quantity, at in self.outputs:
            row = np.zeros(2 * n)
            if quantity == "speed":
                row[n + at] = 1.0
            else:
                row[:n] = k[at] * self.e[at]
                row[n:] = self.damping[at] * self.e[at]
            c.append(row)
        big = np.zeros((2 * n + b.shape[1], 2 * n + b.shape[1]))
        big[: 2 * n, : 2 * n], big[: 2 * n, 2 * n:] = a, b
        phi = expm(big * self.dt)
        ad, bd = phi[: 2 * n, : 2 * n], phi[: 2 * n, 2 * n:]
        y = lti_outputs(ad, bd, np.array(c), self.u, self.start(j, kk))
        return [high_pass(y[:, i], self.dt, self.fc) for i in range(len(c))]

    def residual(self, x):
        sim = self.simulate(x)
        r = np.concatenate([(m - s) * w for m, s, w in zip(self.measured, sim, self.weights)])
        return r if np.all(np.isfinite(r)) else np.full(r.size, 1e10)

    def cost(self, x):
        r = self.residual(x)
        return float(r @ r)


def check(seed, rigtwin, out):
    t = survey_lines.truth_of(seed)
    bundle = survey_lines.write_bundle(out, t)
    report, none = diagnosed(rigtwin, bundle)
    rec = Record(bundle)
    params = none["parameters"]
    names = [f"inertia_b{j + 1}_kg_m2" for j in range(rec.n)] + \
        [f"stiffness_coupling{i + 1}_Nm_per_rad" for i in range(rec.nc)]
    declared = np.concatenate([rec.inertia, rec.stiffness])
    x_rig = np.log(np.array([params[k] for k in names]) / declared)
    same_cost = rec.cost(np.zeros(x_rig.size)) / report["error_before"] ** 2
    bound = np.log(MAX_FACTOR)
    fits = [least_squares(rec.residual, np.clip(x0, -bound * 0.999, bound * 0.999), bounds=(-bound, bound),
                          method="trf", x_scale=1.0, xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=400)
            for x0 in (np.zeros(x_rig.size), x_rig)]
    best = min(fits, key=lambda f: f.cost)
    ratio = rec.cost(x_rig) / (2 * best.cost)
    return dict(seed=seed, bodies=rec.n, gears=int(np.sum(t["line"]["ratio"] > 1)),
                truth="+".join(e["effect"] for e in t["effects"]) or "none", verdict=report.get("verdict"),
                same_cost=same_cost, rigtwin_cost=rec.cost(x_rig), rigtwin_error=none["error_after"],
                scipy_cost=2 * best.cost, ratio=ratio, largest_log_difference=float(np.max(np.abs(best.x - x_rig))),
                rigtwin_x=x_rig.tolist(), scipy_x=best.x.tolist())


def main():
    checks_main(
        __doc__, check, "0,7,14",
        "| seed | line | truth | verdict | declared cost here / rigtwin's | rigtwin's re-fit: its cost here "
        "| scipy's least_squares: its cost | ratio | largest difference of ln(parameter) |",
        lambda r: f"| {r['seed']} | {r['bodies']} bodies, {r['gears']} gear stages | {r['truth']} | {r['verdict']} "
                  f"| {r['same_cost']:.5f} | {r['rigtwin_cost']:.6f} | {r['scipy_cost']:.6f} | {r['ratio']:.4f} "
                  f"| {r['largest_log_difference']:.3f} |")


if __name__ == "__main__":
    main()
