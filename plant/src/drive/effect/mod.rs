//! The effects a drive model's elements carry: one file per effect, holding its type and its
//! [`EffectModel`] implementation — its name, the element it acts on, its parameters with their
//! dimensions and bounds, how it enters the right-hand side ([`Dynamics`]) and its
//! linearisation, and what the diagnosis needs to know of it ([`Moves`]). [`Effect`] is the
//! closed set a model file names (`effect = "backlash"`); adding an effect is its file, one
//! variant, one line of [`each`], of `into_effect!` and of [`Effect::vocabulary`] here; the
//! diagnosis of drive records then searches for it ([`Search`]).

mod actuator_lag;
mod backlash;
mod compliance;
mod coulomb_friction;
mod time_delay;

pub use actuator_lag::ActuatorLag;
pub use backlash::Backlash;
pub use compliance::Compliance;
pub use coulomb_friction::CoulombFriction;
pub use time_delay::TimeDelay;

use serde::{Deserialize, Serialize};

use super::{Dimension, DriveModel, Dynamics};
use crate::error::Result;

/// The element an effect acts on (0-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Element {
    /// A body (its Coulomb friction).
    Body(usize),
    /// A coupling (its play).
    Coupling(usize),
    /// An input (its dead time or lag).
    Input(usize),
}

impl Element {
    /// Its index among the elements of its kind.
    pub fn index(self) -> usize {
        match self {
            Element::Body(i) | Element::Coupling(i) | Element::Input(i) => i,
        }
    }

    /// The key that names an element of this kind in a model file.
    pub fn key(self) -> &'static str {
        match self {
            Element::Body(_) => "body",
            Element::Coupling(_) => "coupling",
            Element::Input(_) => "input",
        }
    }

    /// How many elements of this kind `model` has.
    pub fn count(self, model: &DriveModel) -> usize {
        match self {
            Element::Body(_) => model.line.bodies.len(),
            Element::Coupling(_) => model.line.couplings.len(),
            Element::Input(_) => model.inputs.len(),
        }
    }

    /// The stem of its parameters' names: the body's label, `coupling_<i>` (1-based), the
    /// input's name.
    pub fn label(self, model: &DriveModel) -> String {
        let unknown = || "?".to_string();
        match self {
            Element::Body(i) => model.body_labels().get(i).cloned().unwrap_or_else(unknown),
            Element::Coupling(i) => format!("coupling_{}", i + 1),
            Element::Input(i) => model.input_names().get(i).cloned().unwrap_or_else(unknown),
        }
    }

    /// After a parameter's description: "at motor", "of coupling 2", "of input M_motor".
    pub fn phrase(self, model: &DriveModel) -> String {
        match self {
            Element::Body(_) => format!("at {}", self.label(model)),
            Element::Coupling(_) => format!("of {}", self.words(model)),
            Element::Input(_) => format!("of input {}", self.label(model)),
        }
    }

    /// In words: "body load", "coupling 2", "input 1" (positions 1-based).
    pub fn words(self, model: &DriveModel) -> String {
        match self {
            Element::Body(i) => format!("body {}", model.line.bodies.get(i).map_or("?", |b| b.name.as_str())),
            Element::Coupling(i) => format!("coupling {}", i + 1),
            Element::Input(i) => format!("input {}", i + 1),
        }
    }
}

/// One parameter of an effect. Every effect parameter is bounded to positive, finite values
/// (an effect of size 0 is no effect: leave it out).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EffectParameter {
    /// Its name after the element's label in the parameter list (`<label>.<name>`).
    pub name: &'static str,
    /// Its key stem in reports, before the unit (`<key>_<unit>`).
    pub key: &'static str,
    /// What it measures.
    pub dimension: Dimension,
    /// In words, before "at <body>" / "of <coupling or input>".
    pub what: &'static str,
}

/// What an effect may change of the declared mechanics that a record measured: the diagnosis
/// re-fits the declared inertias and stiffnesses beside every candidate effect, and a fit that
/// moves them in a way the effect cannot explain imitates a missing effect by distorting the
/// declared model (`ident::diagnose::verdict::declared_moved` judges it, one rule for every
/// model).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Moves {
    /// Nothing: it acts beside the declared inertias and stiffnesses (a friction, a play, a dead
    /// time, a lag, damping), which keep the values the record measured.
    Nothing,
    /// It splits an inertia in two, their total the declared one, and puts a spring in series
    /// with the declared stiffness (a compliance inside a machine): what the declared stiffness
    /// measured is the series pair, so the declared spring itself may be stiffer than declared,
    /// never softer, and the pair never stiffer.
    SeriesSpring,
}

/// How the diagnosis searches a record for an effect (`ident::diagnose::drive`): where the
/// record can show it, what its size is measured against, the sizes the search starts from and
/// the largest size that is still an answer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Search {
    /// Where in the declared model's motion the record can show it.
    pub shows: Shows,
    /// What its size (its first parameter) is searched as a multiple of.
    pub scale: Scale,
    /// The multiples the search starts from: from, to, and how many, evenly spaced in logarithm.
    pub grid: (f64, f64, usize),
    /// Its error over its size is rough (a play's: each impact shifts with it), so the best
    /// start is refined on finer grids around it before the local fit.
    pub rough: bool,
    /// The largest size that is still an answer.
    pub limit: Limit,
    /// The smallest size the record can show, a multiple of the scale (0: none): a fit does
    /// not go below it.
    pub floor: f64,
    /// Where its body turns one way throughout the record it is a constant force against the
    /// motion, which a record shows only as offsets (removed with the record's own) and through
    /// the state its simulation is assumed to start in — and at a body an input drives, exactly
    /// as an offset of the input's measured force (a friction under a motor held at speed) — so
    /// there it is no finding.
    pub offset_where_one_way: bool,
}

/// Where a record can show an effect, judged on the declared model's own motion under the
/// recorded inputs and, where the record measures that speed or force, on the measurement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shows {
    /// Anywhere.
    Always,
    /// Where the body's speed comes near zero (within ten times the smoothing speed the
    /// diagnosis gives a friction there) or changes sign.
    SpeedNearZero,
    /// Where the coupling's force changes sign.
    ForceChangesSign,
}

/// What an effect's size is searched as a multiple of.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// The largest RMS input force reflected to the body through the gear stages.
    BodyForce,
    /// The coupling's RMS elastic twist under the declared model.
    CouplingTwist,
    /// The record's sample time.
    SampleTime,
    /// The stiffness the body's couplings give it, K_bb = Σ c e_b² (its diagonal entry of the
    /// line's stiffness matrix).
    BodyStiffness,
}

/// The largest size of an effect that is still an answer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Limit {
    /// None.
    Unbounded,
    /// This many times its scale.
    TimesScale(f64),
    /// This share of the record's length.
    RecordShare(f64),
}

/// The search of an input's time (a dead time, a lag's time constant): at every input, from 0.3
/// to 100 samples (12 starts), up to a tenth of the record, and no shorter than
/// [`INPUT_TIME_FLOOR_SAMPLES`].
pub const INPUT_TIME_SEARCH: Search = Search {
    shows: Shows::Always,
    scale: Scale::SampleTime,
    grid: (0.3, 100.0, 12),
    rough: false,
    limit: Limit::RecordShare(0.1),
    floor: INPUT_TIME_FLOOR_SAMPLES,
    offset_where_one_way: false,
};

/// The shortest dead time or lag a sampled record can show, in samples: an input is known only
/// as held over each sample, so a shift of a fraction of one is within the sample-and-hold's own
/// timing. A fit where the record has no such effect runs towards zero, and beside a friction or
/// a play every simulation's step follows a lag's time constant (`cargo run --release -p ident
/// --example drive_sim_cost`: 6.5 times the cost at 0.3 ms, hundreds of times at the 1e-5 s
/// such fits reached), so the fit stops here.
pub const INPUT_TIME_FLOOR_SAMPLES: f64 = 0.3;

/// What the record and the declared model leave open of an effect of a given size, at its
/// element: a friction's smoothing speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SizeContext {
    /// The smoothing speed the diagnosis gives a friction at the body (a share of its RMS
    /// speed), m/s (rad/s).
    pub smoothing_speed: f64,
    /// The body's inertia (mass), kg·m² (kg).
    pub inertia: f64,
    /// The fastest rate of the declared model's linear part, 1/s.
    pub fastest_rate: f64,
}

/// What one effect is and does.
pub trait EffectModel: Copy + Into<Effect> {
    /// The vocabulary name (as in model files and reports).
    const NAME: &'static str;
    /// Its parameters, in the order of [`EffectModel::values`].
    const PARAMETERS: &'static [EffectParameter];
    /// Whether it makes the right-hand side nonlinear (integrated by RK4, not the exact ZOH).
    const NONLINEAR: bool = false;
    /// What it may change of the declared mechanics (the diagnosis's plausibility).
    const MOVES: Moves = Moves::Nothing;
    /// Whether it changes the line's structure (a compliance splits a body): it is then written
    /// into the line before the dynamics are built ([`EffectModel::write_into_line`]), not into a
    /// slot of the right-hand side.
    const STRUCTURAL: bool = false;
    /// How the diagnosis searches a record for it.
    const SEARCH: Search;
    /// How a controller's linear prediction (the linearisation in contact, friction and dead
    /// times left out of the matrices) holds it, after "is" or "is NOT": what the controller's
    /// notes say of it.
    const PREDICTION: &'static str;

    /// Where it acts.
    fn element(&self) -> Element;
    /// The same effect at element `index` of the same kind.
    fn at_index(self, index: usize) -> Self;
    /// Its parameter values, SI, in [`EffectModel::PARAMETERS`] order.
    fn values(&self) -> Vec<f64>;
    /// Sets its parameter values (as many as [`EffectModel::PARAMETERS`]).
    fn set_values(&mut self, v: &[f64]);
    /// The same effect with size `size` (its first parameter, SI); `context` gives what the
    /// size leaves open.
    fn of_size(self, size: f64, context: &SizeContext) -> Self;
    /// Names of the states it adds, after the angles and speeds.
    fn state_names(&self, _model: &DriveModel) -> Vec<String> {
        Vec::new()
    }
    /// How it enters the right-hand side: fills its element's slot of the dynamics (called once
    /// per effect, in the model's order, on dynamics without effects).
    fn enter(&self, d: &mut Dynamics);
    /// Its part of the linearisation of the piece where every play is in contact (`contact`)
    /// or open: nothing for a linear effect.
    fn linearise(&self, _d: &mut Dynamics, _contact: bool) {}
    /// A structural effect ([`EffectModel::STRUCTURAL`]) writes itself into `m`'s bodies,
    /// couplings, inputs and other effects ([`DriveModel::resolved`], which has left it out of
    /// `m`'s effects).
    fn write_into_line(&self, _m: &mut DriveModel) -> Result<()> {
        Ok(())
    }
}

/// An effect attached to an element of the line (indices 0-based): the closed set of
/// [`EffectModel`]s a model file may name.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "effect", rename_all = "snake_case")]
pub enum Effect {
    /// [`CoulombFriction`].
    CoulombFriction(CoulombFriction),
    /// [`Backlash`].
    Backlash(Backlash),
    /// [`TimeDelay`].
    TimeDelay(TimeDelay),
    /// [`ActuatorLag`].
    ActuatorLag(ActuatorLag),
    /// [`Compliance`].
    Compliance(Compliance),
}

/// `each!(effect, e => expr)`: `expr` with `e` bound to the effect's own type, for every variant.
macro_rules! each {
    ($effect:expr, $e:ident => $body:expr) => {
        match $effect {
            Effect::CoulombFriction($e) => $body,
            Effect::Backlash($e) => $body,
            Effect::TimeDelay($e) => $body,
            Effect::ActuatorLag($e) => $body,
            Effect::Compliance($e) => $body,
        }
    };
}

macro_rules! into_effect {
    ($($t:ident),*) => {$(
        impl From<$t> for Effect {
            fn from(e: $t) -> Effect {
                Effect::$t(e)
            }
        }
    )*};
}
into_effect!(CoulombFriction, Backlash, TimeDelay, ActuatorLag, Compliance);

impl Effect {
    /// The vocabulary name.
    pub fn name(&self) -> &'static str {
        fn name<E: EffectModel>(_: &E) -> &'static str {
            E::NAME
        }
        each!(self, e => name(e))
    }

    /// Its parameters' descriptions.
    pub fn parameter_kinds(&self) -> &'static [EffectParameter] {
        fn kinds<E: EffectModel>(_: &E) -> &'static [EffectParameter] {
            E::PARAMETERS
        }
        each!(self, e => kinds(e))
    }

    /// Whether it makes the right-hand side nonlinear.
    pub fn is_nonlinear(&self) -> bool {
        fn nonlinear<E: EffectModel>(_: &E) -> bool {
            E::NONLINEAR
        }
        each!(self, e => nonlinear(e))
    }

    /// What it may change of the declared mechanics.
    pub fn moves(&self) -> Moves {
        fn moves<E: EffectModel>(_: &E) -> Moves {
            E::MOVES
        }
        each!(self, e => moves(e))
    }

    /// How a controller's linear prediction holds it ([`EffectModel::PREDICTION`]).
    pub fn prediction(&self) -> &'static str {
        fn prediction<E: EffectModel>(_: &E) -> &'static str {
            E::PREDICTION
        }
        each!(self, e => prediction(e))
    }

    /// How the diagnosis searches a record for it.
    pub fn search(&self) -> Search {
        fn search<E: EffectModel>(_: &E) -> Search {
            E::SEARCH
        }
        each!(self, e => search(e))
    }

    /// The same effect with size `size` (its first parameter, SI).
    pub fn of_size(self, size: f64, context: &SizeContext) -> Effect {
        each!(self, e => e.of_size(size, context).into())
    }

    /// One of each effect of the vocabulary, at element 0 and of size 0: what the diagnosis
    /// places at every element where the record can show it. A [`Compliance`] is searched with
    /// its motor share at one half, and only where asked (`ident::diagnose::drive::SearchSettings`);
    /// the diagnosis profiles the share and damping of an answer that holds one.
    pub fn vocabulary() -> [Effect; 5] {
        [
            CoulombFriction { body: 0, friction: 0.0, smoothing_speed: 1.0 }.into(),
            Backlash { coupling: 0, backlash: 0.0 }.into(),
            TimeDelay { input: 0, delay_s: 0.0 }.into(),
            ActuatorLag { input: 0, time_constant_s: 0.0 }.into(),
            Compliance { body: 0, stiffness: 0.0, motor_share: 0.5, damping: None }.into(),
        ]
    }

    /// Where it acts.
    pub fn at(&self) -> Element {
        each!(self, e => e.element())
    }

    /// Where it acts, in words ("body load", "coupling 2", "input 1"; positions 1-based).
    pub fn element(&self, model: &DriveModel) -> String {
        self.at().words(model)
    }

    /// The index of the element it acts on (body, coupling or input, 0-based) and the key that
    /// names that element in a model file (`body`, `coupling`, `input`).
    pub fn element_index(&self) -> (usize, &'static str) {
        let at = self.at();
        (at.index(), at.key())
    }

    /// The same effect at element `index` (of the same kind: body, coupling or input).
    pub fn at_index(self, index: usize) -> Effect {
        each!(self, e => e.at_index(index).into())
    }

    /// Its parameter values, SI, in [`Effect::parameter_kinds`] order.
    pub fn values(&self) -> Vec<f64> {
        each!(self, e => e.values())
    }

    /// Sets its parameter values in [`Effect::parameter_kinds`] order.
    pub fn set_values(&mut self, v: &[f64]) {
        each!(self, e => e.set_values(v))
    }

    /// Names of the states it adds.
    pub fn state_names(&self, model: &DriveModel) -> Vec<String> {
        each!(self, e => e.state_names(model))
    }

    /// Its parameters, SI, keyed with their units in the line's domain (`friction_Nm`,
    /// `backlash_m`, `delay_s`).
    pub fn parameters(&self, model: &DriveModel) -> Vec<(String, f64)> {
        let rotational = model.line.domain == crate::line::Domain::Rotational;
        self.parameter_kinds()
            .iter()
            .zip(self.values())
            .map(|(p, v)| (format!("{}_{}", p.key, p.dimension.key_unit(rotational)), v))
            .collect()
    }

    /// It in words, where it acts and its parameters, as descriptions and notes name it
    /// ("time_delay at input 2 (delay_s = 0.002)").
    pub fn summary(&self, model: &DriveModel) -> String {
        let values: Vec<String> = self.parameters(model).iter().map(|(k, v)| format!("{k} = {v}")).collect();
        format!("{} at {} ({})", self.name(), self.element(model), values.join(", "))
    }

    /// Fills its slot of the dynamics.
    pub(super) fn enter(&self, d: &mut Dynamics) {
        each!(self, e => e.enter(d))
    }

    /// Its part of the linearisation.
    pub(super) fn linearise(&self, d: &mut Dynamics, contact: bool) {
        each!(self, e => e.linearise(d, contact))
    }

    /// Whether it changes the line's structure ([`EffectModel::STRUCTURAL`]).
    pub fn is_structural(&self) -> bool {
        fn structural<E: EffectModel>(_: &E) -> bool {
            E::STRUCTURAL
        }
        each!(self, e => structural(e))
    }

    /// Writes a structural effect into `m` ([`EffectModel::write_into_line`]).
    pub(super) fn write_into_line(&self, m: &mut DriveModel) -> Result<()> {
        each!(self, e => e.write_into_line(m))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The vocabulary holds every effect once: a new variant fails to compile here until it has
    /// its position, and fails the test until [`Effect::vocabulary`] lists it.
    #[test]
    fn the_vocabulary_has_every_effect_once() {
        let position = |e: &Effect| match e {
            Effect::CoulombFriction(_) => 0,
            Effect::Backlash(_) => 1,
            Effect::TimeDelay(_) => 2,
            Effect::ActuatorLag(_) => 3,
            Effect::Compliance(_) => 4,
        };
        let mut seen: Vec<usize> = Effect::vocabulary().iter().map(position).collect();
        seen.sort();
        assert_eq!(seen, [0, 1, 2, 3, 4]);
    }

    /// An effect of a size has that size as its first parameter, at the element it was placed
    /// at, and the search's grid and scale are sane (starts below its limit, positive).
    #[test]
    fn an_effect_of_a_size_has_it() {
        let context = SizeContext { smoothing_speed: 0.02, inertia: 0.5, fastest_rate: 400.0 };
        for prototype in Effect::vocabulary() {
            let e = prototype.at_index(2).of_size(0.37, &context);
            assert_eq!(e.values()[0], 0.37, "{}", e.name());
            assert_eq!(e.at().index(), 2, "{}", e.name());
            let s = e.search();
            assert!(s.grid.0 > 0.0 && s.grid.1 > s.grid.0 && s.grid.2 >= 2, "{}: {s:?}", e.name());
            if let Limit::TimesScale(k) = s.limit {
                assert!(k > s.grid.1, "{}: its starts reach beyond its limit", e.name());
            }
        }
        // a friction's smoothing: the context's, or wider where its slope F/(v_s J) would be
        // faster than the mechanics (0.37/(0.02·0.5) = 37 /s < 400 /s: the context's; 40 N
        // would give 4000 /s: widened to 40/(0.5·400) = 0.2 m/s)
        let f = |size: f64| Effect::vocabulary()[0].of_size(size, &context).values()[1];
        assert_eq!(f(0.37), 0.02);
        assert!((f(40.0) - 0.2).abs() < 1e-15);
    }
}
