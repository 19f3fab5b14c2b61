//! The budgets `cargo xtask embedded` enforces (issue 13) and their verdicts, computed
//! once: the failures of the task and the report's budget line both read them here.
use crate::measure::{Build, Measured};

/// Method 1's floor: 9 multiplications, 6 additions, 3 subtractions per sample.
pub const M1_FLOOR: u64 = 18;
/// Method 1 with the physics terms between the machines' steps: its floor, the offsets
/// (15) and the K2/asymmetry correction (30).
pub const PM1_FLOOR: u64 = M1_FLOOR + 15 + 30;

/// A full table of 8 discovered terms per sample: the 3 magnitudes of the force, then for
/// each term 2 multiplications (its force part), 1 (times its weight) and 1 addition
/// (into its axis's error).
pub const TERMS_FLOOR: u64 = 3 + 8 * 4;
/// Method 1 with the physics terms and a full table of discovered terms: its floor.
pub const TM1_FLOOR: u64 = PM1_FLOOR + TERMS_FLOOR;

/// One budget of a firmware build.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Budget {
    /// Painted stack of blob validation.
    DecodeStack,
    /// Painted stack of `compensate` with a temperature update.
    CompensateStack,
    /// `size_of::<FlashCompensator>`.
    State,
    /// Flash of compensation + blob validation (the library components), built without
    /// `physics`.
    Flash,
    /// The same with `physics` (without `terms`).
    PhysicsFlash,
    /// The same with `physics` and `terms`.
    TermsFlash,
    /// Method 1's net instructions per sample: at most 2.5x its floor.
    Method1,
    /// The physics path's method 1 per sample, between the machines' steps.
    PhysicsSample,
    /// The physics path's temperature machines stepping (once per 0.1 s), the cached
    /// matrices kept.
    PhysicsStep,
    /// The physics path's temperature update: the machines' step and the cached matrices
    /// of the diagnosed blob's table recomputed.
    PhysicsUpdate,
    /// Method 1 per sample with the physics terms and a full table of discovered terms,
    /// between the machines' steps.
    TermsSample,
    /// The machines' step with a full table of discovered terms (their state parts).
    TermsStep,
    /// No soft-double routine linked.
    NoSoftDouble,
}

/// How a build stands against one budget.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Within the limit.
    Met,
    /// Over it.
    Missed,
    /// The run gave no figure to judge (a miss too).
    NotMeasured,
}

impl Verdict {
    /// As the report writes it.
    pub fn word(self) -> &'static str {
        match self {
            Verdict::Met => "met",
            Verdict::Missed | Verdict::NotMeasured => "missed",
        }
    }
}

impl Budget {
    /// Every budget, in the report's order.
    pub const ALL: [Budget; 13] = [
        Budget::DecodeStack,
        Budget::CompensateStack,
        Budget::State,
        Budget::Flash,
        Budget::PhysicsFlash,
        Budget::TermsFlash,
        Budget::Method1,
        Budget::PhysicsSample,
        Budget::PhysicsStep,
        Budget::PhysicsUpdate,
        Budget::TermsSample,
        Budget::TermsStep,
        Budget::NoSoftDouble,
    ];

    /// The limit, in the budget's unit.
    ///
    /// The physics path's: flash 6.875 KiB (the machines, their f32 exponential and the
    /// offsets, 2 KiB over the build without; 6.5 KiB until the zero-lag rate estimator,
    /// its second low-pass, its settling after a power-on and the physics section read
    /// through an offset brought it from 6606 to 6768 bytes; 6.625 KiB until the
    /// hysteresis's play operator, a gradual hysteresis, and its power-on brought it to 7002); per sample no more than the
    /// format-3 path (230); the machines' step at most 600 (three exponentials of about 40
    /// instructions, six divisions, the filters, the direction and the offsets: 464
    /// measured at format 4's introduction, 586 with the zero-lag rate and its settling);
    /// a temperature update at most 3000 (the machines' step and a fifth-order table's 12
    /// polynomials and inverse: 2722 measured).
    pub fn limit(self) -> u64 {
        match self {
            Budget::DecodeStack => 1024,
            Budget::CompensateStack => 512,
            Budget::State => 256,
            Budget::Flash => 6 * 1024,
            Budget::PhysicsFlash => 55 * 128,
            Budget::TermsFlash => TERMS_FLASH,
            Budget::Method1 => M1_FLOOR * 5 / 2,
            Budget::PhysicsSample => 230,
            Budget::PhysicsStep => 600,
            Budget::PhysicsUpdate => 3000,
            Budget::TermsSample => TERMS_SAMPLE,
            Budget::TermsStep => TERMS_STEP,
            Budget::NoSoftDouble => 0,
        }
    }

    /// Whether the budget is for the build `m`: each flash budget for its own build, the
    /// physics path's instructions for both builds with `physics`, the discovered terms'
    /// for the build with `terms`.
    pub fn applies(self, m: &Measured) -> bool {
        match self {
            Budget::Flash => m.build == Build::Core,
            Budget::PhysicsFlash => m.build == Build::Physics,
            Budget::TermsFlash | Budget::TermsSample | Budget::TermsStep => m.build.terms(),
            Budget::PhysicsSample | Budget::PhysicsStep | Budget::PhysicsUpdate => {
                m.build.physics()
            }
            Budget::DecodeStack
            | Budget::CompensateStack
            | Budget::State
            | Budget::Method1
            | Budget::NoSoftDouble => true,
        }
    }

    /// The measured figure (for `NoSoftDouble`, the number of routines linked).
    pub fn measured(self, m: &Measured) -> Option<u64> {
        match self {
            Budget::DecodeStack => m.stack_decode,
            Budget::CompensateStack => m.stack_compensate,
            Budget::State => m.state,
            Budget::Flash | Budget::PhysicsFlash | Budget::TermsFlash => Some(m.library_bytes()),
            Budget::Method1 => m.net("sample_m1"),
            Budget::PhysicsSample => m.net("sample_pm1"),
            Budget::PhysicsStep => m.net("step_pm1"),
            Budget::PhysicsUpdate => m.net("update_pm1"),
            Budget::TermsSample => m.net("sample_tm1"),
            Budget::TermsStep => m.net("step_tm1"),
            Budget::NoSoftDouble => Some(m.soft_double.len() as u64),
        }
    }

    /// Whether `m` meets the budget.
    pub fn verdict(self, m: &Measured) -> Verdict {
        match self.measured(m) {
            Some(v) if v <= self.limit() => Verdict::Met,
            Some(_) => Verdict::Missed,
            None => Verdict::NotMeasured,
        }
    }

    /// What a failure calls it.
    fn failure_name(self) -> &'static str {
        match self {
            Budget::DecodeStack => "decode stack",
            Budget::CompensateStack => "compensate stack",
            Budget::State => "compensator state",
            Budget::Flash => "flash for compensation + blob validation",
            Budget::PhysicsFlash => "flash for compensation + blob validation with physics",
            Budget::TermsFlash => {
                "flash for compensation + blob validation with physics and discovered terms"
            }
            Budget::Method1 => "method 1 per sample (2.5x the floor of 18)",
            Budget::PhysicsSample => "method 1 per sample with the physics terms",
            Budget::PhysicsStep => "the physics terms' step",
            Budget::PhysicsUpdate => "the physics path's temperature update",
            Budget::TermsSample => "method 1 per sample with physics and 8 discovered terms",
            Budget::TermsStep => "the machines' step with 8 discovered terms",
            Budget::NoSoftDouble => "no soft-double routines",
        }
    }

    /// The unit of the figure.
    fn unit(self) -> &'static str {
        match self {
            Budget::Method1
            | Budget::PhysicsSample
            | Budget::PhysicsStep
            | Budget::PhysicsUpdate
            | Budget::TermsSample
            | Budget::TermsStep => "instructions",
            Budget::NoSoftDouble => "routines",
            Budget::DecodeStack
            | Budget::CompensateStack
            | Budget::State
            | Budget::Flash
            | Budget::PhysicsFlash
            | Budget::TermsFlash => "bytes",
        }
    }

    /// The miss of build `build` (`with physics`), if it missed: the budget and build,
    /// and the figure against the limit.
    pub fn miss(self, m: &Measured, build: &str) -> Option<(String, String)> {
        let (unit, limit) = (self.unit(), self.limit());
        let why = match (self, self.verdict(m), self.measured(m)) {
            (_, Verdict::Met, _) => return None,
            (Budget::NoSoftDouble, _, _) => m.soft_double.join(", "),
            (_, _, Some(v)) => format!("{v} {unit} > {limit} {unit}"),
            (_, _, None) => "not measured".to_string(),
        };
        Some((format!("{} ({build})", self.failure_name()), why))
    }

    /// The report's clause: `decode stack 472 bytes (<= 1024: met)`.
    pub fn report(self, m: &Measured) -> String {
        let (limit, verdict) = (self.limit(), self.verdict(m).word());
        let v = self.measured(m).unwrap_or(0);
        match self {
            Budget::DecodeStack => format!("decode stack {v} bytes (<= {limit}: {verdict})"),
            Budget::CompensateStack => {
                format!("compensate stack {v} bytes (<= {limit}: {verdict})")
            }
            Budget::State => format!("compensator state {v} bytes (<= {limit}: {verdict})"),
            Budget::Flash | Budget::PhysicsFlash | Budget::TermsFlash => {
                format!("flash {v} bytes (<= {limit}: {verdict})")
            }
            Budget::Method1 => format!(
                "method 1 {v} instructions per sample (<= {limit}, 2.5x the floor: {verdict})"
            ),
            Budget::PhysicsSample => format!(
                "method 1 with the physics terms {v} instructions per sample (<= {limit}: {verdict})"
            ),
            Budget::PhysicsStep => {
                format!("the physics terms' step {v} instructions (<= {limit}: {verdict})")
            }
            Budget::PhysicsUpdate => format!(
                "the physics path's temperature update {v} instructions (<= {limit}: {verdict})"
            ),
            Budget::TermsSample => format!(
                "method 1 with physics and 8 discovered terms {v} instructions per sample (<= {limit}: {verdict})"
            ),
            Budget::TermsStep => format!(
                "the machines' step with 8 discovered terms {v} instructions (<= {limit}: {verdict})"
            ),
            Budget::NoSoftDouble => format!(
                "soft-double routines: {}",
                if v == 0 {
                    "none (met)"
                } else {
                    "linked (missed)"
                }
            ),
        }
    }
}

/// The flash of compensation + blob validation in the build with `terms`, bytes: 8.75 KiB,
/// the physics build's and the discovered terms' 1.6 KiB (the table's validation where it
/// lies, the factor tables, the state parts with their decays, the per-sample pass;
/// 8382 measured at format 5's introduction; 8.5 KiB until the hysteresis's play
/// operator brought it to 8816).
pub const TERMS_FLASH: u64 = 35 * 256;
/// Method 1 per sample with the physics terms and a full table of 8 discovered terms:
/// the physics path's 199 and about 38 per term (its word read where it lies, 2 + 1
/// multiplications and the addition into its axis; 506 measured), with 10 % room.
pub const TERMS_SAMPLE: u64 = 560;
/// The machines' step with 8 discovered terms' state parts: the physics step's 520 and
/// about 110 per term (its entry read, its state part, an f32 exponential for a decay;
/// 1386 measured with two decays), with 10 % room.
pub const TERMS_STEP: u64 = 1500;

/// Each budget this build misses, named with its measured value.
pub fn missed(m: &Measured, build: &str) -> Vec<(String, String)> {
    Budget::ALL
        .iter()
        .filter(|b| b.applies(m))
        .filter_map(|b| b.miss(m, build))
        .collect()
}

/// The report's clauses of the budgets for build `m`, joined.
pub fn report(m: &Measured) -> String {
    Budget::ALL
        .iter()
        .filter(|b| b.applies(m))
        .map(|b| b.report(m))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn measured() -> Measured {
        Measured {
            build: Build::Core,
            samples: 10,
            departures: Vec::new(),
            sizes: Vec::new(),
            components: vec![("firmware-core compensate".into(), 6084)],
            icount: [("call_overhead", 20), ("sample_m1", 63)]
                .map(|(k, v)| (k.to_string(), v))
                .to_vec(),
            soft_double: Vec::new(),
            stack_decode: Some(472),
            stack_compensate: Some(464),
            state: Some(200),
            blob_view: Some(40),
        }
    }

    #[test]
    fn a_build_within_every_budget_misses_none() {
        let m = measured();
        assert_eq!(missed(&m, "without physics"), []);
        assert_eq!(
            report(&m),
            "decode stack 472 bytes (<= 1024: met), compensate stack 464 bytes (<= 512: met), \
             compensator state 200 bytes (<= 256: met), flash 6084 bytes (<= 6144: met), \
             method 1 43 instructions per sample (<= 45, 2.5x the floor: met), \
             soft-double routines: none (met)"
        );
    }

    #[test]
    fn every_miss_is_named_with_its_figure() {
        let mut m = measured();
        m.stack_decode = None;
        m.stack_compensate = Some(513);
        m.icount[1].1 = 66;
        m.components[0].1 = 6145;
        m.soft_double = vec!["__aeabi_dmul".into()];
        let text: Vec<String> = missed(&m, "without physics")
            .into_iter()
            .map(|(name, why)| format!("{name}: {why}"))
            .collect();
        assert_eq!(
            text,
            [
                "decode stack (without physics): not measured",
                "compensate stack (without physics): 513 bytes > 512 bytes",
                "flash for compensation + blob validation (without physics): 6145 bytes > 6144 bytes",
                "method 1 per sample (2.5x the floor of 18) (without physics): 46 instructions > 45 instructions",
                "no soft-double routines (without physics): __aeabi_dmul",
            ]
        );
        assert_eq!(
            Budget::DecodeStack.report(&m),
            "decode stack 0 bytes (<= 1024: missed)"
        );
        assert_eq!(
            Budget::NoSoftDouble.report(&m),
            "soft-double routines: linked (missed)"
        );
        assert_eq!(Budget::State.verdict(&m), Verdict::Met);
    }

    /// The build with `physics` is held to its own flash limit and to the physics path's
    /// instruction budgets; a physics figure missing is a miss.
    #[test]
    fn the_physics_build_has_its_own_budgets() {
        let mut m = measured();
        m.build = Build::Physics;
        m.components[0].1 = 6600;
        m.icount
            .extend([("sample_pm1", 211), ("step_pm1", 484)].map(|(k, v)| (k.to_string(), v)));
        let text: Vec<String> = missed(&m, "with physics")
            .into_iter()
            .map(|(name, why)| format!("{name}: {why}"))
            .collect();
        assert_eq!(
            text,
            ["the physics path's temperature update (with physics): not measured"]
        );
        assert!(
            report(&m).contains("flash 6600 bytes (<= 7040: met)"),
            "{}",
            report(&m)
        );
        assert!(report(&m)
            .contains("method 1 with the physics terms 191 instructions per sample (<= 230: met)"));
        m.components[0].1 = 7041;
        assert_eq!(Budget::PhysicsFlash.verdict(&m), Verdict::Missed);
        assert!(!Budget::Flash.applies(&m));
        assert!(!Budget::TermsSample.applies(&m));
    }

    /// The build with `terms` is held to its own flash limit, the physics path's budgets
    /// and the discovered terms' per sample and per step; their figures missing are
    /// misses.
    #[test]
    fn the_terms_build_has_its_own_budgets() {
        let mut m = measured();
        m.build = Build::Terms;
        m.components[0].1 = 8300;
        m.icount.extend(
            [
                ("sample_pm1", 219),
                ("step_pm1", 537),
                ("update_pm1", 2802),
                ("sample_tm1", 526),
            ]
            .map(|(k, v)| (k.to_string(), v)),
        );
        let text: Vec<String> = missed(&m, "with physics and terms")
            .into_iter()
            .map(|(name, why)| format!("{name}: {why}"))
            .collect();
        assert_eq!(
            text,
            ["the machines' step with 8 discovered terms (with physics and terms): not measured"]
        );
        assert!(report(&m).contains("flash 8300 bytes (<= 8960: met)"));
        assert!(report(&m).contains(
            "method 1 with physics and 8 discovered terms 506 instructions per sample (<= 560: met)"
        ));
        m.icount.push(("step_tm1".into(), 1521));
        assert_eq!(Budget::TermsStep.verdict(&m), Verdict::Missed);
        assert!(!Budget::PhysicsFlash.applies(&m) && !Budget::Flash.applies(&m));
    }
}
