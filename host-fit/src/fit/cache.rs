//! The firmware cache's step for a model of the static, joint or per-stop route: the
//! largest whose cost stays within a verification dwell's own noise as the fit predicts
//! it ([`crate::model::cache::Cache::choose`] over that floor).
use crate::data::recording::Recording;
use crate::fit::noise::Noise;
use crate::fit::pipeline::FitOutcome;
use crate::fit::predict::{directions, sigma_dwell_noise};
use crate::fit::temperature::ModelFit;
use crate::model::cache::Cache;
use firmware_core::temperature::Calibration;

/// A fitted model of a recording, as the cache's floor needs it.
#[derive(Debug, Clone, Copy)]
pub struct Model<'a> {
    /// The recording.
    pub rec: &'a Recording,
    /// Its positions, every pose with a vector (the estimated ones where unknown).
    pub positions: &'a crate::data::positions::Positions,
    /// The model.
    pub fit: &'a ModelFit,
    /// Its noise.
    pub noise: &'a Noise,
}

impl Cache {
    /// The cache of a fitted model's calibration (`fit`, `batch`): `given`
    /// (`--update-step`), or chosen within a verification dwell's own noise as the fit
    /// predicts it ([`Cache::for_model`], with the poses it estimated); `cal` takes the
    /// step.
    pub fn for_fit(
        rec: &Recording,
        oc: &FitOutcome,
        cal: &mut Calibration<f64>,
        given: Option<f64>,
    ) -> Cache {
        // the estimated poses' vectors, carried with the fit
        let positions = oc
            .orientation
            .as_ref()
            .map_or(&rec.positions, |o| &o.positions);
        let model = Model {
            rec,
            positions,
            fit: &oc.fit,
            noise: &oc.noise,
        };
        Cache::for_model(&model, cal, given)
    }

    /// [`Cache::choose`] for the model `fit` of `rec`: the floor is the noise a
    /// verification dwell of the recording's median length adds of its own (1 sigma,
    /// worst of its verification directions, as `fit` predicts it); `cal` takes the step.
    pub fn for_model(m: &Model, cal: &mut Calibration<f64>, given: Option<f64>) -> Cache {
        let (fit, noise) = (m.fit, m.noise);
        let floor = (!fit.axis_cov.is_empty()).then(|| {
            let (dirs, n) = directions(m.rec, m.positions);
            dirs.iter()
                .map(|d| sigma_dwell_noise(fit, noise, fit.t0_c, d.a, n))
                .fold(0.0, f64::max)
                * 1e3
        });
        let cache = Cache::choose(cal, floor, given);
        cal.update_step_c = cache.step_c;
        cache
    }
}
