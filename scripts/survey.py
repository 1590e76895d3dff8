"""A survey of `rigtwin diagnose` on records made by a simulator that shares no code with
rigtwin: the paper's rig (variant V1, the declared model of ../shared/DATA.md) integrated by
scipy's adaptive LSODA, with the effects modelled its own way — play as a dead zone whose damper
acts only in contact, Coulomb friction with a Stribeck rise to a static friction 1.3 times the
sliding one, a dead time read off the held torque, a first-order lag, a compliance splitting the
drive's inertia, shaft damping the declared model lacks — and the measurement as a rig's is:
white and coloured noise, an offset drifting over the record, encoder quantisation. Excitations:
a sweep, a multisine, steps and a PRBS about a set point near or far from zero.

    python scripts/survey.py --rigtwin target/release/rigtwin --seeds 0-39 --out /tmp/survey

writes one `torsional_sweep` bundle per seed, diagnoses it, and prints the verdict matrix, the
parameter errors and run times as the markdown of docs/validation.md. Seeds 0-999 are the
survey's tuning part; seeds from 1000 on are held out (run once after a change, never tuned on).
"""

import reproducible  # noqa: F401  (first: the records alike on every machine)
import argparse
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from numba import njit
from scipy.integrate import odeint
from scipy.signal import lfilter

# the declared model (DATA.md), SI
DECLARED = dict(j_m2=0.9148, j_drive=0.529, j_m3=0.9148, c_short=1479.0, c_long=1150.33,
                c_delta=64330.0, d_short=1.12, d_long=0.87, load_drag=0.5)
DT = 1e-3
DURATION_S = 20.0
EFFECTS = ["none", "time_delay", "actuator_lag", "backlash", "drive_compliance", "coulomb_friction",
           "shaft_damping"]
# the parameter each effect's answer is scored on (rigtwin's report key) and its truth's name
SCORED = {"time_delay": "delay_s", "actuator_lag": "time_constant_s", "backlash": "backlash_rad",
          "drive_compliance": "stiffness_Nm_per_rad", "coulomb_friction": "friction_Nm",
          "shaft_damping": "damping_ratio"}


def truth_of(seed):
    """The record's truth: effect, its parameters, excitation, set point (all from the seed)."""
    rng = np.random.default_rng(seed)
    effect = EFFECTS[seed % len(EFFECTS)]
    t = dict(effect=effect, seed=seed)
    # magnitudes from near the noise to large, log-uniform
    if effect == "time_delay":
        t["delay_s"] = float(np.exp(rng.uniform(np.log(0.001), np.log(0.015))))
    elif effect == "actuator_lag":
        t["lag_s"] = float(np.exp(rng.uniform(np.log(0.002), np.log(0.02))))
    elif effect == "backlash":
        t["backlash_rad"] = float(np.exp(rng.uniform(np.log(0.0005), np.log(0.01))))
    elif effect == "drive_compliance":
        # the motor-cage mode between 1.5 and 4 times the shuffle (about 7 Hz), inside a 30 Hz band
        t["motor_fraction"] = float(rng.uniform(0.3, 0.7))
        f = t["motor_fraction"]
        mode_hz = 7.0 * rng.uniform(1.5, 3.5)
        t["stiffness"] = float((2 * np.pi * mode_hz) ** 2 * DECLARED["j_drive"] * f * (1 - f))
    elif effect == "coulomb_friction":
        t["friction_at"] = str(rng.choice(["M2", "M3"]))
        t["friction_nm"] = float(np.exp(rng.uniform(np.log(0.2), np.log(2.0))))
    elif effect == "shaft_damping":
        t["damping_ratio"] = float(rng.uniform(0.02, 0.08))
    t["excitation"] = str(rng.choice(["sweep", "multisine", "steps", "prbs"]))
    # friction and play show only where speeds reverse or shaft torques cross zero: about zero
    # torque for them, anywhere for the others
    if effect in ("coulomb_friction", "backlash"):
        t["set_point_nm"] = float(rng.choice([0.0, 0.0, 2.0]))
    else:
        t["set_point_nm"] = float(rng.choice([0.0, 5.0, 20.0, 40.0]))
    t["noise_seed"] = int(rng.integers(1 << 31))
    return t


def excitation(kind, set_point, rng, n):
    """The drive torque, Nm, held over each sample as a rig's converter holds it."""
    tt = np.arange(n) * DT
    if kind == "sweep":
        u = 8.0 * np.sin(2 * np.pi * (1.0 * tt + 0.5 * 29.0 / DURATION_S * tt ** 2))
    elif kind == "multisine":
        f = np.linspace(1.0, 30.0, 30)
        ph = rng.uniform(0, 2 * np.pi, f.size)
        u = sum(np.sin(2 * np.pi * fi * tt + p) for fi, p in zip(f, ph))
        u *= 8.0 / np.max(np.abs(u))
    elif kind == "steps":
        levels = rng.uniform(-8.0, 8.0, int(DURATION_S / 0.5))
        u = np.repeat(levels, int(0.5 / DT))[:n]
    else:  # PRBS: a new ±8 Nm level every 20 ms with probability 1/2
        flips = rng.random(int(DURATION_S / 0.02)) < 0.5
        level = np.cumprod(np.where(flips, -1.0, 1.0)) * 8.0
        u = np.repeat(level, int(0.02 / DT))[:n]
    return set_point + u


def simulate(t, u):
    """Speeds of M2 and M3 sampled at DT (LSODA, adaptive steps within each held sample)."""
    d = DECLARED
    cl, cr = d["c_short"], d["c_long"]
    cs = cl * cr / (cl + cr)
    dl, dr = d["d_short"], d["d_long"]
    if t["effect"] == "shaft_damping":
        # the truth's shafts damped at ratio ζ of the shuffle (the declared model has none)
        w = np.sqrt(cs * (1 / d["j_m2"] + 4 / d["j_drive"] + 1 / d["j_m3"]))
        dl = 2 * t["damping_ratio"] * cl / w
        dr = dl * cr / cl
    ds = dl * (cr / (cl + cr)) ** 2 + dr * (cl / (cl + cr)) ** 2
    b = t.get("backlash_rad", 0.0)
    k = t.get("stiffness", 0.0)
    fr = t.get("motor_fraction", 0.5)
    tc = t.get("friction_nm", 0.0)
    p = np.array([cs, ds, b, t.get("delay_s", 0.0), t.get("lag_s", 0.0), k,
                  (1 - fr) * d["j_drive"] if k > 0 else d["j_drive"], fr * d["j_drive"],
                  tc if t.get("friction_at") == "M2" else 0.0, tc if t.get("friction_at") == "M3" else 0.0,
                  d["load_drag"], d["j_m2"], d["j_m3"]])
    # start at the set point's steady state: the speeds T0/(2 drag), the shafts twisted to carry it
    t0 = u[0]
    w0 = t0 / (2 * d["load_drag"])
    shaft0 = t0 / 2
    s0 = shaft0 / cs + b * np.sign(shaft0)
    x0 = [0.0, s0 / 2, 0.0, s0 / 2 + (t0 / k if k > 0 else 0.0), w0, w0, w0, w0, t0]
    y = lsoda(rig_rhs, x0, np.arange(u.size) * DT, (p, np.ascontiguousarray(u, dtype=float)), t["seed"])
    return y[:, 4], y[:, 6]


def lsoda(rhs, x0, times, args, seed, atol=1e-9):
    """The states at `times` (samples x states): scipy's LSODA (ODEPACK, through `odeint`) on the
    compiled right-hand side `rhs(time, x, *args)`, steps of at most half a sample (the inputs
    are held over a sample) and none beyond the last time (a closed loop has not yet chosen the
    next input), relative tolerance 1e-7, absolute `atol`."""
    y, info = odeint(rhs, np.asarray(x0, dtype=float), times, args=args, tfirst=True, rtol=1e-7, atol=atol,
                     hmax=DT / 2, tcrit=times[-1:], mxstep=10 ** 7, full_output=True)
    if info["message"] != "Integration successful.":
        raise RuntimeError(f"seed {seed}: {info['message']}")
    return y


@njit(cache=True)
def rig_rhs(time, x, p, u):
    """The rig's right-hand side, states [q2, q_cage, q3, q_motor, w2, w_cage, w3, w_motor, z]
    (z the lagged drive torque); p as `simulate` packs it, u the commanded torque per sample."""
    cs, ds, b, delay, lag, k, j_cage, j_motor = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    fric_m2, fric_m3, load_drag, j_m2, j_m3 = p[8], p[9], p[10], p[11], p[12]
    q2, qc, q3, qm, w2, wc, w3, wm, z = x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8]
    s = 2 * qc - q2 - q3
    sd = 2 * wc - w2 - w3
    if s > b:
        shaft = cs * (s - b) + ds * sd
    elif s < -b:
        shaft = cs * (s + b) + ds * sd
    else:
        shaft = 0.0  # inside the play: no spring, no damper
    held = u[held_sample(time, delay, DT, u.size)]
    drive = z if lag > 0 else held
    dz = (held - z) / lag if lag > 0 else 0.0
    a2 = (shaft - load_drag * w2 - stribeck(fric_m2, w2)) / j_m2
    a3 = (shaft - load_drag * w3 - stribeck(fric_m3, w3)) / j_m3
    if k > 0:
        inner = k * (qm - qc) + ds / cs * k * (wm - wc)
        ac = (-2 * shaft + inner) / j_cage
        am = (drive - inner) / j_motor
    else:
        ac = (-2 * shaft + drive) / j_cage
        am = 0.0
    return np.array([w2, wc, w3, wm, a2, ac, a3, am, dz])


@njit(cache=True)
def held_sample(time, delay, dt, samples):
    """The sample (of `samples`, `dt` apart) of a held input that acts at `time`: the one
    commanded `delay` before, held over its sample (the first before the record, the last after
    it)."""
    i = int(np.floor((time - delay) / dt + 1e-9))
    return min(max(i, 0), samples - 1)


@njit(cache=True)
def stribeck(tc, w):
    """Coulomb friction tc at speed w with a Stribeck rise: 1.3 tc near rest falling to tc above
    0.05 rad/s, its sign smoothed over 5 mrad/s."""
    if tc == 0.0:
        return 0.0
    return np.tanh(w / 0.005) * tc * (1.0 + 0.3 * np.exp(-(w / 0.05) ** 2))


def measured(w, rng):
    """A speed as an encoder gives it: white (2 mrad/s) and coloured noise (AR(1), ρ = 0.95,
    2 mrad/s), an offset drifting by up to 20 mrad/s over the record, 1 mrad/s quantisation."""
    n = w.size
    white = rng.normal(0, 0.002, n)
    coloured = lfilter([np.sqrt(1 - 0.95 ** 2)], [1, -0.95], rng.normal(0, 0.002, n))
    drift = rng.uniform(-0.02, 0.02) * np.arange(n) / n
    return np.round((w + white + coloured + drift) / 1e-3) * 1e-3


def write_bundle(folder, t):
    rng = np.random.default_rng(t["noise_seed"])
    n = int(DURATION_S / DT)
    u = excitation(t["excitation"], t["set_point_nm"], rng, n)
    w2, w3 = simulate(t, u)
    torque_meas = u + rng.normal(0, 0.01, n)
    name = f"seed_{t['seed']:04d}"
    csv = os.path.join(folder, name + ".csv")
    data = np.column_stack([np.arange(n) * DT, torque_meas, measured(w2, rng), measured(w3, rng)])
    np.savetxt(csv, data, delimiter=",", header="time_s,torque_drive_Nm,speed_m2_radps,speed_m3_radps",
               comments="", fmt="%.9g")
    model = dict(DECLARED)
    if t["effect"] == "shaft_damping":
        model["d_short"] = 0.0
        model["d_long"] = 0.0
    lines = [f'kind = "torsional_sweep"', f'data = "{name}.csv"', 'variant = "V1"', "", "[model]"]
    lines += [f"{k_} = {v}" for k_, v in model.items()]
    bundle = os.path.join(folder, name + ".toml")
    with open(bundle, "w") as f:
        f.write("\n".join(lines) + "\n")
    return bundle


def score(t, report):
    """'right', 'not explained' (an honest miss) or 'wrong'; where right, the scored parameter's
    relative error and whether its 95 % interval (the report's `intervals`) holds the truth."""
    verdict = report.get("verdict")
    found = [e["effect"] for e in report.get("effects", [])]
    if t["effect"] == "none":
        if verdict == "declared_model_fits":
            return "right", None, None
        return ("not explained" if verdict == "not_explained" else "wrong"), None, None
    if verdict == "not_explained":
        return "not explained", None, None
    if verdict != "explained" or found != [t["effect"]]:
        return "wrong", None, None
    e = report["effects"][0]
    if t["effect"] == "coulomb_friction" and e.get("at") != t["friction_at"]:
        return "wrong", None, None
    key = SCORED[t["effect"]]
    truth = {"time_delay": t.get("delay_s"), "actuator_lag": t.get("lag_s"), "backlash": t.get("backlash_rad"),
             "drive_compliance": t.get("stiffness"), "coulomb_friction": t.get("friction_nm"),
             "shaft_damping": t.get("damping_ratio")}[t["effect"]]
    value = e["parameters"].get(key)
    if value is None:
        return "wrong", None, None
    interval = e.get("intervals", {}).get(key)
    covered = None if interval is None or None in interval else bool(interval[0] <= truth <= interval[1])
    return "right", abs(value - truth) / truth, covered


def diagnose(rigtwin, bundle, out, flags=()):
    """`rigtwin diagnose` of `bundle` (with `flags`), its JSON written to `out`: (the report, or
    None where rigtwin failed; seconds; what failed)."""
    start = time.time()
    p = subprocess.run([rigtwin, "diagnose", bundle, "--json", out, *flags], capture_output=True, text=True)
    elapsed = time.time() - start
    if p.returncode not in (0, 3) or not os.path.exists(out):
        return None, elapsed, f"rigtwin failed ({p.returncode}): {p.stderr.strip()[:300]}"
    with open(out) as f:
        return json.load(f), elapsed, None


def diagnose_all(rigtwin, seeds, truths, bundles, score, describe, flags=()):
    """Diagnoses each bundle (its JSON beside it; `rigtwin diagnose` with `flags`), scores the
    report against its truth with `score`, and tells each on standard error (`describe(truth,
    report)`: what it held and what rigtwin said). The rows (truth, outcome, parameter error, seconds, interval holds, whether the
    report gives an interval beside folds whose fit did not move — which it must not)."""
    rows = []
    for seed, t, bundle in zip(seeds, truths, bundles):
        report, elapsed, failure = diagnose(rigtwin, bundle, os.path.splitext(bundle)[0] + ".json", flags)
        if report is None:
            rows.append((t, "error", None, elapsed, None, False))
            print(f"seed {seed}: {failure}", file=sys.stderr)
            continue
        outcome, err, covered = score(t, report)
        rows.append((t, outcome, err, elapsed, covered, unmeasured_intervals(report)))
        print(f"seed {seed:4d} {describe(t, report)} {outcome}"
              + (f" ({100 * err:.0f} %{', interval misses' if covered is False else ''})" if err is not None else "")
              + f" {elapsed:.1f} s", file=sys.stderr)
    return rows


def describe(t, report):
    """A record's truth and rigtwin's answer, for the log."""
    found = "+".join(e["effect"] + (f"@{e['at']}" if e.get("at") else "") for e in report.get("effects", []))
    return (f"{t['effect']:17s} {t['excitation']:9s} {t['set_point_nm']:4.0f} Nm -> "
            f"{report.get('verdict'):20s} {found or 'none':30s}")


def parse_seeds(text):
    seeds = []
    for part in text.split(","):
        a, _, b = part.partition("-")
        seeds += list(range(int(a), int(b or a) + 1))
    return seeds


def arguments(doc):
    """The survey scripts' command line."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--rigtwin", required=True)
    ap.add_argument("--seeds", default="0-34")
    ap.add_argument("--out", required=True)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="processes simulating the records")
    ap.add_argument("--summary", help="write the counts (right, not explained, wrong, records) as JSON here")
    ap.add_argument("--reuse", action="store_true", help="diagnose the records already in --out (written by an "
                    "earlier run with the same seeds) instead of simulating them again")
    return ap


def bundles_of(args, truths, write_bundle, name):
    """The bundles of `truths` in `args.out`: those an earlier run wrote there (`--reuse`; `name`
    the file name of a seed's), else written now on `args.jobs` processes."""
    if args.reuse:
        return [os.path.join(args.out, name(t["seed"])) for t in truths]
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        return list(pool.map(write_bundle, [args.out] * len(truths), truths))


def unmeasured_intervals(report):
    """Whether `report` gives an interval although a fold's fit did not move
    (`held_out.unmoved_folds`): such folds add no spread, so rigtwin gives none."""
    if not (report.get("held_out") or {}).get("unmoved_folds"):
        return False
    return bool(report.get("intervals")) or any(e.get("intervals") for e in report.get("effects", []))


def write_summary(path, rows):
    """The counts of `rows` (see `diagnose_all`) as JSON."""
    with open(path, "w") as f:
        json.dump({"records": len(rows),
                   "right": sum(1 for r in rows if r[1] == "right"),
                   "not_explained": sum(1 for r in rows if r[1] == "not explained"),
                   "wrong": sum(1 for r in rows if r[1] in ("wrong", "error")),
                   "right_beyond_20_percent": sum(1 for r in rows if r[2] is not None and r[2] > 0.2),
                   "intervals": sum(1 for r in rows if r[4] is not None),
                   "intervals_covering": sum(1 for r in rows if r[4]),
                   "intervals_beside_unmoved_folds": sum(1 for r in rows if r[5])}, f)


def main():
    args = arguments(__doc__).parse_args()
    os.makedirs(args.out, exist_ok=True)
    seeds = parse_seeds(args.seeds)
    truths = [truth_of(seed) for seed in seeds]
    # the records are simulated on every core (the simulations are independent and
    # single-threaded); the diagnoses then run one at a time (each uses two threads)
    bundles = bundles_of(args, truths, write_bundle, lambda seed: f"seed_{seed:04d}.toml")
    rows = diagnose_all(args.rigtwin, seeds, truths, bundles, score, describe)
    print(table(rows, [(e, lambda t, e=e: t["effect"] == e) for e in EFFECTS]))
    if args.summary:
        write_summary(args.summary, rows)


def table(rows, groups):
    """The verdict matrix of `rows` as markdown: a line per (name, membership test of a truth)
    of `groups` that has records, then all."""
    lines = ["| truth | records | right | not explained | wrong | parameter error of the right: median / max (beyond 20 %) "
             "| 95 % interval holds the truth | run time, median |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    cover = lambda r: (f"{sum(1 for row in r if row[4])} of {sum(1 for row in r if row[4] is not None)}"
                       if any(row[4] is not None for row in r) else "–")
    for name, member in groups:
        r = [row for row in rows if member(row[0])]
        if not r:
            continue
        count = lambda o: sum(1 for row in r if row[1] == o)
        errs = [row[2] for row in r if row[2] is not None]
        beyond = sum(1 for e in errs if e > 0.2)
        err = f"{100 * np.median(errs):.1f} % / {100 * max(errs):.0f} % ({beyond})" if errs else "–"
        lines.append(f"| {name} | {len(r)} | {count('right')} | {count('not explained')} | "
                     f"{count('wrong') + count('error')} | {err} | {cover(r)} | {np.median([row[3] for row in r]):.1f} s |")
    total = len(rows)
    lines.append(f"| all | {total} | {sum(1 for r in rows if r[1] == 'right')} | "
                 f"{sum(1 for r in rows if r[1] == 'not explained')} | "
                 f"{sum(1 for r in rows if r[1] in ('wrong', 'error'))} | | {cover(rows)} | |")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
