"""A survey of `rigtwin diagnose` on `drive_test` records of random drive lines, made by a
simulator that shares no code with rigtwin: lines of 2-8 bodies with 0-2 gear stages, coupled
by spring-dampers, driven by one or two torques, integrated by scipy's adaptive LSODA; the
effects modelled their own way (play as a dead zone whose damper acts only in contact, Coulomb
friction with a Stribeck rise to a static friction 1.3 times the sliding one, a dead time read
off the held torque, a first-order lag; with `--only compliance`, a compliance inside a body: the
body split into two inertias joined by a spring-damper of its own, damped at 1-5 % of that
mode's critical damping), single and in pairs, at random places; the measurement
as a rig's (survey.py's encoder noise, drift and quantisation; noise on torques); the declared
model a few per cent off the truth, as a drawing's values are. Excitations: a sweep, a
multisine, steps, a PRBS and a closed loop (a PI speed controller on the first body's measured
speed), about a set point near or far from zero.

    python scripts/survey_lines.py --rigtwin target/release/rigtwin --seeds 0-34 --out /tmp/lines

writes one `drive_test` bundle per seed, diagnoses it, and prints the verdict matrix, the
parameter errors and run times as the markdown of docs/validation.md. `--only KIND` gives every
record one effect of that kind (`compliance` is drawn only so: the plan of the other records
stays as it was); `--search-compliance` diagnoses with `rigtwin diagnose --search-compliance`.
An effect of the truth
that cannot act on its record (a friction whose body never turns slower than 0.25 rad/s, a play
whose coupling never leaves contact: `not_acting`, judged on the true states and kept beside the
bundle as `.truth.json`) is scored as absent and marked "(cannot act)" in the log. Seeds 0-999 are the
survey's tuning part; seeds from 1000 on are held out (run once after a change, never tuned on),
for each `--only` kind on its own.
"""

import reproducible  # noqa: F401  (first: the records alike on every machine)
import json
import os

import numpy as np
from numba import njit

from survey import (arguments, bundles_of, diagnose_all, held_sample, lsoda, measured, parse_seeds, stribeck, table,
                    write_summary)

DT = 1e-3
DURATION_S = 10.0
# what each seed's record holds, in turn: nothing, each effect alone, and pairs
PLAN = ["none", "time_delay", "actuator_lag", "backlash", "coulomb_friction", "pair", "pair"]
KINDS = ["time_delay", "actuator_lag", "backlash", "coulomb_friction"]
# the kinds `--only` may ask for: those of the plan, and the compliance, drawn only so
ONLY_KINDS = KINDS + ["compliance"]
# the parameter each effect is scored on (rigtwin's report key)
SCORED = {"time_delay": "delay_s", "actuator_lag": "time_constant_s", "backlash": "backlash_rad",
          "coulomb_friction": "friction_Nm", "compliance": "compliance_stiffness_Nm_per_rad"}
EXCITATIONS = ["sweep", "multisine", "steps", "prbs", "closed_loop"]
# the lowest and highest natural frequency a line may have, Hz: within what a 1 kHz record with
# a 1-30 Hz excitation band shows
MODES_HZ = (3.0, 150.0)
# the quiet start of every record, s
LEAD_IN_S = 0.2


def line_of(rng):
    """A random line: inertias, couplings (stiffness, damping, ratio), drags; its modes within
    MODES_HZ (drawn again until they are)."""
    while True:
        n = int(rng.integers(2, 9))
        inertia = np.exp(rng.uniform(np.log(2e-4), np.log(5e-2), n))
        ratio = np.ones(n - 1)
        stages = min(int(rng.integers(0, 3)), n - 1)
        for i in rng.choice(n - 1, stages, replace=False):
            ratio[i] = float(rng.choice([2.0, 3.0, 4.0, 5.0]))
        stiffness, damping = np.zeros(n - 1), np.zeros(n - 1)
        for i in range(n - 1):
            # the coupling's own two-mass mode 8-80 Hz, damped at 1-5 % of critical
            j_red = inertia[i] * ratio[i] ** 2 * inertia[i + 1] / (inertia[i] * ratio[i] ** 2 + inertia[i + 1])
            f = np.exp(rng.uniform(np.log(8.0), np.log(80.0)))
            stiffness[i] = (2 * np.pi * f) ** 2 * j_red
            damping[i] = 2 * rng.uniform(0.01, 0.05) * np.sqrt(stiffness[i] * j_red)
        drag = np.zeros(n)
        tau = rng.uniform(0.5, 3.0)
        drag[0] = inertia[0] / tau
        drag[-1] = inertia[-1] / tau
        line = dict(inertia=inertia, ratio=ratio, stiffness=stiffness, damping=damping, drag=drag)
        hz = modes_hz(line)
        if n == 1 or (hz.min() >= MODES_HZ[0] and hz.max() <= MODES_HZ[1]):
            return line


def elongations(line):
    """E: twist_i = E[i] . q (q_i / r_i - q_(i+1))."""
    n = len(line["inertia"])
    e = np.zeros((n - 1, n))
    for i in range(n - 1):
        e[i, i] = 1.0 / line["ratio"][i]
        e[i, i + 1] = -1.0
    return e


def modes_hz(line):
    """The undamped natural frequencies other than the rigid-body mode, Hz."""
    e = elongations(line)
    k = e.T @ np.diag(line["stiffness"]) @ e
    m = np.diag(line["inertia"])
    w2 = np.sort(np.real(np.linalg.eigvals(np.linalg.solve(m, k))))
    return np.sqrt(np.maximum(w2[1:], 0.0)) / (2 * np.pi)


def torque_scale(line, j):
    """How much a torque at body 0 is amplified by the gear stages before body j."""
    return float(np.prod(line["ratio"][:j]))


def truth_of(seed, only=None):
    """The record's truth: the line, the effects (kind, place, size), the declared model, the
    excitation and set point (all from the seed); `only`: one effect of that kind."""
    rng = np.random.default_rng(seed)
    line = line_of(rng)
    n = len(line["inertia"])
    inputs = [0] + ([n - 1] if n > 1 and rng.random() < 0.4 else [])
    # torque amplitude: the first body's speed about 5 rad/s at 1 Hz (the whole line reflected
    # to it)
    j_total = sum(line["inertia"][j] / torque_scale(line, j) ** 2 for j in range(n))
    amplitude = float(5.0 * 2 * np.pi * j_total)
    plan = only or PLAN[seed % len(PLAN)]
    kinds = [plan] if plan != "pair" else list(rng.choice(KINDS, 2, replace=False))
    effects = []
    for kind in ([] if plan == "none" else kinds):
        e = dict(effect=kind)
        if kind == "time_delay":
            e["input"] = int(rng.integers(len(inputs)))
            e["size"] = float(np.exp(rng.uniform(np.log(0.001), np.log(0.015))))
        elif kind == "actuator_lag":
            e["input"] = int(rng.integers(len(inputs)))
            e["size"] = float(np.exp(rng.uniform(np.log(0.002), np.log(0.02))))
        elif kind == "backlash":
            if n < 2:
                continue
            i = int(rng.integers(n - 1))
            e["coupling"] = i
            # total play 0.2-5 times the coupling's elastic twist under the excitation's torque
            twist = amplitude * torque_scale(line, i + 1) / line["stiffness"][i]
            e["size"] = float(twist * np.exp(rng.uniform(np.log(0.2), np.log(5.0))))
        elif kind == "coulomb_friction":
            j = int(rng.integers(n))
            e["body"] = j
            # 2-30 % of the excitation's torque as it reaches the body
            e["size"] = float(amplitude * torque_scale(line, j) * np.exp(rng.uniform(np.log(0.02), np.log(0.3))))
        elif kind == "compliance":
            j = int(rng.integers(n))
            e["body"] = j
            # the body split: a share 0.3-0.7 of its inertia on the driven side, the two parts'
            # own mode 8-60 Hz, damped at 1-5 % of its critical damping
            share = float(rng.uniform(0.3, 0.7))
            j_red = share * (1 - share) * line["inertia"][j]
            f = np.exp(rng.uniform(np.log(8.0), np.log(60.0)))
            e["share"] = share
            e["size"] = float((2 * np.pi * f) ** 2 * j_red)
            e["damping"] = float(2 * rng.uniform(0.01, 0.05) * np.sqrt(e["size"] * j_red))
        effects.append(e)
    near_zero = any(e["effect"] in ("backlash", "coulomb_friction") for e in effects)
    set_point = float(rng.choice([0.0, 0.0, 0.1]) if near_zero else rng.choice([0.0, 0.5, 2.0])) * amplitude
    outputs = [("speed", 0)] + ([("speed", n - 1)] if n > 1 else [])
    if n > 2 and rng.random() < 0.5:
        outputs.append(("speed", int(rng.integers(1, n - 1))))
    if n > 1 and rng.random() < 0.5:
        outputs.append(("coupling_torque", int(rng.integers(n - 1))))
    # the declared model: the truth's inertias and stiffnesses each a few per cent off
    declared = dict(inertia=line["inertia"] * np.exp(rng.normal(0, 0.03, n)),
                    stiffness=line["stiffness"] * np.exp(rng.normal(0, 0.03, n - 1)))
    return dict(seed=seed, plan=plan, line=line, inputs=inputs, effects=effects, amplitude=amplitude,
                set_point_nm=set_point, outputs=outputs, declared=declared,
                excitation=str(rng.choice(EXCITATIONS)), noise_seed=int(rng.integers(1 << 31)))


def open_loop(kind, rng, n):
    """An excitation of unit amplitude, held over each sample, after a quiet lead-in (the line
    at its set point's steady state, where a record of a rig starts)."""
    u = excitation_of(kind, rng, n)
    u[: int(LEAD_IN_S / DT)] = 0.0
    return u


def excitation_of(kind, rng, n):
    tt = np.arange(n) * DT
    if kind == "sweep":
        return np.sin(2 * np.pi * (1.0 * tt + 0.5 * 29.0 / DURATION_S * tt ** 2))
    if kind == "multisine":
        f = np.linspace(1.0, 30.0, 30)
        u = sum(np.sin(2 * np.pi * fi * tt + p) for fi, p in zip(f, rng.uniform(0, 2 * np.pi, f.size)))
        return u / np.max(np.abs(u))
    if kind == "steps":
        return np.repeat(rng.uniform(-1.0, 1.0, int(DURATION_S / 0.5)), int(0.5 / DT))[:n]
    # PRBS (and the closed loop's reference): a new ±1 level every 20 ms with probability 1/2
    flips = rng.random(int(DURATION_S / 0.02)) < 0.5
    return np.repeat(np.cumprod(np.where(flips, -1.0, 1.0)), int(0.02 / DT))[:n]


class Line:
    """The truth's right-hand side: states q (n), w (n), one lagged torque per input."""

    def __init__(self, t):
        self.t = t
        ln = t["line"]
        self.n = len(ln["inertia"])
        self.e = elongations(ln)
        self.inertia = np.asarray(ln["inertia"], dtype=float).copy()
        self.stiffness = np.asarray(ln["stiffness"], dtype=float).copy()
        self.damping = np.asarray(ln["damping"], dtype=float).copy()
        self.drag = np.asarray(ln["drag"], dtype=float).copy()
        self.inputs = np.asarray(t["inputs"], dtype=np.int64).copy()
        self.half = np.zeros(self.n - 1)
        self.friction = np.zeros(self.n)
        self.split = None  # a compliance: (body, spring stiffness)
        for e in t["effects"]:
            if e["effect"] == "compliance":
                self.split_body(e)
        self.delay = np.zeros(len(t["inputs"]))
        self.lag = np.zeros(len(t["inputs"]))
        for e in t["effects"]:
            if e["effect"] == "backlash":
                self.half[e["coupling"]] = e["size"] / 2
            elif e["effect"] == "coulomb_friction":
                self.friction[e["body"]] = e["size"]
            elif e["effect"] == "time_delay":
                self.delay[e["input"]] = e["size"]
            elif e["effect"] == "actuator_lag":
                self.lag[e["input"]] = e["size"]
        self.u = None  # commanded torques, samples x inputs, filled as the record runs

    def split_body(self, e):
        """Body e["body"] split by a compliance: the share e["share"] of its inertia becomes a new
        last body, which the body's inputs drive, joined to the rest (which keeps the couplings
        and the drag) by a spring e["size"] with damper e["damping"] on its twist q_new - q_body."""
        b, n = e["body"], self.n
        j = self.inertia[b]
        self.inertia[b] = (1 - e["share"]) * j
        self.inertia = np.append(self.inertia, e["share"] * j)
        self.drag = np.append(self.drag, 0.0)
        self.friction = np.append(self.friction, 0.0)
        row = np.zeros(n + 1)
        row[b], row[n] = -1.0, 1.0
        self.e = np.vstack([np.hstack([self.e, np.zeros((self.e.shape[0], 1))]), row])
        self.stiffness = np.append(self.stiffness, e["size"])
        self.damping = np.append(self.damping, e["damping"])
        self.half = np.append(self.half, 0.0)
        self.inputs[self.inputs == b] = n
        self.split = (b, e["size"])
        self.n = n + 1

    def args(self):
        """`line_rhs`'s arguments after the time and the state."""
        return (self.e, self.half, self.stiffness, self.damping, self.drag, self.inertia, self.friction, self.inputs,
                self.delay, self.lag, np.ascontiguousarray(self.u, dtype=float))

    def coupling_torques(self, q, w):
        return coupling_torques(self.e, self.half, self.stiffness, self.damping, np.asarray(q, dtype=float),
                                np.asarray(w, dtype=float))

    def rhs(self, time, x):
        return line_rhs(time, np.asarray(x, dtype=float), *self.args())

    def start(self, torques):
        """Rest or steady rotation under constant `torques` (one per input), friction aside; a
        split body's driven part turning with the rest, its spring carrying the body's inputs."""
        ln = self.t["line"]
        n = len(ln["inertia"])
        scale = np.array([1.0 / torque_scale(ln, j) for j in range(n)])  # speed of j per speed of 0
        t_in = np.zeros(n)
        for k, body in enumerate(self.t["inputs"]):
            t_in[body] += torques[k]
        w0 = (t_in @ scale) / (ln["drag"] @ scale ** 2)
        w = w0 * scale
        # force balance body by body: the coupling torques, then the twists
        q = np.zeros(n)
        carried = 0.0
        for j in range(n - 1):
            carried = ln["ratio"][j] * (carried + t_in[j] - ln["drag"][j] * w[j])
            s = carried / ln["stiffness"][j] + np.sign(carried) * self.half[j]
            q[j + 1] = q[j] / ln["ratio"][j] - s
        if self.split is not None:
            b, k = self.split
            q = np.append(q, q[b] + t_in[b] / k)
            w = np.append(w, w[b])
        return np.concatenate([q, w, torques])


@njit(cache=True)
def coupling_torques(e, half, stiffness, damping, q, w):
    """Each coupling's torque: spring and damper beyond its half play `half` (a dead zone, the
    damper too acting only in contact). e: the elongations (twist = e q)."""
    torque = np.zeros(e.shape[0])
    for c in range(e.shape[0]):
        s, sd = 0.0, 0.0
        for j in range(e.shape[1]):
            s += e[c, j] * q[j]
            sd += e[c, j] * w[j]
        if s > half[c]:
            torque[c] = stiffness[c] * (s - half[c]) + damping[c] * sd
        elif s < -half[c]:
            torque[c] = stiffness[c] * (s + half[c]) + damping[c] * sd
    return torque


@njit(cache=True)
def line_rhs(time, x, e, half, stiffness, damping, drag, inertia, friction, inputs, delay, lag, u):
    """The line's right-hand side (states q, w, one lagged torque per input); u the commanded
    torques (samples x inputs), each input's held over its sample and read a dead time late."""
    n = inertia.size
    q, w, z = x[:n], x[n:2 * n], x[2 * n:]
    force = np.empty(n)
    for j in range(n):
        force[j] = -drag[j] * w[j] - stribeck(friction[j], w[j])
    torque = coupling_torques(e, half, stiffness, damping, q, w)
    for j in range(n):
        for c in range(e.shape[0]):
            force[j] -= e[c, j] * torque[c]
    dz = np.zeros(z.size)
    for k in range(inputs.size):
        held = u[held_sample(time, delay[k], DT, u.shape[0]), k]
        if lag[k] > 0:
            dz[k] = (held - z[k]) / lag[k]
            force[inputs[k]] += z[k]
        else:
            force[inputs[k]] += held
    return np.concatenate((w, force / inertia, dz))


def simulate(t, rng):
    """The inputs' commanded torques (samples x inputs) and the outputs' true values."""
    u, outputs, _ = simulate_states(t, rng)
    return u, outputs


def simulate_states(t, rng):
    """`simulate`'s torques and outputs, and the true states (samples x states: q, w, lags)."""
    steps = int(DURATION_S / DT)
    line = Line(t)
    a, sp = t["amplitude"], t["set_point_nm"]
    ninputs = len(t["inputs"])
    u = np.zeros((steps, ninputs))
    # the second input (a load machine) holds the set point against the first and is excited
    # at half the amplitude
    gear = torque_scale(t["line"], line.n - 1)
    second = [-sp * gear] if ninputs > 1 else []
    x = line.start(np.array([sp] + second))
    if t["excitation"] != "closed_loop":
        u[:, 0] = sp + a * open_loop(t["excitation"], rng, steps)
        if ninputs > 1:
            u[:, 1] = second[0] + 0.5 * a * gear * open_loop("multisine", rng, steps)
        line.u = u
        states = lsoda(line_rhs, x, np.arange(steps) * DT, line.args(), t["seed"], atol=1e-10)
    else:
        # a PI speed loop on the first body's measured speed (bandwidth 5 Hz on the line's
        # inertia reflected to it), its reference a PRBS of ±2 rad/s about the set point's speed
        j_total = a / (5.0 * 2 * np.pi)
        kp, ki = j_total * 2 * np.pi * 5.0, j_total * (2 * np.pi * 5.0) * (2 * np.pi * 1.0)
        reference = x[line.n] + 2.0 * open_loop("prbs", rng, steps)
        noise = measured(np.zeros(steps), rng)
        load = (second[0] + 0.5 * a * gear * open_loop("multisine", rng, steps)) if ninputs > 1 else None
        states = np.zeros((steps, x.size))
        integral = 0.0
        line.u = u
        args = line.args()  # holds u itself: each sample's torques are written into it
        for k in range(steps):
            states[k] = x
            error = reference[k] - (x[line.n] + noise[k])
            integral += error * DT
            u[k, 0] = np.clip(sp + kp * error + ki * integral, sp - 3 * a, sp + 3 * a)
            if load is not None:
                u[k, 1] = load[k]
            x = lsoda(line_rhs, x, np.array([k * DT, (k + 1) * DT]), args, t["seed"], atol=1e-10)[-1]
    n = line.n
    outputs = []
    for quantity, at in t["outputs"]:
        if quantity == "speed":
            outputs.append(states[:, n + at])
        else:
            torques = np.array([line.coupling_torques(s[:n], s[n:2 * n]) for s in states])
            outputs.append(torques[:, at])
    return u, outputs, states


# A friction's torque is constant where its body's speed keeps one sign beyond this: the truth's
# Stribeck rise (below 0.05 rad/s) is then below 1e-10 of it and its sign's smoothing (5 mrad/s)
# gone.
FRICTION_CONSTANT_BEYOND_RADPS = 0.25


def not_acting(t, states):
    """The truth's effects that cannot act on the record (their indices in t["effects"], each with
    why), judged on the true states: a friction whose body's speed keeps one sign beyond
    FRICTION_CONSTANT_BEYOND_RADPS (its torque is then a constant, which the record cannot tell
    from an offset of the input torque, and which every diagnosis's high-pass removes with the
    offsets), a play whose coupling never leaves contact on one side (the coupling is then
    linear, the play a constant twist). No record can show such an effect; the survey scores
    the record without it."""
    # the states' bodies and couplings (a split body adds one of each, after the line's own)
    line = Line(t)
    n, elong = line.n, line.e
    found = []
    for i, e in enumerate(t["effects"]):
        if e["effect"] == "coulomb_friction":
            w = states[:, n + e["body"]]
            if np.all(w > FRICTION_CONSTANT_BEYOND_RADPS) or np.all(w < -FRICTION_CONSTANT_BEYOND_RADPS):
                found.append(dict(index=i, why=f"its body turns at {w.min():.3g}-{w.max():.3g} rad/s throughout: "
                                                "a constant torque"))
        elif e["effect"] == "backlash":
            twist = states[:, :n] @ elong[e["coupling"]]
            half = e["size"] / 2
            if np.all(twist > half) or np.all(twist < -half):
                found.append(dict(index=i, why="its coupling never leaves contact"))
    return found


def truth_file(bundle):
    """Where a bundle's record of the effects that cannot act (`not_acting`) is kept."""
    return os.path.splitext(bundle)[0] + ".truth.json"


def keep_not_acting(t, states, bundle):
    """Writes `not_acting` of the record of `t` beside its `bundle`."""
    with open(truth_file(bundle), "w") as f:
        json.dump(not_acting(t, states), f)


def effects_not_acting(t, bundle):
    """`not_acting` of the record at `bundle`, read from beside it — or, for a record written
    before it was kept, from the record simulated again (the same seeds give the same states)."""
    path = truth_file(bundle)
    if not os.path.exists(path):
        if not any(e["effect"] in ("backlash", "coulomb_friction") for e in t["effects"]):
            return []
        _, _, states = simulate_states(t, np.random.default_rng(t["noise_seed"]))
        keep_not_acting(t, states, bundle)
    with open(path) as f:
        return json.load(f)


def silent(t):
    """The indices in t["effects"] of those that cannot act on the record (`effects_not_acting`)."""
    return {d["index"] for d in t.get("not_acting", [])}


def write_bundle(folder, t):
    rng = np.random.default_rng(t["noise_seed"])
    u, outputs, states = simulate_states(t, rng)
    steps = u.shape[0]
    name = f"line_{t['seed']:04d}"
    columns = {"time_s": np.arange(steps) * DT}
    # a torque sensor's noise: 0.2 % of the excitation's amplitude
    noise = 0.002 * t["amplitude"]
    for k in range(u.shape[1]):
        columns[f"torque_in{k + 1}_Nm"] = u[:, k] + rng.normal(0, noise, steps)
    for (quantity, at), y in zip(t["outputs"], outputs):
        if quantity == "speed":
            columns[f"speed_b{at + 1}_radps"] = measured(y, rng)
        else:
            columns[f"torque_c{at + 1}_Nm"] = y + rng.normal(0, noise, steps)
    np.savetxt(os.path.join(folder, name + ".csv"), np.column_stack(list(columns.values())), delimiter=",",
               header=",".join(columns), comments="", fmt="%.9g")
    ln, dec = t["line"], t["declared"]
    n = len(ln["inertia"])
    lines = ['kind = "drive_test"', f'data = "{name}.csv"', 'domain = "rotational"', "", "[model]", "bodies = ["]
    for j in range(n):
        lines.append(f'  {{ name = "b{j + 1}", inertia = {dec["inertia"][j]:.6g}, drag = {ln["drag"][j]:.6g} }},')
    lines += ["]", "couplings = ["]
    for i in range(n - 1):
        lines.append(f'  {{ stiffness = {dec["stiffness"][i]:.6g}, damping = {ln["damping"][i]:.6g}, '
                     f'ratio = {ln["ratio"][i]:g} }},')
    lines.append("]")
    for k, body in enumerate(t["inputs"]):
        lines += ["", "[[inputs]]", f'column = "torque_in{k + 1}_Nm"', f'body = "b{body + 1}"']
    for quantity, at in t["outputs"]:
        if quantity == "speed":
            lines += ["", "[[outputs]]", f'column = "speed_b{at + 1}_radps"', f'body = "b{at + 1}"',
                      'quantity = "speed"']
        else:
            lines += ["", "[[outputs]]", f'column = "torque_c{at + 1}_Nm"', f"coupling = {at + 1}",
                      'quantity = "coupling_torque"']
    bundle = os.path.join(folder, name + ".toml")
    with open(bundle, "w") as f:
        f.write("\n".join(lines) + "\n")
    keep_not_acting(t, states, bundle)
    return bundle


def place(e):
    """Where an effect of the truth acts, in rigtwin's words ("body b2", "coupling 1", "input 2")."""
    if "body" in e:
        return f"body b{e['body'] + 1}"
    if "coupling" in e:
        return f"coupling {e['coupling'] + 1}"
    return f"input {e['input'] + 1}"


def found_effects(report):
    """The report's effects as (name, place): the drive engine's one `effect`, or `effects`."""
    if "effects" in report:
        return sorted((e["effect"], e.get("at")) for e in report["effects"])
    if report.get("effect") in (None, "none", "damping"):
        return []
    return [(report["effect"], report.get("at"))]


def score(t, report):
    """'right', 'not explained' (an honest miss) or 'wrong'; where right with one effect, its
    size's relative error and whether its 95 % interval holds the truth."""
    verdict = report.get("verdict")
    if verdict == "not_explained":
        return "not explained", None, None
    acting = [e for i, e in enumerate(t["effects"]) if i not in silent(t)]
    truth = sorted((e["effect"], place(e)) for e in acting)
    if not truth:
        return ("right" if verdict == "declared_model_fits" else "wrong"), None, None
    if verdict != "explained" or found_effects(report) != truth:
        return "wrong", None, None
    if len(acting) != 1:
        return "right", None, None
    e = acting[0]
    key = SCORED[e["effect"]]
    params = report.get("parameters") or report["effects"][0]["parameters"]
    value = params.get(key)
    if value is None:
        return "wrong", None, None
    interval = (report.get("intervals") or {}).get(key)
    covered = None if interval is None or None in interval else bool(interval[0] <= e["size"] <= interval[1])
    return "right", abs(value - e["size"]) / e["size"], covered


def describe(t, report):
    """A record's line and truth and rigtwin's answer, for the log."""
    quiet = silent(t)
    truth = "+".join(f"{e['effect']}@{place(e)}" + ("(cannot act)" if i in quiet else "")
                     for i, e in enumerate(t["effects"])) or "none"
    found = "+".join(f"{e}@{a}" for e, a in found_effects(report)) or "none"
    return (f"{len(t['line']['inertia'])} bodies {int(sum(t['line']['ratio'] > 1))} gears {truth:45s} "
            f"{t['excitation']:11s} -> {report.get('verdict'):20s} {found:40s}")


def main():
    ap = arguments(__doc__)
    ap.add_argument("--only", choices=ONLY_KINDS,
                    help="every record one effect of this kind (its own tuning and held-out seeds)")
    ap.add_argument("--search-compliance", action="store_true",
                    help="diagnose with `rigtwin diagnose --search-compliance`")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    seeds = parse_seeds(args.seeds)
    truths = [truth_of(seed, args.only) for seed in seeds]
    bundles = bundles_of(args, truths, write_bundle, lambda seed: f"line_{seed:04d}.toml")
    for t, bundle in zip(truths, bundles):
        t["not_acting"] = effects_not_acting(t, bundle)
    flags = ["--search-compliance"] if args.search_compliance else []
    rows = diagnose_all(args.rigtwin, seeds, truths, bundles, score, describe, flags)
    groups = [("none", lambda t: not t["effects"])]
    groups += [(k, lambda t, k=k: [e["effect"] for e in t["effects"]] == [k]) for k in ONLY_KINDS]
    groups.append(("pairs", lambda t: len(t["effects"]) == 2))
    print(table(rows, groups))
    if args.summary:
        write_summary(args.summary, rows)


if __name__ == "__main__":
    main()
