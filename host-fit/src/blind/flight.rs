//! Flight-like recordings of the blind suite's units: the same unit and physics on the
//! twin's flight (a cold power-on at -30 C, fast warming and cooling both ways, a second
//! power cycle, 24 attitudes over the sphere at 20 Hz), for the check that a blob
//! diagnosed from the unit's production recording compensates its terms through
//! firmware-core. The flight carries the unit's own state (force products and powers,
//! temperature, its rate, the turn-on transients: what firmware can compensate); the
//! session's and the rig's physics stay on the bench: a drift in time and a turn-on step
//! (the calibration is referred to the recording's start, so the flight is flown in that
//! state), a settling after moves and stops and the tilter's repeatability (no tilter or
//! chamber in flight), fixture errors, and disturbances no model predicts (a walk, a
//! periodic or two-level bias).
use crate::blind::cases::Case;
use crate::blind::config::configure;
use crate::simulate::{Effects, Flight, SimConfig};

/// The flight-like recording of `case`'s unit: its configuration with the twin's default
/// [`Flight`] and the effects of the unit's own state (see the module doc).
pub fn flight_config(case: &Case) -> SimConfig {
    let mut c = configure(case);
    c.effects = unit_state(&c.effects);
    c.flight = Some(Flight::default());
    c
}

/// The effects of `e` that are the unit's own state, the rest off.
pub fn unit_state(e: &Effects) -> Effects {
    Effects {
        // the session: referred to the recording's start
        scale_aging: None,
        bias_aging: None,
        turn_on_bias: None,
        // the rig
        fixture_error: None,
        fixture_error2: None,
        fixture_change: None,
        move_settle: None,
        stop_settle: None,
        tilter_repeatability: None,
        // disturbances no model predicts
        bias_step: None,
        bias_walk: None,
        periodic: None,
        bias_settle: None,
        telegraph: None,
        ..e.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blind::beyond::{Expressed, Plain};
    use crate::blind::forms::Form;
    use crate::simulate::simulate;

    /// A flight of a unit with a temperature-sized warm-up, a scale with the rate and a
    /// cross-coupling differs from the same flight without them (the terms fly), and a
    /// settling after moves stays on the bench.
    #[test]
    fn the_units_terms_fly_and_the_rigs_stay_on_the_bench() {
        let flies = [
            Expressed::WarmupOfTemperature,
            Expressed::ScaleOfRate,
            Expressed::CrossCoupling,
            Expressed::K2OfTemperature,
            Expressed::Cubic,
            Expressed::CrossSquare,
        ];
        let short = |mut c: SimConfig| {
            if let Some(f) = c.flight.as_mut() {
                f.legs.truncate(2);
                f.rate_hz = 2.0;
            }
            c
        };
        for form in flies {
            let c = short(flight_config(&Case::of_form(Form::Expressed(form), 1)));
            let mut bare = c.clone();
            bare.effects = Effects::default();
            let a = simulate(&c, |_| {}).unwrap();
            let b = simulate(&bare, |_| {}).unwrap();
            assert!(a.positions_csv.is_some());
            assert_ne!(a.csv, b.csv, "{}: nothing in flight", form.name());
        }
        for form in [
            Expressed::MoveSettle,
            Expressed::TurnOnStep,
            Expressed::ScaleDrift,
        ] {
            let c = flight_config(&Case::of_form(Form::Expressed(form), 1));
            assert_eq!(c.effects, Effects::default(), "{}", form.name());
        }
        let lag = flight_config(&Case::of_form(Form::Plain(Plain::LagRateTurning), 1));
        assert!(lag.effects.thermal_lag.is_some() && lag.effects.temp_rate.is_some());
    }
}
