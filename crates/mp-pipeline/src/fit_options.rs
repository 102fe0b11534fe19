//! The options of `mp fit`, the Python `fit` and `cargo xtask eval
//! concrete`: one type that each of them maps its arguments to, so the
//! three read them the same way.

use mp_concrete::{Continuity, Lambda, RefitNorm, UnobservedJoints};
use mp_geom::PrimitiveKind;
use serde::{Deserialize, Serialize};

use crate::error::{PipelineError, Result};
use crate::params::Params;

/// Changes to the product's synthesis ([`Params::default`]): each field left
/// at `None` (or `false`) keeps the default.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FitOptions {
    /// A fixed λ at the 512-pixel reference scale (the first paper's setting).
    pub lambda: Option<f64>,
    /// At most this fraction of the track's numbers `T·J·D` in the program.
    pub budget: Option<f64>,
    /// λ from the local spread of the keypoints held for this many seconds.
    pub lambda_spread: Option<f64>,
    /// Longest segment, frames.
    pub max_segment_frames: Option<usize>,
    /// Whether consecutive segments share their boundary pose.
    pub continuity: Option<Continuity>,
    /// What the C0 refit minimises.
    pub refit_norm: Option<RefitNorm>,
    /// The primitive kinds a segment may use.
    pub kinds: Option<Vec<PrimitiveKind>>,
    /// Circles with an angular acceleration.
    pub quadratic_angle: bool,
    /// Refuse a track with a joint that is never observed (the default fits
    /// it to its stored positions).
    pub strict_joints: bool,
}

impl FitOptions {
    /// Applies the options to `params` and checks the result. At most one
    /// of `lambda`, `budget` and `lambda_spread` may be given.
    pub fn apply(&self, params: &mut Params) -> Result<()> {
        let rules = [
            self.lambda.is_some(),
            self.budget.is_some(),
            self.lambda_spread.is_some(),
        ];
        if rules.iter().filter(|&&r| r).count() > 1 {
            return Err(PipelineError::param(
                "lambda",
                "give at most one of lambda, budget and lambda_spread",
            ));
        }
        let synth = &mut params.analysis.synth;
        if let Some(l) = self.lambda {
            synth.lambda = Lambda::fixed(l);
        }
        if let Some(b) = self.budget {
            synth.lambda = Lambda::budget(b);
        }
        if let Some(s) = self.lambda_spread {
            synth.lambda = Lambda::spread(s);
        }
        if let Some(w) = self.max_segment_frames {
            synth.max_segment_frames = w;
        }
        if let Some(c) = self.continuity {
            synth.continuity = c;
        }
        if let Some(n) = self.refit_norm {
            synth.refit_norm = n;
        }
        if let Some(k) = &self.kinds {
            synth.fit.kinds = k.clone();
        }
        synth.fit.quadratic_angle |= self.quadratic_angle;
        if self.strict_joints {
            synth.unobserved_joints = UnobservedJoints::Error;
        }
        params.validate()
    }

    /// The product's parameters with these options.
    pub fn params(&self) -> Result<Params> {
        let mut p = Params::default();
        self.apply(&mut p)?;
        Ok(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_change_only_what_they_name_and_one_lambda_rule_at_most() {
        assert_eq!(FitOptions::default().params().unwrap(), Params::default());
        let p = FitOptions {
            lambda: Some(800.0),
            max_segment_frames: Some(30),
            kinds: Some(vec![PrimitiveKind::Stationary, PrimitiveKind::Line]),
            strict_joints: true,
            ..FitOptions::default()
        }
        .params()
        .unwrap();
        assert_eq!(p.analysis.synth.lambda, Lambda::fixed(800.0));
        assert_eq!(p.analysis.synth.max_segment_frames, 30);
        assert_eq!(p.analysis.synth.fit.kinds.len(), 2);
        assert_eq!(p.analysis.synth.unobserved_joints, UnobservedJoints::Error);
        assert_eq!(
            p.analysis.synth.continuity,
            Params::default().analysis.synth.continuity
        );
        let e = FitOptions {
            lambda: Some(800.0),
            budget: Some(0.1),
            ..FitOptions::default()
        }
        .params()
        .unwrap_err();
        assert!(e.to_string().contains("at most one"), "{e}");
        let e = FitOptions {
            max_segment_frames: Some(0),
            ..FitOptions::default()
        }
        .params()
        .unwrap_err();
        assert!(e.to_string().contains("max_segment_frames"), "{e}");
    }
}
