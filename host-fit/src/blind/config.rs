//! A blind case as a twin configuration: the catalogue's forms here, the others in
//! [`crate::blind::forms`].
use crate::blind::cases::{profile, Case};
use crate::blind::draw::conceal;
use crate::rng::Rng;
use crate::simulate::SimConfig;

/// Conceal the effects of `case` in the profile; returns the config.
pub fn configure(case: &Case) -> SimConfig {
    let mut c = profile(case.tp_only);
    c.seed = case.seed;
    let mut rng = Rng::new(case.seed ^ 0xB11D);
    if let Some(form) = case.form {
        form.apply(case.scale, &mut c, &mut rng);
        return c;
    }
    for e in &case.effects {
        conceal(*e, case.scale, &mut c, &mut rng);
    }
    c
}
