//! Execution of abstract programs: deterministic (means) or stochastic
//! (seeded sampling), through the best-fitting concrete primitive.
//!
//! To execute an abstract primitive with duration `d` and points
//! `start, mid, end` for a joint, the three points are placed at
//! `t = 0, (d−1)/2, d−1`, the quadratic through them is sampled at every frame,
//! and the best concrete primitive ([`mp_geom::fit_best`]) is fitted to
//! those samples and executed (paper §3: "pick the concrete primitive c that
//! best fits the sample, and then execute c").

use nalgebra::{DMatrix, DVector};
use ndarray::{Array2, Array3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use serde::{Deserialize, Serialize};

use mp_geom::{fit_best, FitParams};
use mp_geom::{Primitive, Skeleton, Track, Units};

use crate::error::{AbstractError, Result};
use crate::model::{AbstractProgram, DetPrim, Gaussian, Loop, ProbPrim, Stmt};

/// How loops are executed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[non_exhaustive]
pub enum LoopReplay {
    /// Every iteration executes the body's means (mean duration, rounded).
    #[default]
    Mean,
    /// Recorded iterations are replayed as observed; iterations beyond the
    /// recorded ones use the means.
    Observed,
}

/// Parameters of execution.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AbstractExecParams {
    /// Fitting parameters for choosing the concrete primitive (their `unit_scale` should match the track's).
    pub fit: FitParams,
    /// Loop replay mode for deterministic execution.
    pub replay: LoopReplay,
    /// Covariance jitter added to the diagonal before sampling (in squared units), so that
    /// singular covariances (few iterations) can be sampled. Finite and ≥ 0. Default 1e-9.
    pub jitter: f64,
}

impl Default for AbstractExecParams {
    fn default() -> Self {
        AbstractExecParams {
            fit: FitParams::default(),
            replay: LoopReplay::Mean,
            jitter: 1e-9,
        }
    }
}

impl AbstractExecParams {
    /// Checks every field: the fit parameters ([`FitParams::validate`]; their
    /// `unit_scale` is not checked since execution uses the program's) and
    /// `jitter` finite and ≥ 0.
    pub fn validate(&self) -> Result<()> {
        FitParams {
            unit_scale: 1.0,
            ..self.fit.clone()
        }
        .validate()?;
        AbstractError::check_non_negative("jitter", self.jitter)
    }
}

/// Concrete primitive for one joint of a deterministic abstract primitive.
pub(crate) fn concretize(
    points: &[f64],
    duration: usize,
    dims: usize,
    fit: &FitParams,
) -> Result<Primitive> {
    if points.len() != 3 * dims {
        return Err(AbstractError::Shape(format!(
            "expected {} values, got {}",
            3 * dims,
            points.len()
        )));
    }
    let (s, m, e) = (
        &points[..dims],
        &points[dims..2 * dims],
        &points[2 * dims..],
    );
    if duration <= 2 {
        // Too short for a curve: a line from start to end (or a point).
        let velocity = if duration == 2 {
            (0..dims).map(|k| e[k] - s[k]).collect()
        } else {
            vec![0.0; dims]
        };
        return Ok(Primitive::Line {
            start: s.to_vec(),
            velocity,
        });
    }
    let last = (duration - 1) as f64;
    let tm = last / 2.0;
    // Quadratic through (0, s), (tm, m), (last, e) per axis (Lagrange form).
    let mut samples = Array2::zeros((duration, dims));
    for t in 0..duration {
        let x = t as f64;
        let l0 = (x - tm) * (x - last) / ((0.0 - tm) * (0.0 - last));
        let l1 = x * (x - last) / (tm * (tm - last));
        let l2 = x * (x - tm) / (last * (last - tm));
        for k in 0..dims {
            samples[[t, k]] = l0 * s[k] + l1 * m[k] + l2 * e[k];
        }
    }
    Ok(fit_best(samples.view(), None, fit)?.primitive)
}

/// Draws one sample of a Gaussian (Cholesky with jitter; falls back to the
/// diagonal when the covariance is not positive definite).
pub(crate) fn sample_gaussian(g: &Gaussian, rng: &mut ChaCha8Rng, jitter: f64) -> Result<Vec<f64>> {
    g.validate("Gaussian")?;
    let n = g.dim();
    let mut cov = DMatrix::from_row_slice(n, n, &g.cov);
    for i in 0..n {
        cov[(i, i)] += jitter;
    }
    let z = DVector::from_iterator(n, (0..n).map(|_| rng.sample::<f64, _>(StandardNormal)));
    let l = match cov.clone().cholesky() {
        Some(c) => c.l(),
        None => DMatrix::from_diagonal(&DVector::from_iterator(
            n,
            (0..n).map(|i| cov[(i, i)].max(0.0).sqrt()),
        )),
    };
    let x = l * z;
    Ok(g.mean.iter().zip(x.iter()).map(|(m, d)| m + d).collect())
}

fn mean_prim(p: &ProbPrim) -> Result<DetPrim> {
    let duration = p
        .duration
        .mean_rounded()
        .ok_or_else(|| AbstractError::InvalidLoop("empty duration distribution".into()))?;
    Ok(DetPrim {
        duration,
        points: p.joints.iter().map(|g| g.mean.clone()).collect(),
    })
}

fn sample_prim(p: &ProbPrim, rng: &mut ChaCha8Rng, jitter: f64) -> Result<DetPrim> {
    let u: f64 = rng.random();
    let duration = p
        .duration
        .sample_with(u)
        .ok_or_else(|| AbstractError::InvalidLoop("empty duration distribution".into()))?;
    let points = p
        .joints
        .iter()
        .map(|g| sample_gaussian(g, rng, jitter))
        .collect::<Result<Vec<_>>>()?;
    Ok(DetPrim { duration, points })
}

/// Unrolls a loop into deterministic primitives.
pub(crate) fn unroll_loop(l: &Loop, replay: LoopReplay) -> Result<Vec<DetPrim>> {
    let mut out = Vec::new();
    for it in 0..l.iterations {
        match (replay, l.observed.get(it)) {
            (LoopReplay::Observed, Some(obs)) => out.extend(obs.iter().cloned()),
            _ => {
                for b in &l.body {
                    out.push(mean_prim(b)?);
                }
            }
        }
    }
    Ok(out)
}

/// The deterministic primitive sequence of a program.
pub fn flatten(prog: &AbstractProgram, replay: LoopReplay) -> Result<Vec<DetPrim>> {
    let mut out = Vec::new();
    for s in &prog.stmts {
        match s {
            Stmt::Prim(p) => out.push(p.clone()),
            Stmt::Loop(l) => out.extend(unroll_loop(l, replay)?),
        }
    }
    Ok(out)
}

/// The primitive sequence of one stochastic execution.
pub fn flatten_sampled(prog: &AbstractProgram, seed: u64, jitter: f64) -> Result<Vec<DetPrim>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::new();
    for s in &prog.stmts {
        match s {
            Stmt::Prim(p) => out.push(p.clone()),
            Stmt::Loop(l) => {
                for _ in 0..l.iterations {
                    for b in &l.body {
                        out.push(sample_prim(b, &mut rng, jitter)?);
                    }
                }
            }
        }
    }
    Ok(out)
}

/// Skeleton for the given joint names: a built-in one when the names match, else a named custom skeleton.
pub fn skeleton_for(joints: &[String]) -> Skeleton {
    for s in [
        Skeleton::coco17(),
        Skeleton::blazepose33(),
        Skeleton::penn13(),
        Skeleton::msr20(),
    ] {
        if s.joints == joints {
            return s;
        }
    }
    Skeleton::custom("custom", joints.to_vec(), Vec::new(), None)
}

/// Renders deterministic primitives to a track (one frame per duration unit).
pub fn render(prims: &[DetPrim], prog: &AbstractProgram, fit: &FitParams) -> Result<Track> {
    let total: usize = prims.iter().map(|p| p.duration).sum();
    if total == 0 {
        return Err(AbstractError::Empty(
            "the program executes to zero frames".into(),
        ));
    }
    let j = prog.joints.len();
    let d = prog.dims;
    let mut pos = Array3::zeros((total, j, d));
    let mut t0 = 0;
    let mut buf = vec![0.0; d];
    for p in prims {
        for (ji, pts) in p.points.iter().enumerate() {
            let c = concretize(pts, p.duration, d, fit)?;
            for t in 0..p.duration {
                c.eval_into(t as f64, &mut buf);
                for k in 0..d {
                    pos[[t0 + t, ji, k]] = buf[k];
                }
            }
        }
        t0 += p.duration;
    }
    let units = Units::parse(&prog.units)?;
    Ok(Track::new(
        pos,
        None,
        prog.fps,
        units,
        skeleton_for(&prog.joints),
    )?)
}

/// The fit parameters of `params` at the program's scale.
pub(crate) fn fit_for(prog: &AbstractProgram, params: &AbstractExecParams) -> FitParams {
    FitParams {
        unit_scale: prog.unit_scale,
        ..params.fit.clone()
    }
}

/// Upper bound of the frames one execution of `prog` produces, computed in
/// `f64` without unrolling (absurd iteration counts cannot overflow):
/// deterministic execution with `replay` when `sampled` is false, else the
/// longest duration of each body primitive's distribution.
pub fn output_frames_bound(prog: &AbstractProgram, replay: LoopReplay, sampled: bool) -> f64 {
    let body_frames = |l: &Loop| -> f64 {
        l.body
            .iter()
            .map(|b| {
                let d = if sampled {
                    b.duration.counts.keys().next_back().copied()
                } else {
                    b.duration.mean_rounded()
                };
                d.unwrap_or(1) as f64
            })
            .sum()
    };
    prog.stmts
        .iter()
        .map(|s| match s {
            Stmt::Prim(p) => p.duration as f64,
            Stmt::Loop(l) => {
                let per_iter = body_frames(l);
                if !sampled && replay == LoopReplay::Observed {
                    let n_obs = l.observed.len().min(l.iterations);
                    let obs: f64 = l.observed[..n_obs]
                        .iter()
                        .flatten()
                        .map(|p| p.duration as f64)
                        .sum();
                    obs + (l.iterations - n_obs) as f64 * per_iter
                } else {
                    l.iterations as f64 * per_iter
                }
            }
        })
        .sum()
}

/// Checks that `frames` output frames fit
/// [`mp_concrete::ExecParams::max_output_frames`] for the program's joints. The error
/// names `iterations` (the largest iteration count) when the program has
/// loops, else `frames`.
pub fn check_output_frames(prog: &AbstractProgram, frames: f64) -> Result<usize> {
    let most_iterations = prog
        .stmts
        .iter()
        .filter_map(|s| match s {
            Stmt::Loop(l) => Some(l.iterations),
            Stmt::Prim(_) => None,
        })
        .max();
    let j = prog.joints.len();
    Ok(match most_iterations {
        Some(it) => mp_concrete::ExecParams::check_output_frames("iterations", it, frames, j)?,
        None => mp_concrete::ExecParams::check_output_frames("frames", frames, frames, j)?,
    })
}

impl AbstractProgram {
    /// Deterministic execution (loop bodies at their means, or replayed as observed).
    pub fn execute(&self, params: &AbstractExecParams) -> Result<Track> {
        params.validate()?;
        self.validate()?;
        check_output_frames(self, output_frames_bound(self, params.replay, false))?;
        let prims = flatten(self, params.replay)?;
        render(&prims, self, &fit_for(self, params))
    }

    /// Stochastic execution with a seed: each loop iteration samples its
    /// start/mid/end points and duration. The same seed gives the same track.
    pub fn sample(&self, seed: u64, params: &AbstractExecParams) -> Result<Track> {
        params.validate()?;
        self.validate()?;
        check_output_frames(self, output_frames_bound(self, params.replay, true))?;
        let prims = flatten_sampled(self, seed, params.jitter)?;
        render(&prims, self, &fit_for(self, params))
    }
}
