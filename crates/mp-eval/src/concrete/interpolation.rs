//! The interpolation experiment: keep every `step`-th frame, synthesise a
//! program on the kept frames, execute it at the original rate and compare
//! the dropped frames with the truth, against linear interpolation between
//! the kept frames and against the in-between poses `mp interpolate` warps
//! to ([`mp_concrete::InBetweenPoses`] with the default rule).
//!
//! Only dropped frames up to the last kept frame are scored (both methods
//! interpolate there; neither extrapolates), and only observed
//! (confidence > `min_confidence`) joints.
//!
//! The fit error of a segment is a sum over its frames, so on a track kept
//! every `step` frames the same λ would buy `step` times longer segments.
//! With [`InterpolationExperiment::lambda_per_time`] (default) λ (fixed, or the
//! adaptive clamps) is divided by `step`, which keeps the trade-off between
//! error and number of segments per second of motion.

use mp_geom::Track;
use serde::{Deserialize, Serialize};

use mp_concrete::{InBetween, InBetweenPoses, Lambda, Program, SynthParams, Transition};

/// Parameters of [`interpolation_experiment`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InterpolationExperiment {
    /// Keep every `step`-th frame (≥ 2).
    pub step: usize,
    /// Synthesis on the kept frames.
    pub synth: SynthParams,
    /// Between-segment behaviour when executing.
    pub transition: Transition,
    /// Divide λ by `step` (see the module docs). Default true.
    pub lambda_per_time: bool,
}

impl InterpolationExperiment {
    /// Defaults for one factor: default synthesis, blend, λ per time.
    pub fn new(step: usize) -> Self {
        InterpolationExperiment {
            step,
            synth: SynthParams::paper(),
            transition: Transition::Blend,
            lambda_per_time: true,
        }
    }
}

/// Result of [`interpolation_experiment`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InterpolationResult {
    /// Subsampling factor.
    pub step: usize,
    /// Number of (dropped frame, joint) entries scored.
    pub n_scored: usize,
    /// Segments of the program fitted on the kept frames.
    pub n_segments: usize,
    /// Mean distance of the program's positions to the truth (track units).
    pub kd_program: f64,
    /// Mean distance of linear interpolation to the truth (track units).
    pub kd_linear: f64,
    /// Mean distance of the in-between poses `mp interpolate` warps to
    /// ([`InBetweenPoses`] with [`InBetween::default`], on the kept frames
    /// and this program) to the truth; where neither kept frame around a
    /// dropped one sees the joint, the linear interpolation across the gap.
    #[serde(default)]
    pub kd_inbetween: f64,
}

/// Runs the experiment for one track and one factor (`step ≥ 2`).
///
/// Errors when fewer than 2 frames are kept or nothing can be scored.
pub fn interpolation_experiment(
    track: &Track,
    ip: &InterpolationExperiment,
) -> anyhow::Result<InterpolationResult> {
    let step = ip.step;
    let transition = ip.transition;
    if step < 2 {
        anyhow::bail!("step must be ≥ 2, got {step}");
    }
    let kept = track.subsample(step)?;
    let n_kept = kept.n_frames();
    if n_kept < 2 {
        anyhow::bail!(
            "{} frames subsampled ×{step} leave {n_kept} frame; need at least 2",
            track.n_frames()
        );
    }
    let mut params = ip.synth.clone();
    if ip.lambda_per_time {
        let k = step as f64;
        params.lambda = match params.lambda {
            Lambda::Fixed { lambda_ref } => Lambda::Fixed {
                lambda_ref: lambda_ref / k,
            },
            // A budget is a share of the (kept) frames' numbers already.
            Lambda::Budget { ratio } => Lambda::Budget { ratio },
            // (A spread's `seconds` stay seconds: the kept track's rate is
            // divided by the factor.)
            // Adaptive and spread rules (any later one: unchanged).
            rule => rule.map_window_clamp(|w, lo, hi| (w.div_ceil(step).max(1), lo / k, hi / k)),
        };
    }
    let program = Program::synthesize(&kept, &params)?;
    let last = (n_kept - 1) * step;
    let dropped: Vec<usize> = (0..=last).filter(|f| f % step != 0).collect();
    let frames: Vec<f64> = dropped.iter().map(|&f| f as f64 / step as f64).collect();
    let exec = program.sample_frames(&frames, transition)?;
    let tween = InBetweenPoses::new(
        &kept,
        Some(&program),
        InBetween::default(),
        params.min_confidence,
    )?;
    let mut between = Vec::with_capacity(dropped.len());
    for &f in &dropped {
        between.push(
            tween
                .pose(f / step, (f % step) as f64 / step as f64)?
                .unwrap_or_default(),
        );
    }

    // Linear interpolation between kept frames where the joint is observed.
    let (j, d) = (track.n_joints(), track.dims());
    let pos = track.positions();
    let conf = track.confidence();
    let min_conf = params.min_confidence;
    let (mut sum_p, mut sum_l, mut sum_b, mut n) = (0.0, 0.0, 0.0, 0usize);
    for ji in 0..j {
        let valid: Vec<usize> = (0..n_kept)
            .map(|i| i * step)
            .filter(|&f| conf[[f, ji]] > min_conf)
            .collect();
        if valid.is_empty() {
            continue;
        }
        for (row, &f) in dropped.iter().enumerate() {
            if conf[[f, ji]] <= min_conf {
                continue;
            }
            let Some((a, b, w)) = mp_geom::bracket(&valid, f) else {
                continue;
            };
            let tw = between[row].get(ji).and_then(|p| p.as_ref());
            let (mut ep, mut el, mut eb) = (0.0, 0.0, 0.0);
            for k in 0..d {
                let truth = pos[[f, ji, k]];
                let lin = (1.0 - w) * pos[[a, ji, k]] + w * pos[[b, ji, k]];
                let e1 = exec[[row, ji, k]] - truth;
                let e2 = lin - truth;
                let e3 = tw.map_or(lin, |p| p[k]) - truth;
                ep += e1 * e1;
                el += e2 * e2;
                eb += e3 * e3;
            }
            sum_p += ep.sqrt();
            sum_l += el.sqrt();
            sum_b += eb.sqrt();
            n += 1;
        }
    }
    if n == 0 {
        anyhow::bail!("no observed keypoint among the frames dropped by ×{step} subsampling");
    }
    Ok(InterpolationResult {
        step,
        n_scored: n,
        n_segments: program.n_segments(),
        kd_program: sum_p / n as f64,
        kd_linear: sum_l / n as f64,
        kd_inbetween: sum_b / n as f64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use mp_concrete::{Program, Scale, Segment};
    use mp_geom::{Primitive, Units};

    fn arc(cx: f64, cy: f64, r: f64, start: f64, vel: f64) -> Primitive {
        Primitive::Circle {
            center: vec![cx, cy],
            radius: r,
            angle_start: start,
            angle_vel: vel,
            angle_acc: 0.0,
            axes: vec![],
        }
    }

    fn params_px() -> SynthParams {
        SynthParams {
            scale: Scale::UnitScale { unit_scale: 1.0 },
            lambda: Lambda::fixed(300.0),
            continuity: mp_concrete::Continuity::None,
            ..SynthParams::paper()
        }
    }

    #[test]
    fn interpolation_beats_linear_on_circles() {
        // A joint going round a circle: the program interpolates along the arc.
        let p = Program {
            fps: 30.0,
            units: Units::Pixels,
            dims: 2,
            skeleton: "generic".into(),
            joints: vec!["a".into()],
            continuity: mp_concrete::Continuity::None,
            segments: vec![Segment {
                duration_frames: 41,
                primitives: vec![arc(200.0, 200.0, 80.0, 0.0, 4.0)],
            }],
        };
        let track = p.execute().unwrap();
        for step in [2, 4, 8] {
            let ip = InterpolationExperiment {
                synth: params_px(),
                ..InterpolationExperiment::new(step)
            };
            let r = interpolation_experiment(&track, &ip).unwrap();
            assert_eq!(r.n_scored, 40 - 40 / step);
            assert!(r.kd_program < 1e-6, "×{step}: {r:?}");
            assert!(r.kd_linear > 0.01, "×{step}: {r:?}");
            // The in-between poses (a spline through the kept poses) follow the
            // arc too, except over the first and last kept intervals, where a
            // neighbour is missing and the velocity is the chord's.
            assert!(r.kd_inbetween < 0.6 * r.kd_linear, "×{step}: {r:?}");
        }
        assert!(interpolation_experiment(&track, &InterpolationExperiment::new(1)).is_err());
        assert!(interpolation_experiment(&track, &InterpolationExperiment::new(41)).is_err());
    }
}
