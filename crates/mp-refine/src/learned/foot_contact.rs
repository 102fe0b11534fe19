//! Foot contact in the refinement: where a foot is planted, a refill must
//! not move it horizontally, and a planted foot that slides away and back
//! is held.
//!
//! Every size is in units of the body height (the median over frames of
//! the vertical extent of the skeleton) and every duration in seconds, so
//! the same settings hold for any clip length, frame rate or body size.
//!
//! * [`foot_contacts`]: a foot joint is in contact at a frame when its
//!   height is within [`FootContactParams::height_tolerance`] of its lowest
//!   height over [`FootContactParams::window_s`] around the frame and its
//!   vertical speed is below [`FootContactParams::vertical_speed`]
//!   (horizontal speed is not used: a sliding foot is fast horizontally).
//! * [`guard_refills`]: a refilled run of a foot joint keeps the input's
//!   horizontal coordinates when the refill would make the foot travel
//!   further horizontally than the input did (a refill never adds slide;
//!   the test is not limited to contact frames, where Kinect contact flags
//!   flicker).
//! * [`hold_slides`]: per leg (the foot joints of one side), a run of
//!   contact frames in which every joint of the leg moved away from its
//!   planted position (the median of its contact positions over the window)
//!   by more than [`FootContactParams::slide_tolerance`], by nearly the same
//!   vector ([`FootContactParams::leg_coherence`]), and came back, lasting
//!   [`FootContactParams::min_slide_s`] to [`FootContactParams::max_slide_s`],
//!   is a slide: its horizontal coordinates are replaced by the straight
//!   line between the frames before and after it.
//! * [`foot_slide`]: the slide of a track — horizontal travel of the foot
//!   joints per second over the frames where they are in contact.

use mp_geom::median;
use ndarray::{Array2, Array3, ArrayView3};
use serde::{Deserialize, Serialize};

use super::RepairedRun;
use crate::error::{RefineError, Result};

/// Parameters of the foot-contact handling.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FootContactParams {
    /// Vertical axis (1 = y up, MSR Action3D). Default 1.
    pub up_axis: usize,
    /// A foot is in contact within this height above its lowest height over
    /// the window (body heights). Default 0.03 (≈ 5 cm for 1.6 m).
    pub height_tolerance: f64,
    /// … and below this vertical speed (body heights per second). Default 0.5.
    pub vertical_speed: f64,
    /// Half width of the window of the lowest height and of the planted
    /// position (seconds). Default 1.
    pub window_s: f64,
    /// A planted foot joint has slid when it is further than this from its
    /// planted position (body heights). Default 0.03: the Kinect feet of MSR
    /// Action3D jitter by ≈ 1 cm a frame.
    pub slide_tolerance: f64,
    /// The joints of a sliding leg moved by vectors closer than this (body
    /// heights). Default 0.02: independent jitter of the ankle and the foot
    /// rarely agrees.
    pub leg_coherence: f64,
    /// Shortest slide (seconds). Default 0.2 (3 frames at 15 fps).
    pub min_slide_s: f64,
    /// Longest slide (seconds); a foot away for longer was moved on
    /// purpose. Default 1.4.
    pub max_slide_s: f64,
    /// Hold slides (`hold_slides`); otherwise only the refill guard runs.
    /// Default true.
    pub hold_slides: bool,
}

impl Default for FootContactParams {
    fn default() -> Self {
        FootContactParams {
            up_axis: 1,
            height_tolerance: 0.03,
            vertical_speed: 0.5,
            window_s: 1.0,
            slide_tolerance: 0.03,
            leg_coherence: 0.02,
            min_slide_s: 0.2,
            max_slide_s: 1.4,
            hold_slides: true,
        }
    }
}

impl FootContactParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        let pos = RefineError::check_positive;
        pos("height_tolerance", self.height_tolerance)?;
        pos("vertical_speed", self.vertical_speed)?;
        pos("window_s", self.window_s)?;
        pos("slide_tolerance", self.slide_tolerance)?;
        pos("leg_coherence", self.leg_coherence)?;
        pos("min_slide_s", self.min_slide_s)?;
        pos("max_slide_s", self.max_slide_s)?;
        if self.max_slide_s < self.min_slide_s {
            return Err(RefineError::param(
                "max_slide_s",
                format!("must be ≥ min_slide_s = {}", self.min_slide_s),
            ));
        }
        if self.up_axis > 2 {
            return Err(RefineError::param(
                "up_axis",
                format!("must be 0, 1 or 2, got {}", self.up_axis),
            ));
        }
        Ok(())
    }
}

/// Foot joints grouped by side: joints whose names contain `ankle`, `foot`,
/// `heel` or `toe`, one group for the names with `left`, one for `right`,
/// and one group per other foot joint.
pub fn foot_legs(names: &[String]) -> Vec<Vec<usize>> {
    let (mut left, mut right, mut other) = (Vec::new(), Vec::new(), Vec::new());
    for (i, n) in names.iter().enumerate() {
        let n = n.to_lowercase();
        if !["ankle", "foot", "heel", "toe"]
            .iter()
            .any(|k| n.contains(k))
        {
            continue;
        }
        if n.contains("left") {
            left.push(i);
        } else if n.contains("right") {
            right.push(i);
        } else {
            other.push(vec![i]);
        }
    }
    [left, right]
        .into_iter()
        .filter(|g| !g.is_empty())
        .chain(other)
        .collect()
}

/// Body height: the median over frames of the vertical extent of the joints.
pub fn body_height(pos: ArrayView3<'_, f64>, up: usize) -> Result<f64> {
    let (t, nj, d) = pos.dim();
    if up >= d || nj == 0 || t == 0 {
        return Err(RefineError::Shape(format!(
            "body_height: positions {:?}, up axis {up}",
            pos.dim()
        )));
    }
    let mut ext: Vec<f64> = (0..t)
        .map(|f| {
            let (lo, hi) = (0..nj).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), j| {
                let v = pos[[f, j, up]];
                (lo.min(v), hi.max(v))
            });
            hi - lo
        })
        .filter(|v| v.is_finite())
        .collect();
    ext.sort_by(f64::total_cmp);
    let h = ext.get(ext.len() / 2).copied().unwrap_or(0.0);
    if h.is_nan() || h <= 0.0 {
        return Err(RefineError::NonFinite(
            "body_height: the skeleton has no vertical extent".into(),
        ));
    }
    Ok(h)
}

fn frames_of(seconds: f64, fps: f64) -> usize {
    (seconds * fps).round().max(1.0) as usize
}

/// Contact flags (`T × feet.len()`) of the foot joints `feet` (see the module docs).
pub fn foot_contacts(
    pos: ArrayView3<'_, f64>,
    feet: &[usize],
    fps: f64,
    p: &FootContactParams,
) -> Result<Array2<bool>> {
    p.validate()?;
    if !(fps.is_finite() && fps > 0.0) {
        return Err(RefineError::param(
            "fps",
            format!("must be finite and > 0, got {fps}"),
        ));
    }
    let (t, nj, _) = pos.dim();
    if let Some(&j) = feet.iter().find(|&&j| j >= nj) {
        return Err(RefineError::Shape(format!(
            "foot_contacts: joint {j} of {nj}"
        )));
    }
    let scale = body_height(pos, p.up_axis)?;
    let w = frames_of(p.window_s, fps);
    let up = p.up_axis;
    let mut out = Array2::from_elem((t, feet.len()), false);
    for (k, &j) in feet.iter().enumerate() {
        for f in 0..t {
            let (lo, hi) = (f.saturating_sub(w), (f + w).min(t - 1));
            let floor = (lo..=hi)
                .map(|g| pos[[g, j, up]])
                .fold(f64::INFINITY, f64::min);
            let vy = if t < 2 {
                0.0
            } else {
                let (a, b) = (f.saturating_sub(1), (f + 1).min(t - 1));
                (pos[[b, j, up]] - pos[[a, j, up]]).abs() / (b - a) as f64 * fps
            };
            out[[f, k]] = pos[[f, j, up]] - floor <= p.height_tolerance * scale
                && vy <= p.vertical_speed * scale;
        }
    }
    Ok(out)
}

fn horizontal(up: usize) -> [usize; 2] {
    match up {
        0 => [1, 2],
        1 => [0, 2],
        _ => [0, 1],
    }
}

fn hdist(pos: ArrayView3<'_, f64>, a: usize, b: usize, j: usize, h: [usize; 2]) -> f64 {
    let dx = pos[[a, j, h[0]]] - pos[[b, j, h[0]]];
    let dz = pos[[a, j, h[1]]] - pos[[b, j, h[1]]];
    (dx * dx + dz * dz).sqrt()
}

/// Horizontal travel of joint `j` over frames `a..=b`.
fn travel(pos: ArrayView3<'_, f64>, a: usize, b: usize, j: usize, h: [usize; 2]) -> f64 {
    (a..b).map(|f| hdist(pos, f + 1, f, j, h)).sum()
}

/// The refill guard (see the module docs): `input` are the positions before
/// the refill, `pos` after it, `feet` the foot joints. Returns how many runs
/// kept the input's horizontal path.
pub fn guard_refills(
    input: ArrayView3<'_, f64>,
    pos: &mut Array3<f64>,
    runs: &[RepairedRun],
    feet: &[usize],
    up: usize,
) -> usize {
    let t = pos.dim().0;
    let h = horizontal(up);
    let mut kept = 0;
    for r in runs {
        if !feet.contains(&r.joint) {
            continue;
        }
        let (a, b) = (r.start.saturating_sub(1), (r.end + 1).min(t - 1));
        if travel(pos.view(), a, b, r.joint, h) > travel(input, a, b, r.joint, h) {
            for f in r.start..=r.end {
                for &x in &h {
                    pos[[f, r.joint, x]] = input[[f, r.joint, x]];
                }
            }
            kept += 1;
        }
    }
    kept
}

/// Holds slides of planted feet (see the module docs) in place; `legs` are
/// groups of foot joints ([`foot_legs`]). Returns the held runs, one per
/// joint.
pub fn hold_slides(
    pos: &mut Array3<f64>,
    legs: &[Vec<usize>],
    fps: f64,
    p: &FootContactParams,
) -> Result<Vec<RepairedRun>> {
    let t = pos.dim().0;
    let mut out = Vec::new();
    if t < 3 || !p.hold_slides {
        return Ok(out);
    }
    let scale = body_height(pos.view(), p.up_axis)?;
    let h = horizontal(p.up_axis);
    let w = frames_of(p.window_s, fps);
    let (min_run, max_run) = (frames_of(p.min_slide_s, fps), frames_of(p.max_slide_s, fps));
    let (tol, coh) = (p.slide_tolerance * scale, p.leg_coherence * scale);
    for leg in legs {
        let c = foot_contacts(pos.view(), leg, fps, p)?;
        // Deviation of each joint of the leg from its planted position.
        let mut dev = vec![[f64::NAN; 2]; t * leg.len()];
        for (k, &j) in leg.iter().enumerate() {
            for f in (0..t).filter(|&f| c[[f, k]]) {
                let (lo, hi) = (f.saturating_sub(w), (f + w).min(t - 1));
                let idx: Vec<usize> = (lo..=hi).filter(|&g| c[[g, k]]).collect();
                for (x, &ax) in h.iter().enumerate() {
                    let mut v: Vec<f64> = idx.iter().map(|&g| pos[[g, j, ax]]).collect();
                    dev[f * leg.len() + k][x] = pos[[f, j, ax]] - median(&mut v).unwrap_or(0.0);
                }
            }
        }
        let d = |f: usize, k: usize| dev[f * leg.len() + k];
        let norm = |v: [f64; 2]| (v[0] * v[0] + v[1] * v[1]).sqrt();
        let planted = |f: usize| (0..leg.len()).all(|k| c[[f, k]]);
        let away = |f: usize, thr: f64| (0..leg.len()).all(|k| norm(d(f, k)) > thr);
        let coherent = |f: usize| {
            (1..leg.len()).all(|k| norm([d(f, k)[0] - d(f, 0)[0], d(f, k)[1] - d(f, 0)[1]]) < coh)
        };
        let slid: Vec<bool> = (0..t)
            .map(|f| planted(f) && away(f, tol) && coherent(f))
            .collect();
        let mut f = 0;
        while f < t {
            if !slid[f] {
                f += 1;
                continue;
            }
            let (mut r0, mut r1) = (f, f);
            while r1 + 1 < t && slid[r1 + 1] {
                r1 += 1;
            }
            f = r1 + 1;
            // Grow over the slide's ramps: planted frames still half-way out.
            while r0 > 0 && planted(r0 - 1) && away(r0 - 1, 0.5 * tol) {
                r0 -= 1;
            }
            while r1 + 1 < t && planted(r1 + 1) && away(r1 + 1, 0.5 * tol) {
                r1 += 1;
            }
            f = f.max(r1 + 1);
            let len = r1 - r0 + 1;
            if len < min_run || len > max_run || r0 == 0 || r1 + 1 >= t {
                continue;
            }
            let (a, b) = (r0 - 1, r1 + 1);
            // Horizontal travel of the leg over consecutive contact frames of [a, b].
            let contact_travel = |x: &Array3<f64>| -> f64 {
                leg.iter()
                    .enumerate()
                    .map(|(k, &j)| {
                        (a..b)
                            .filter(|&g| c[[g, k]] && c[[g + 1, k]])
                            .map(|g| hdist(x.view(), g + 1, g, j, h))
                            .sum::<f64>()
                    })
                    .sum()
            };
            let mut held = pos.clone();
            for &j in leg {
                for g in r0..=r1 {
                    let u = (g - a) as f64 / (b - a) as f64;
                    for &ax in &h {
                        held[[g, j, ax]] = (1.0 - u) * pos[[a, j, ax]] + u * pos[[b, j, ax]];
                    }
                }
            }
            // The straight line is the shortest path over [a, b]; over the
            // contact frames alone it can be longer, and then it is not held.
            if contact_travel(&held) > contact_travel(pos) {
                continue;
            }
            *pos = held;
            for &j in leg {
                out.push(RepairedRun {
                    joint: j,
                    start: r0,
                    end: r1,
                });
            }
        }
    }
    Ok(out)
}

/// Foot slide of `pos`: horizontal travel of the foot joints `feet` per
/// second, summed over consecutive frames where `contacts` (`T × feet`,
/// e.g. [`foot_contacts`] of the clean clip) holds at both, averaged over
/// the joints; `up` is the vertical axis.
pub fn foot_slide(
    pos: ArrayView3<'_, f64>,
    feet: &[usize],
    contacts: &Array2<bool>,
    fps: f64,
    up: usize,
) -> Result<f64> {
    let t = pos.dim().0;
    if contacts.dim() != (t, feet.len()) || feet.is_empty() || t < 2 {
        return Err(RefineError::Shape(format!(
            "foot_slide: contacts {:?} for {t} frames and {} feet",
            contacts.dim(),
            feet.len()
        )));
    }
    let h = horizontal(up);
    let mut s = 0.0;
    for (k, &j) in feet.iter().enumerate() {
        for f in 1..t {
            if contacts[[f, k]] && contacts[[f - 1, k]] {
                s += hdist(pos, f, f - 1, j, h);
            }
        }
    }
    Ok(s / feet.len() as f64 / ((t - 1) as f64 / fps))
}
