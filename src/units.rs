//! Units of recorded signals and their conversion to SI (`../shared/DATA.md`, "Records in other
//! formats"): one table of the units rig files carry, each with its dimension and its factor to
//! SI, and the calibration of a channel, SI value = gain · (recorded value in SI) + offset.

/// What a signal measures, as far as units go.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dimension {
    /// s.
    Time,
    /// rad.
    Angle,
    /// rad/s.
    AngularSpeed,
    /// N·m.
    Torque,
    /// m.
    Length,
    /// m/s.
    Speed,
    /// N.
    Force,
}

impl Dimension {
    /// The SI unit.
    pub fn si(self) -> &'static str {
        match self {
            Dimension::Time => "s",
            Dimension::Angle => "rad",
            Dimension::AngularSpeed => "rad/s",
            Dimension::Torque => "N·m",
            Dimension::Length => "m",
            Dimension::Speed => "m/s",
            Dimension::Force => "N",
        }
    }

    /// In words, for messages.
    pub fn name(self) -> &'static str {
        match self {
            Dimension::Time => "a time",
            Dimension::Angle => "an angle",
            Dimension::AngularSpeed => "an angular speed",
            Dimension::Torque => "a torque",
            Dimension::Length => "a length",
            Dimension::Speed => "a speed",
            Dimension::Force => "a force",
        }
    }
}

/// A unit's dimension: one of the signals', or an electrical or raw one that only a gain turns
/// into a physical value (a motor current reference in V, a strain-gauge bridge in mV/V).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnitKind {
    /// A physical dimension.
    Physical(Dimension),
    /// Volts, amperes, counts, per cent or dimensionless: needs a `gain`.
    Raw,
}

/// The units rigtwin converts: (spellings, kind, factor to SI). Every factor is exact by
/// definition (the inch is 0.0254 m, the pound 0.45359237 kg, g_n = 9.80665 m/s²).
const TABLE: &[(&[&str], UnitKind, f64)] = {
    use Dimension::*;
    use UnitKind::*;
    const TAU: f64 = 2.0 * std::f64::consts::PI;
    const DEG: f64 = std::f64::consts::PI / 180.0;
    const LBF: f64 = 0.45359237 * 9.80665;
    &[
        (&["s"], Physical(Time), 1.0),
        (&["ms"], Physical(Time), 1e-3),
        (&["us", "µs", "μs"], Physical(Time), 1e-6),
        (&["min"], Physical(Time), 60.0),
        (&["rad"], Physical(Angle), 1.0),
        (&["deg", "°"], Physical(Angle), DEG),
        (&["rev"], Physical(Angle), TAU),
        (&["rad/s"], Physical(AngularSpeed), 1.0),
        (&["deg/s", "°/s"], Physical(AngularSpeed), DEG),
        (&["rpm", "1/min", "r/min", "rev/min"], Physical(AngularSpeed), TAU / 60.0),
        (&["rev/s", "rps"], Physical(AngularSpeed), TAU),
        (&["Nm", "N·m", "N.m", "N m"], Physical(Torque), 1.0),
        (&["kNm", "kN·m", "kN.m", "kN m"], Physical(Torque), 1e3),
        (&["Nmm", "N·mm", "N.mm", "N mm"], Physical(Torque), 1e-3),
        (&["lbf·in", "lbf.in", "lbf in", "in·lbf", "in.lbf", "in-lbf"], Physical(Torque), LBF * 0.0254),
        (&["lbf·ft", "lbf.ft", "lbf ft", "ft·lbf", "ft.lbf", "ft-lbf"], Physical(Torque), LBF * 0.3048),
        (&["m"], Physical(Length), 1.0),
        (&["mm"], Physical(Length), 1e-3),
        (&["um", "µm", "μm"], Physical(Length), 1e-6),
        (&["mil", "mils"], Physical(Length), 25.4e-6),
        (&["in", "inch"], Physical(Length), 0.0254),
        (&["m/s"], Physical(Speed), 1.0),
        (&["mm/s"], Physical(Speed), 1e-3),
        (&["um/s", "µm/s", "μm/s"], Physical(Speed), 1e-6),
        (&["in/s", "ips"], Physical(Speed), 0.0254),
        (&["N"], Physical(Force), 1.0),
        (&["kN"], Physical(Force), 1e3),
        (&["lbf"], Physical(Force), LBF),
        (&["V", "mV", "A", "mA", "1", "-", "%", "counts", "mV/V"], Raw, 1.0),
    ]
};

/// The kind and the factor to SI of `unit` (spaces around it ignored); None when unknown.
/// Raw units have factor 1 except their decimal prefixes (mV, mA: 1e-3; %: 1e-2).
pub fn lookup(unit: &str) -> Option<(UnitKind, f64)> {
    let u = unit.trim();
    let raw_factor = match u {
        "mV" | "mA" => 1e-3,
        "%" => 1e-2,
        _ => 1.0,
    };
    TABLE.iter().find(|(names, _, _)| names.contains(&u)).map(|&(_, kind, f)| match kind {
        UnitKind::Raw => (kind, raw_factor),
        _ => (kind, f),
    })
}

/// How a recorded channel becomes the SI value of a signal.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The recorded unit (None: the value is taken as SI).
    pub unit: Option<String>,
    /// SI value = gain · recorded (in SI) + offset.
    pub gain: f64,
    /// See `gain`.
    pub offset: f64,
}

impl Default for Calibration {
    fn default() -> Self {
        Calibration { unit: None, gain: 1.0, offset: 0.0 }
    }
}

impl Calibration {
    /// The (scale, offset) that turn a recorded value into the SI value of a signal of
    /// `dimension`: SI = scale · recorded + offset. Errors say what is wrong with which unit.
    pub fn resolve(&self, dimension: Dimension) -> Result<(f64, f64), String> {
        if !(self.gain.is_finite() && self.gain != 0.0) {
            return Err(format!("`gain` = {}: expected a finite, non-zero number", self.gain));
        }
        if !self.offset.is_finite() {
            return Err(format!("`offset` = {}: expected a finite number", self.offset));
        }
        let factor = match &self.unit {
            None => 1.0,
            Some(u) => match lookup(u) {
                None => {
                    return Err(format!(
                        "unit \"{u}\" is not known: expected {} in a unit such as {}",
                        dimension.name(),
                        examples(dimension)
                    ))
                }
                Some((UnitKind::Physical(d), f)) if d == dimension => f,
                Some((UnitKind::Physical(d), _)) => {
                    return Err(format!(
                        "unit \"{u}\" is {}, but this signal is {} ({})",
                        d.name(),
                        dimension.name(),
                        dimension.si()
                    ))
                }
                Some((UnitKind::Raw, f)) if self.gain != 1.0 => f,
                Some((UnitKind::Raw, _)) => {
                    return Err(format!(
                        "unit \"{u}\" is not {}: give the sensor's `gain` in {} per {u}",
                        dimension.name(),
                        dimension.si()
                    ))
                }
            },
        };
        Ok((self.gain * factor, self.offset))
    }

    /// A line for the report: what was done to the recorded values, None for SI as recorded.
    pub fn describe(&self, signal: &str, channel: &str, dimension: Dimension) -> Option<String> {
        let (scale, offset) = self.resolve(dimension).ok()?;
        if scale == 1.0 && offset == 0.0 && channel == signal {
            return None;
        }
        let unit = self.unit.as_deref().unwrap_or(dimension.si());
        let mut s = format!("{signal} [{}] = {scale:.6e} × {channel} [{unit}]", dimension.si());
        if offset != 0.0 {
            s += &format!(" + {offset:e}");
        }
        Some(s)
    }
}

fn examples(d: Dimension) -> String {
    let names: Vec<&str> =
        TABLE.iter().filter(|(_, k, _)| *k == UnitKind::Physical(d)).map(|(names, _, _)| names[0]).collect();
    names.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use std::f64::consts::PI;

    /// Every unit of the table against a factor computed by hand from its definition.
    #[test]
    fn each_unit_has_its_defined_factor() {
        let lbf = 4.4482216152605; // N, by definition of the pound-force
        for (unit, dim, factor) in [
            ("ms", Dimension::Time, 0.001),
            ("µs", Dimension::Time, 1e-6),
            ("min", Dimension::Time, 60.0),
            ("deg", Dimension::Angle, PI / 180.0),
            ("rev", Dimension::Angle, 2.0 * PI),
            ("rpm", Dimension::AngularSpeed, 2.0 * PI / 60.0),
            ("deg/s", Dimension::AngularSpeed, PI / 180.0),
            ("rev/s", Dimension::AngularSpeed, 2.0 * PI),
            ("kNm", Dimension::Torque, 1000.0),
            ("N·mm", Dimension::Torque, 0.001),
            ("lbf·in", Dimension::Torque, lbf * 0.0254),
            ("lbf·ft", Dimension::Torque, lbf * 0.3048),
            ("mm", Dimension::Length, 0.001),
            ("µm", Dimension::Length, 1e-6),
            ("mil", Dimension::Length, 0.0000254),
            ("in", Dimension::Length, 0.0254),
            ("mm/s", Dimension::Speed, 0.001),
            ("in/s", Dimension::Speed, 0.0254),
            ("kN", Dimension::Force, 1000.0),
            ("lbf", Dimension::Force, lbf),
        ] {
            let (scale, offset) = Calibration { unit: Some(unit.into()), ..Default::default() }.resolve(dim).unwrap();
            assert_relative_eq!(scale, factor, max_relative = 1e-14);
            assert_eq!(offset, 0.0);
        }
        // every spelling in the table resolves to its own kind
        for (names, kind, _) in TABLE {
            for n in *names {
                assert_eq!(lookup(n).unwrap().0, *kind, "{n}");
            }
        }
    }

    #[test]
    fn wrong_or_unknown_units_and_raw_units_without_gain_are_refused() {
        let c = |u: &str, gain: f64| Calibration { unit: Some(u.into()), gain, offset: 0.0 };
        let e = c("Nm", 1.0).resolve(Dimension::AngularSpeed).unwrap_err();
        assert!(e.contains("a torque") && e.contains("an angular speed"), "{e}");
        let e = c("furlong", 1.0).resolve(Dimension::Length).unwrap_err();
        assert!(e.contains("not known") && e.contains("mm"), "{e}");
        let e = c("V", 1.0).resolve(Dimension::Force).unwrap_err();
        assert!(e.contains("gain") && e.contains("N per V"), "{e}");
        // a current reference in V times the drive's gain in N/V
        assert_eq!(c("V", 35.15).resolve(Dimension::Force).unwrap(), (35.15, 0.0));
        assert_eq!(c("mV", 2.0).resolve(Dimension::Force).unwrap(), (2.0e-3, 0.0));
        assert!(c("rpm", 0.0).resolve(Dimension::AngularSpeed).is_err());
        // gain and offset after the unit: 1000 rpm with gain 2, offset 1 rad/s
        let (s, o) =
            Calibration { unit: Some("rpm".into()), gain: 2.0, offset: 1.0 }.resolve(Dimension::AngularSpeed).unwrap();
        assert_relative_eq!(s * 1000.0 + o, 2.0 * 1000.0 * 2.0 * PI / 60.0 + 1.0, max_relative = 1e-15);
    }
}

/// The SI unit of a drive line's quantity as text shows it (`rad/s`, `N·m`; `m/s`, `N` on a
/// linear axis): plot axes and labels.
pub fn quantity_unit(q: plant::Quantity, domain: plant::Domain) -> &'static str {
    let rotational = domain == plant::Domain::Rotational;
    match (q, rotational) {
        (plant::Quantity::Position, true) => "rad",
        (plant::Quantity::Position, false) => "m",
        (plant::Quantity::Speed, true) => "rad/s",
        (plant::Quantity::Speed, false) => "m/s",
        (plant::Quantity::CouplingForce, true) => "N·m",
        (plant::Quantity::CouplingForce, false) => "N",
    }
}

/// A report key's name without its unit suffix, and the unit (as in the JSON). Keys the rig
/// reports without a suffix (`j_drive`, `c_short`, …) have their unit here.
fn name_and_unit(key: &str) -> (&str, &'static str) {
    // (suffix, unit shown, scales to try: (factor, prefixed unit))
    const SUFFIXES: [(&str, &str); 18] = [
        ("_Nm_per_rad", "N·m/rad"),
        ("_Nms_per_rad", "N·m·s/rad"),
        ("_N_per_m", "N/m"),
        ("_Ns_per_m", "N·s/m"),
        ("_kg_m2", "kg·m²"),
        ("_kgm2", "kg·m²"),
        ("_radps", "rad/s"),
        ("_mps", "m/s"),
        ("_Nm", "N·m"),
        ("_hz", "Hz"),
        ("_Hz", "Hz"),
        ("_rad", "rad"),
        ("_kg", "kg"),
        ("_N", "N"),
        ("_s", "s"),
        ("_m", "m"),
        ("_1", ""),
        ("_deg", "°"),
    ];
    const BARE: [(&str, &str); 7] = [
        ("j_drive", "kg·m²"),
        ("j_m2", "kg·m²"),
        ("j_m3", "kg·m²"),
        ("c_short", "N·m/rad"),
        ("c_long", "N·m/rad"),
        ("c_delta", "N·m/rad"),
        ("damping_ratio", ""),
    ];
    let (name, unit) = SUFFIXES
        .iter()
        .find_map(|(suffix, unit)| key.strip_suffix(suffix).filter(|n| !n.is_empty()).map(|n| (n, *unit)))
        .or_else(|| BARE.iter().find(|(k, _)| *k == key).map(|(k, u)| (*k, *u)))
        .unwrap_or((key, ""));
    (name, unit)
}

/// Report keys (their unit as a suffix, as in the JSON) as a person reads them: the name without
/// the suffix and the value with its unit, in engineering form — `delay_s` 0.0055 → `delay 5.50
/// ms`, `c_short` 1478.27 → `c_short 1478.3 N·m/rad`, `backlash_rad` 0.00274 → `backlash 2.740
/// mrad`.
pub fn display(key: &str, value: f64) -> String {
    let (name, unit) = name_and_unit(key);
    format!("{name} {}", quantity(value, unit))
}

/// [`display`] with the value's 95 % interval behind it where there is a finite one
/// (`backlash 2.740 mrad (95 %: 2.701 … 2.779 mrad)`).
pub fn display_within(key: &str, value: f64, interval: Option<&[f64; 2]>) -> String {
    match interval.filter(|i| i.iter().all(|v| v.is_finite())) {
        Some([lo, hi]) => {
            let (name, unit) = name_and_unit(key);
            format!("{name} {} (95 %: {} … {})", quantity(value, unit), quantity(*lo, unit), quantity(*hi, unit))
        }
        None => display(key, value),
    }
}

/// A parameter the record does not determine: no value, only its 95 % interval (where finite).
pub fn display_not_determined(key: &str, interval: Option<&[f64; 2]>) -> String {
    let (name, unit) = name_and_unit(key);
    match interval.filter(|i| i.iter().all(|v| v.is_finite())) {
        Some([lo, hi]) => {
            format!("{name} not determined by the record (95 %: {} … {})", quantity(*lo, unit), quantity(*hi, unit))
        }
        None => format!("{name} not determined by the record"),
    }
}

/// A value with its unit in engineering form: a small time, angle or length with a prefix
/// (ms, µs, mrad, mm, µm), four significant digits (five from 100 up), scientific notation only
/// far from 1.
pub fn quantity(value: f64, unit: &str) -> String {
    let prefixed: &[(f64, &str)] = match unit {
        "s" => &[(1e-3, "ms"), (1e-6, "µs")],
        "rad" => &[(1e-3, "mrad"), (1e-6, "µrad")],
        "m" => &[(1e-3, "mm"), (1e-6, "µm")],
        _ => &[],
    };
    let (v, u) = prefixed
        .iter()
        .find(|(f, _)| value.abs() < 1000.0 * f && value.abs() >= *f)
        .map_or((value, unit), |(f, u)| (value / f, *u));
    // four significant digits, five from 100 up (a stiffness to 0.1 N·m/rad)
    let text = significant(v, if v.abs() >= 100.0 { 5 } else { 4 });
    if u.is_empty() {
        text
    } else {
        format!("{text} {u}")
    }
}

/// `v` with `digits` significant digits: plain notation from 1e-3 to 1e6, else scientific.
pub fn significant(v: f64, digits: usize) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".into();
    }
    let magnitude = v.abs().log10().floor() as i32;
    if !(-3..6).contains(&magnitude) {
        return format!("{:.*e}", digits.saturating_sub(1), v);
    }
    let decimals = (digits as i32 - 1 - magnitude).max(0) as usize;
    format!("{v:.decimals$}")
}

#[cfg(test)]
mod display_tests {
    use super::*;

    #[test]
    fn keys_read_as_engineers_write_them() {
        assert_eq!(display("delay_s", 5.500239e-3), "delay 5.500 ms");
        assert_eq!(display("c_short", 1478.27), "c_short 1478.3 N·m/rad");
        assert_eq!(display("j_drive", 0.5368647), "j_drive 0.5369 kg·m²");
        assert_eq!(display("backlash_rad", 2.74e-3), "backlash 2.740 mrad");
        assert_eq!(display("friction_Nm", 0.2499823), "friction 0.2500 N·m");
        assert_eq!(display("stiffness_Nm_per_rad", 2421.3), "stiffness 2421.3 N·m/rad");
        assert_eq!(display("damping_ratio", 0.0299), "damping_ratio 0.02990");
        assert_eq!(display("smoothing_speed_radps", 7.3e12), "smoothing_speed 7.3000e12 rad/s");
        assert_eq!(quantity(2.5, "s"), "2.500 s");
    }
}
