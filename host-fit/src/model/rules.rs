//! Every rule and threshold the diagnosis judges by, in one place with the reason for
//! each value (as argmin documents a solver's tuning fields). [`Rules::default`] is what
//! `host-fit diagnose` uses; the blind suite varies them (`blind::run_with`) to show what
//! each rule buys.
use crate::data::stops::WINDOW_SPAN_C;
use firmware_core::temperature::{MAX_BREAKPOINTS, MAX_POLY_ORDER};

/// The diagnosis's rules. Units are in the field names (C, s, C/s); "floor units" are
/// residuals divided by the measured floor's sigma.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rules {
    // --- observations: windows and held-out chunks ---
    /// A window spans at most this much temperature, so a coefficient's temperature
    /// dependence is linear across it (the static fits' windows, the same value).
    pub window_span_c: f64,
    /// ... and at most this much time, so slow physics (a warm-up, a lag) still changes
    /// between windows instead of averaging out inside one.
    pub window_max_s: f64,
    /// Fewer windows than this (6 positions at one temperature) cannot determine the
    /// baseline's per-axis scale, offset and cross terms.
    pub min_windows: usize,
    /// Held-out chunks hold about this many windows each: short enough that the rest of
    /// the recording spans the same temperatures, so a chunk tests the effects, not
    /// extrapolation.
    pub chunk_windows: usize,
    /// At least this many chunks, so a held-out score averages over the recording.
    pub min_chunks: usize,

    // --- the floor (what any model can reach) ---
    /// A sample whose second difference is this many robust sigmas out is a spike: far
    /// beyond Gaussian noise (1 in 10^15), near a logger's glitch.
    pub spike_z: f64,
    /// A time scale of the floor is measured when at least this many second differences
    /// support it: a median of fewer is too uncertain to weight every window by.
    pub floor_min_support: usize,
    /// A piece of a dwell counts as steady when its thirds' mean temperatures differ by
    /// at most this end to end (the second difference removes a linear drift) ...
    pub floor_steady_span_c: f64,
    /// ... and bend by at most this: a settling curve would pass its physics off as noise.
    pub floor_steady_bend_c: f64,
    /// Pieces of this many samples keep the three blocks of a second difference far
    /// apart, so correlated noise between neighbours does not hide.
    pub floor_piece: usize,

    // --- the time series: rates, directions, events ---
    /// The firmware's temperature-rate estimate for locating and for static windows uses
    /// this time constant: a minute smooths the sensor's steps, follows a 1 C/min ramp.
    pub rate_tau_s: f64,
    /// A window moving faster than this is not static: it is left out of the static
    /// |dg| and located as heating or cooling (0.12 C/min, a ramp, not a settling).
    pub steady_rate_c_per_s: f64,
    /// Time-series effects are judged only when some window moves faster than this
    /// (0.012 C/min): below, nothing in the recording changes fast enough to show them.
    pub moving_rate_c_per_s: f64,
    /// A temperature change larger than this sets the heating/cooling direction used to
    /// locate residuals: larger than the sensor's noise and steps, smaller than any stop.
    pub direction_threshold_c: f64,
    /// A window is "after heating" (or cooling) when its mean direction is beyond this
    /// (most of its samples); the recording reverses when both occur.
    pub direction_majority: f64,
    /// A `-` run longer than this is handling (the unit re-mounted), where a warm-up may
    /// restart; shorter runs are a turn between positions.
    pub handling_s: f64,
    /// A time step this many times the median one is a gap (the unit may have been off) ...
    pub gap_factor: f64,
    /// ... and at least this long, so a slow logger's jitter is no gap.
    pub gap_min_s: f64,

    // --- the baseline and its candidates ---
    /// The baseline's polynomial order never exceeds this (the firmware's highest).
    pub max_order: usize,
    /// A fixture error that changes between two stops is looked for in recordings of at
    /// most this many stops (each stop a candidate; more is a sweep, not a tilter test).
    pub max_fixture_stops: usize,
    /// Time constants are profiled on a log grid of this ratio: fine enough that the
    /// golden-section refinement around the best point starts inside the right valley.
    pub grid_ratio: f64,
    /// A warm-up is never longer than this fraction of the recording: a settling must be
    /// seen settling (three time constants: 95 % of it); beyond, it is a drift.
    pub warmup_max_fraction: f64,
    /// `fit`'s dynamic route keeps no thermal lag longer than this fraction of the
    /// recording: a lag is told apart from the temperature model only where the element
    /// is seen catching up with its sensor (three time constants: 95 %); a longer one
    /// holds the element near where the recording started and lets the temperature
    /// model bend to the time instead (a 2-h sweep took a 6-h lag and coefficients of
    /// 30x their size, which the f32 path could not carry).
    pub lag_max_fraction: f64,
    /// Broad temperature curvature: one offset breakpoint per this many C (the stops of a
    /// production test are 25-30 C apart; ramps fill in between).
    pub curvature_step_c: f64,
    /// At most this many breakpoints, in a curvature basis and in the blob's table: the
    /// firmware's table size.
    pub max_breakpoints: usize,
    /// The blob's table of the diagnosed model has one point per this many C (at most
    /// [`Rules::max_breakpoints`]): the firmware interpolates linearly between them, so
    /// closer points follow a curved model more closely.
    pub table_step_c: f64,

    // --- acceptance of an effect (all in the dispersion of the larger model) ---
    /// A candidate must lower the quasi-BIC by more than this: odds of e^5 (about 150:1)
    /// that it is not noise.
    pub q_margin: f64,
    /// Two candidates within this much quasi-BIC explain the data equally well: odds of
    /// e^3 (20:1) or less between them is no reason to name one.
    pub ambiguity_margin: f64,
    /// Per round, at most this many of the best-ranked candidates are fitted in full and
    /// judged (each full fit refits every held-out chunk); one ranked lower stays open
    /// for a later round.
    pub judged_per_round: usize,
    /// A candidate must explain at least this share of the chi-square above the floor:
    /// a small improvement of a model far from the data is not a finding.
    pub material_share: f64,
    /// One of the effect's parameters must be this many (scaled) sigmas from zero:
    /// significant after the dispersion and the HAC errors, across several tries.
    pub z_significant: f64,
    /// The held-out chunks must improve by more than this per added parameter (floor
    /// units, in the larger model's dispersion): a parameter that only fits noise makes
    /// held-out data worse by about one, so a gain of two is improvement, not luck.
    pub heldout_gain: f64,
    /// A chunk is an extrapolation, not a test, when its held-out chi-square is more than
    /// this many times its in-sample one (plus one per row): the rest of the data does
    /// not determine the model there (the only dwells at an end temperature, say).
    pub extrapolation: f64,
    /// A profiled time constant is determined when its 1-sigma is within a factor
    /// e^this: a flat profile means the form is not what the data show.
    pub tau_determined_ln: f64,
    /// A bend's place is determined when its 1-sigma is within this many C.
    pub bend_determined_c: f64,
    /// The profile's curvature of a time constant is taken over this ratio either side.
    pub tau_profile_step: f64,
    /// ... and of a bend over this many C either side.
    pub bend_profile_step_c: f64,
    /// Where an effect acts (its contribution above this many floor sigmas) ...
    pub acts_sigmas: f64,
    /// ... the final residual must be at most this fraction of the residual without it
    /// (RMS), or at the floor: an effect that only dents a misfit does not explain it.
    pub adequate_ratio: f64,
    /// A residual RMS at or below this (floor units) is at the floor: room for the floor's
    /// own uncertainty (a robust estimate from the steady stretches) and for windows
    /// whose noise is less white than the floor's model of it.
    pub at_floor_rms: f64,
    /// On each half of the recording (alternate chunks) the effect's amplitude must lie
    /// within this range of the joint fit's, [`Rules::z_significant`] sigmas from zero,
    /// to count as reproduced: the same sign and a similar size on data fitted apart.
    pub reproduced_amplitude: (f64, f64),

    // --- the re-search where the rest is located ---
    /// After the forward search, the worst this many located groups of the joint
    /// model's residual are looked at again (each a position, an axis, a time span ...):
    /// enough to reach a small effect's group past the large one's leftovers.
    pub research_groups: usize,
    /// At most this many re-searches (each adds at most one effect): the catalogue's
    /// effects in a realistic mixture, with room for one the checks drop.
    pub research_rounds: usize,

    // --- the library of discovered terms (after the catalogue) ---
    /// A library column counts as identified when at least this share of its (weighted)
    /// norm is left after the model's columns are projected out: below, the design
    /// cannot tell it from the model (a_x*a_y at six one-axis positions is zero).
    pub identifiable_share: f64,
    /// Two library columns whose projected correlation is at least this are one column
    /// to this design (a_x^2 and |a_x| at one-axis positions): a set, not a choice.
    pub equivalent_correlation: f64,
    /// The best this many library columns (by the chi-square each removes alone) go on
    /// to the resampled selection: far more than a residual's few real terms.
    pub discover_screened: usize,
    /// Bootstrap resamples of the time chunks for the selection's stability.
    pub discover_bags: usize,
    /// A term must be chosen in at least this share of the resamples (stability
    /// selection's usual 0.6-0.9): a term that comes and goes with the chunks drawn is
    /// not one the data determine.
    pub discover_inclusion: f64,
    /// At most this many terms per resample's selection, and per recording: a residual
    /// that needs more is not explained by a short sum of terms.
    pub discover_max_terms: usize,
    /// The resamples' seed: the same recording gives the same diagnosis.
    pub discover_seed: u64,

    // --- locating ---
    /// A group is located when its RMS is above this many floor sigmas ...
    pub located_sigmas: f64,
    /// ... and it carries at least this share of the whole sum of squares (a group of
    /// two windows can be extreme and still not be where the mismatch is).
    pub located_share: f64,

    // --- notes on the data ---
    /// A window mean scattering this many times what white noise predicts is noted as
    /// time-correlated noise.
    pub colour_note: f64,
    /// The sensor and the chamber are compared over steady spans this long (ten minutes
    /// at a steady temperature: both have settled) ...
    pub chamber_hold_s: f64,
    /// ... where both stay within this much temperature.
    pub chamber_steady_c: f64,
    /// A steady sensor-vs-chamber offset (or its spread across soaks) beyond this is
    /// noted: more than a class B Pt100's tolerance near room temperature (0.3-0.4 C).
    pub chamber_note_c: f64,
}

impl Default for Rules {
    fn default() -> Self {
        Rules {
            window_span_c: WINDOW_SPAN_C,
            window_max_s: 300.0,
            min_windows: 6,
            chunk_windows: 40,
            min_chunks: 8,
            spike_z: 8.0,
            floor_min_support: 12,
            floor_steady_span_c: 1.0,
            floor_steady_bend_c: 0.02,
            floor_piece: 120,
            rate_tau_s: 60.0,
            steady_rate_c_per_s: 0.002,
            moving_rate_c_per_s: 2e-4,
            direction_threshold_c: 0.5,
            direction_majority: 0.5,
            handling_s: 120.0,
            gap_factor: 10.0,
            gap_min_s: 60.0,
            max_order: MAX_POLY_ORDER,
            max_fixture_stops: 12,
            grid_ratio: 1.7,
            warmup_max_fraction: 1.0 / 3.0,
            lag_max_fraction: 1.0 / 3.0,
            curvature_step_c: 4.0,
            max_breakpoints: MAX_BREAKPOINTS,
            table_step_c: 2.0,
            q_margin: 10.0,
            ambiguity_margin: 6.0,
            judged_per_round: 6,
            material_share: 0.2,
            z_significant: 4.0,
            heldout_gain: 2.0,
            extrapolation: 10.0,
            tau_determined_ln: 0.5,
            bend_determined_c: 5.0,
            tau_profile_step: 1.2,
            bend_profile_step_c: 1.0,
            acts_sigmas: 2.0,
            adequate_ratio: 0.5,
            at_floor_rms: 1.5,
            reproduced_amplitude: (0.5, 1.5),
            research_groups: 4,
            research_rounds: 4,
            identifiable_share: 1e-4,
            equivalent_correlation: 0.995,
            discover_screened: 24,
            discover_bags: 24,
            discover_inclusion: 0.6,
            discover_max_terms: 4,
            discover_seed: 0x5EED_D15C,
            located_sigmas: 2.0,
            located_share: 0.01,
            colour_note: 2.0,
            chamber_hold_s: 600.0,
            chamber_steady_c: 0.2,
            chamber_note_c: 1.0,
        }
    }
}
