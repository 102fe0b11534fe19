//! From concrete primitives to an abstract program: translation to
//! start/mid/end primitives, loop detection and loop synthesis.

use mp_geom::Primitive;

use crate::error::{AbstractError, Result};
use crate::loops::{detect_loops, DetectedLoop, LoopParams};
use crate::model::{AbstractProgram, DetPrim, FreqDist, Gaussian, Loop, ProbPrim, Stmt};

/// Translates one segment (duration in frames, one concrete primitive per joint)
/// into a deterministic abstract primitive: per joint the positions at the
/// segment's first frame (`t = 0`), middle (`t = (d − 1)/2`) and last frame (`t = d − 1`).
pub(crate) fn translate_segment(duration: usize, prims: &[Primitive]) -> Result<DetPrim> {
    if duration == 0 {
        return Err(AbstractError::param(
            "duration",
            "a segment must last at least one frame",
        ));
    }
    if prims.is_empty() {
        return Err(AbstractError::Empty("segment without joints".into()));
    }
    let last = (duration - 1) as f64;
    let points = prims
        .iter()
        .enumerate()
        .map(|(j, p)| {
            if !p.is_finite() {
                return Err(AbstractError::NonFinite(format!(
                    "joint {j}: primitive has non-finite parameters"
                )));
            }
            let mut v = p.eval(0.0);
            v.extend(p.eval(last / 2.0));
            v.extend(p.eval(last));
            Ok(v)
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(DetPrim { duration, points })
}

/// Translates a whole segmentation (duration and per-joint primitives of each segment).
pub fn translate(segments: &[(usize, Vec<Primitive>)]) -> Result<Vec<DetPrim>> {
    if segments.is_empty() {
        return Err(AbstractError::Empty(
            "the concrete program has no primitives".into(),
        ));
    }
    segments
        .iter()
        .enumerate()
        .map(|(i, (d, p))| {
            translate_segment(*d, p).map_err(|e| AbstractError::Shape(format!("segment {i}: {e}")))
        })
        .collect()
}

/// Fits the loop body: one Gaussian per body position and joint, and the
/// duration distribution, from the primitives of a detected loop.
pub fn fit_loop(prims: &[DetPrim], l: &DetectedLoop) -> Result<Loop> {
    let k = l.body;
    if k == 0 || l.iterations < 2 || l.end > prims.len() || l.start + k * l.iterations != l.end {
        return Err(AbstractError::InvalidLoop(format!(
            "loop {}..{} with body {} and {} iterations is not a whole number of ≥ 2 iterations",
            l.start, l.end, l.body, l.iterations
        )));
    }
    let joints = prims[l.start].points.len();
    let mut body = Vec::with_capacity(k);
    for i in 0..k {
        let members: Vec<&DetPrim> = (0..l.iterations)
            .map(|it| &prims[l.start + it * k + i])
            .collect();
        let duration = FreqDist::from_values(members.iter().map(|p| p.duration));
        let gs = (0..joints)
            .map(|j| gaussian(members.iter().map(|p| p.points[j].as_slice())))
            .collect::<Result<Vec<_>>>()?;
        body.push(ProbPrim {
            duration,
            joints: gs,
        });
    }
    let observed = (0..l.iterations)
        .map(|it| prims[l.start + it * k..l.start + (it + 1) * k].to_vec())
        .collect();
    Ok(Loop {
        iterations: l.iterations,
        body,
        observed,
    })
}

/// Sample mean and covariance (n − 1 denominator; 0 for a single sample).
pub fn gaussian<'a>(samples: impl Iterator<Item = &'a [f64]>) -> Result<Gaussian> {
    let samples: Vec<&[f64]> = samples.collect();
    let first = samples
        .first()
        .ok_or_else(|| AbstractError::Empty("Gaussian of no samples".into()))?;
    let d = first.len();
    let n = samples.len() as f64;
    let mut mean = vec![0.0; d];
    for s in &samples {
        for (m, v) in mean.iter_mut().zip(s.iter()) {
            *m += v / n;
        }
    }
    let mut cov = vec![0.0; d * d];
    if samples.len() > 1 {
        for s in &samples {
            for a in 0..d {
                for b in 0..d {
                    cov[a * d + b] += (s[a] - mean[a]) * (s[b] - mean[b]) / (n - 1.0);
                }
            }
        }
    }
    Ok(Gaussian { mean, cov })
}

/// Builds an abstract program from deterministic primitives: detects loops
/// and rolls them up; everything else stays a deterministic statement.
pub fn synthesize(
    prims: &[DetPrim],
    params: &LoopParams,
    fps: f64,
    units: &str,
    joints: Vec<String>,
) -> Result<(AbstractProgram, Vec<DetectedLoop>)> {
    if prims.is_empty() {
        return Err(AbstractError::Empty(
            "no primitives to synthesise from".into(),
        ));
    }
    let loops = detect_loops(prims, params)?;
    let dims = prims[0].points[0].len() / 3;
    let mut stmts = Vec::new();
    let mut next = 0;
    for l in &loops {
        stmts.extend(prims[next..l.start].iter().cloned().map(Stmt::Prim));
        stmts.push(Stmt::Loop(fit_loop(prims, l)?));
        next = l.end;
    }
    stmts.extend(prims[next..].iter().cloned().map(Stmt::Prim));
    if joints.len() != prims[0].points.len() {
        return Err(AbstractError::Shape(format!(
            "{} joint names for {} joints",
            joints.len(),
            prims[0].points.len()
        )));
    }
    let prog = AbstractProgram {
        fps,
        units: units.to_string(),
        dims,
        unit_scale: params.unit_scale,
        joints,
        stmts,
    };
    prog.validate()?;
    Ok((prog, loops))
}
