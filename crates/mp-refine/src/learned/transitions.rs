//! Step 4, transition refinement, and the regeneration of transitions that
//! the anchor step uses too: the deviation of a transition from its own
//! least-squares cubic, the batch regeneration by the transition
//! refinement network or the generator ([`TransitionMethod`]), and the
//! writing of the generated cubics (pinned to their anchors, optionally
//! only over the deviating frames).

use nalgebra::{Matrix4, Vector4};
use ndarray::{s, Array2};

use super::{
    check_finite, NetRefiner, RefineMode, TransitionMethod, TransitionReason, TransitionReport,
};
use crate::error::{RefineError, Result};
use crate::motion::{FRAME_FEATURES, MSR_JOINTS, NET_FRAMES};
use crate::nets::{N_COEFFS, TRANSITION_FRAMES};

/// Least-squares cubic (in `s = (f − a)/(b − a)`) of every feature over
/// frames `a..=b` of `x` (`T × 60`), and the largest per-frame mean joint
/// distance between the frames and the cubic (metres). `None` when the
/// span has fewer than 5 frames.
pub fn cubic_deviation(x: &Array2<f64>, a: usize, b: usize) -> Option<f64> {
    if b < a + 4 || b >= x.nrows() {
        return None;
    }
    let len = (b - a) as f64;
    let mut ata = Matrix4::<f64>::zeros();
    let basis = |f: usize| {
        let s = (f - a) as f64 / len;
        Vector4::new(1.0, s, s * s, s * s * s)
    };
    for f in a..=b {
        let v = basis(f);
        ata += v * v.transpose();
    }
    let inv = ata.try_inverse()?;
    let nf = x.ncols();
    let mut coef = vec![Vector4::<f64>::zeros(); nf];
    for f in a..=b {
        let v = basis(f);
        for (k, c) in coef.iter_mut().enumerate() {
            *c += v * x[[f, k]];
        }
    }
    for c in coef.iter_mut() {
        *c = inv * *c;
    }
    let mut worst: f64 = 0.0;
    for f in a..=b {
        let v = basis(f);
        let mut s = 0.0;
        for j in 0..nf / 3 {
            let mut e = 0.0;
            for k in 0..3 {
                let d = x[[f, 3 * j + k]] - coef[3 * j + k].dot(&v);
                e += d * d;
            }
            s += e.sqrt();
        }
        worst = worst.max(s / (nf / 3) as f64);
    }
    Some(worst)
}

/// Evaluates cubic coefficients (`4 × 60`, row k multiplies `s^k`) on frames
/// `a..=b` and writes the frames strictly inside into `x` (`T × 60`); with
/// `pin`, end residuals against `x[a]` and `x[b]` are blended away linearly.
fn write_transition(x: &mut Array2<f64>, coeffs: &[f32], a: usize, b: usize, pin: bool) {
    let nf = FRAME_FEATURES;
    let eval = |k: usize, s: f64| -> f64 {
        let c = |i: usize| coeffs[i * nf + k] as f64;
        ((c(3) * s + c(2)) * s + c(1)) * s + c(0)
    };
    let len = (b - a) as f64;
    for k in 0..nf {
        let (r0, r1) = if pin {
            (x[[a, k]] - eval(k, 0.0), x[[b, k]] - eval(k, 1.0))
        } else {
            (0.0, 0.0)
        };
        for f in a + 1..b {
            let s = (f - a) as f64 / len;
            x[[f, k]] = eval(k, s) + (1.0 - s) * r0 + s * r1;
        }
    }
}

/// Keeps the frames of the regenerated span `a..=b` of `x` that are within
/// `tau` (mean joint distance, metres) of `before` (the span before
/// regeneration): frames over `tau` take the regenerated pose, their direct
/// neighbours half of it, every other frame is restored.
fn blend_deviating(x: &mut Array2<f64>, before: &Array2<f64>, a: usize, b: usize, tau: f64) {
    let n = b - a + 1;
    let over: Vec<bool> = (0..n)
        .map(|i| {
            let mut s = 0.0;
            for j in 0..MSR_JOINTS {
                let mut e = 0.0;
                for k in 0..3 {
                    let d = x[[a + i, 3 * j + k]] - before[[i, 3 * j + k]];
                    e += d * d;
                }
                s += e.sqrt();
            }
            s / MSR_JOINTS as f64 > tau
        })
        .collect();
    for i in 0..n {
        let w = if over[i] {
            1.0
        } else if (i > 0 && over[i - 1]) || (i + 1 < n && over[i + 1]) {
            0.5
        } else {
            0.0
        };
        for k in 0..FRAME_FEATURES {
            x[[a + i, k]] = w * x[[a + i, k]] + (1.0 - w) * before[[i, k]];
        }
    }
}

/// Frames `a..=b` of `x` (`T × 60`) resampled to [`TRANSITION_FRAMES`]
/// frames (linear interpolation, both ends included), appended to `out`.
fn push_resampled(out: &mut Vec<f32>, x: &Array2<f64>, a: usize, b: usize) {
    let len = (b - a) as f64;
    for i in 0..TRANSITION_FRAMES {
        let u = a as f64 + len * i as f64 / (TRANSITION_FRAMES - 1) as f64;
        let f0 = (u.floor() as usize).min(b);
        let f1 = (f0 + 1).min(b);
        let w = u - f0 as f64;
        for k in 0..FRAME_FEATURES {
            out.push(((1.0 - w) * x[[f0, k]] + w * x[[f1, k]]) as f32);
        }
    }
}

impl NetRefiner<'_> {
    /// Step 4: the report of every transition between consecutive
    /// `anchors` of the features `xf` (`60 × 60`), and, with
    /// [`RefineMode::AnchorsAndTransitions`], the regeneration of those
    /// next to a refined anchor (`next_to_refined`) or deviating from their
    /// own cubic.
    pub(super) fn refine_transitions(
        &self,
        xf: &mut Array2<f64>,
        anchors: &[usize],
        next_to_refined: &[bool],
    ) -> Result<Vec<TransitionReport>> {
        let p = self.params;
        let mut transitions: Vec<TransitionReport> = anchors
            .windows(2)
            .enumerate()
            .map(|(t, w)| TransitionReport {
                start: w[0],
                end: w[1],
                source_frames: (0, 0),
                deviation_m: if w[1] - w[0] >= p.min_deviation_frames {
                    cubic_deviation(xf, w[0], w[1])
                } else {
                    None
                },
                refined: if next_to_refined[t] {
                    Some(TransitionReason::NextToRefinedAnchor)
                } else {
                    None
                },
            })
            .collect();
        if p.mode == RefineMode::AnchorsAndTransitions {
            for t in transitions.iter_mut() {
                if t.refined.is_none()
                    && t.deviation_m.is_some_and(|d| d > p.transition_deviation_m)
                {
                    t.refined = Some(TransitionReason::Deviation);
                }
            }
            let tr: Vec<usize> = (0..transitions.len())
                .filter(|&t| transitions[t].refined.is_some())
                .collect();
            let partial: Vec<usize> = tr
                .iter()
                .copied()
                .filter(|&t| transitions[t].refined == Some(TransitionReason::Deviation))
                .collect();
            let whole: Vec<usize> = tr
                .iter()
                .copied()
                .filter(|t| !partial.contains(t))
                .collect();
            self.regenerate(xf, anchors, &whole, p.transition_method, None)?;
            self.regenerate(
                xf,
                anchors,
                &partial,
                p.transition_method,
                p.replace_frames_over_m,
            )?;
        } else {
            // Anchor-only: only the generator-rebuilt neighbours changed.
            for t in transitions.iter_mut() {
                if t.refined == Some(TransitionReason::Deviation) {
                    t.refined = None;
                }
            }
        }
        Ok(transitions)
    }

    /// Regenerates transitions `tr` (indices into consecutive anchor pairs)
    /// of `xf` (`60 × 60`) in one batch.
    pub(super) fn regenerate(
        &self,
        xf: &mut Array2<f64>,
        anchors: &[usize],
        tr: &[usize],
        method: TransitionMethod,
        replace_over_m: Option<f64>,
    ) -> Result<()> {
        let tr: Vec<usize> = tr
            .iter()
            .copied()
            .filter(|&t| anchors[t + 1] >= anchors[t] + 2)
            .collect();
        if tr.is_empty() {
            return Ok(());
        }
        let nb = tr.len();
        let mut aa = Vec::with_capacity(nb * FRAME_FEATURES);
        let mut ab = Vec::with_capacity(nb * FRAME_FEATURES);
        let mut dur = Vec::with_capacity(nb);
        for &t in &tr {
            let (a, b) = (anchors[t], anchors[t + 1]);
            aa.extend(xf.row(a).iter().map(|&v| v as f32));
            ab.extend(xf.row(b).iter().map(|&v| v as f32));
            dur.push((b - a) as f32 / NET_FRAMES as f32);
        }
        let coeffs = match method {
            TransitionMethod::Generator => {
                let z = vec![0f32; nb * self.nets.sizes().transition_latent];
                self.nets.generate_transitions(&aa, &ab, &dur, &z)?
            }
            TransitionMethod::Refinement => {
                let mut input = Vec::with_capacity(nb * TRANSITION_FRAMES * FRAME_FEATURES);
                for &t in &tr {
                    push_resampled(&mut input, xf, anchors[t], anchors[t + 1]);
                }
                self.nets.refine_transitions(&input, &aa, &ab, &dur)?
            }
        };
        check_finite("transition network", &coeffs)?;
        let per = N_COEFFS * FRAME_FEATURES;
        for (bi, &t) in tr.iter().enumerate() {
            let c = coeffs.get(bi * per..(bi + 1) * per).ok_or_else(|| {
                RefineError::Shape(format!(
                    "transition network: no coefficients for transition {bi}"
                ))
            })?;
            let (a, b) = (anchors[t], anchors[t + 1]);
            match replace_over_m {
                None => write_transition(xf, c, a, b, self.params.pin_anchors),
                Some(tau) => {
                    let before = xf.slice(s![a..=b, ..]).to_owned();
                    write_transition(xf, c, a, b, self.params.pin_anchors);
                    blend_deviating(xf, &before, a, b, tau);
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cubic_deviation_is_zero_on_a_cubic_and_sees_a_spike() {
        let mut x = Array2::<f64>::zeros((30, FRAME_FEATURES));
        for f in 0..30 {
            for k in 0..FRAME_FEATURES {
                let s = f as f64 / 29.0;
                x[[f, k]] = 0.1 * k as f64 + s - 2.0 * s * s + 0.5 * s * s * s;
            }
        }
        assert!(cubic_deviation(&x, 0, 29).unwrap() < 1e-9);
        assert!(cubic_deviation(&x, 3, 6).is_none());
        x.row_mut(14).mapv_inplace(|v| v + 0.1);
        let d = cubic_deviation(&x, 0, 29).unwrap();
        // A 0.1 offset on every coordinate is 0.1·√3 per joint; the fit absorbs a little.
        assert!(d > 0.1 && d < 0.1 * 3f64.sqrt(), "{d}");
    }

    #[test]
    fn written_transition_meets_its_anchors() {
        let mut x = Array2::<f64>::zeros((10, FRAME_FEATURES));
        x.row_mut(2).fill(1.0);
        x.row_mut(8).fill(3.0);
        // p(s) = 0.5 + s: ends 0.5 and 1.5, residuals 0.5 and 1.5.
        let mut c = vec![0f32; N_COEFFS * FRAME_FEATURES];
        c[..FRAME_FEATURES].fill(0.5);
        c[FRAME_FEATURES..2 * FRAME_FEATURES].fill(1.0);
        write_transition(&mut x, &c, 2, 8, true);
        // Pinned: linear from 1 to 3.
        for f in 2..=8 {
            let expected = 1.0 + 2.0 * (f - 2) as f64 / 6.0;
            assert!((x[[f, 7]] - expected).abs() < 1e-6, "{f}");
        }
        write_transition(&mut x, &c, 2, 8, false);
        assert!((x[[5, 0]] - 1.0).abs() < 1e-6);
        assert_eq!(x[[2, 0]], 1.0);
        assert_eq!(x[[8, 0]], 3.0);
    }

    #[test]
    fn resampled_transition_has_both_ends() {
        let mut x = Array2::<f64>::zeros((40, FRAME_FEATURES));
        for f in 0..40 {
            x.row_mut(f).fill(f as f64);
        }
        let mut out = Vec::new();
        push_resampled(&mut out, &x, 10, 25);
        assert_eq!(out.len(), TRANSITION_FRAMES * FRAME_FEATURES);
        assert_eq!(out[0], 10.0);
        assert_eq!(out[(TRANSITION_FRAMES - 1) * FRAME_FEATURES], 25.0);
        assert!((out[FRAME_FEATURES] - 11.0).abs() < 1e-6);
    }
}
