//! The pose between two frames of a track, guided by the program fitted to
//! it: what `mp interpolate` warps an in-between frame to.
//!
//! Frames `i` and `i + 1` of a track (the kept frames of a video) are known;
//! the pose at time `i + w` (`0 ≤ w ≤ 1`) is not. Per joint:
//!
//! * seen (confidence above `min_confidence`) in both frames: the rule of
//!   [`InBetween`] — the chord between the two keypoints
//!   ([`InBetween::Linear`]), the chord plus the program's bulge away from
//!   its own chord ([`InBetween::Bulge`]), or a cubic Hermite curve through
//!   the two keypoints with velocities estimated at each of them
//!   ([`InBetween::Hermite`]);
//! * seen in one of them only: held there (the program's value where the
//!   joint was not seen is no measurement);
//! * seen in neither: no pose.
//!
//! The Hermite curve is the program's cubic spline primitive
//! ([`mp_geom::Primitive::Spline`]) over one frame interval constrained to
//! pass through both keypoints with the given end velocities: on a turning
//! joint it follows the turn where the chord cuts the corner, and a joint
//! that stops (velocity near zero at a kept frame) eases in and out instead
//! of moving at constant speed. The velocity at frame `i` is
//! [`Tangents::Keypoints`]: `(k[i+1] − k[i−1]) / 2` of the keypoints
//! (Catmull–Rom), or [`Tangents::Program`]: the fitted program's velocity at
//! frame `i`; in both cases scaled by `tension`. Where frame `i − 1` (or
//! `i + 2`) does not show the joint, or the track ends, the velocity there is
//! the chord `k[i+1] − k[i]`, so a curve with both ends so is the chord.
//! The default also keeps the curve within half the chord's length of the
//! chord (`max_bulge`), so that one keypoint far off in a neighbouring
//! frame (a pose-model jump) cannot throw the curve between two good ones.

use mp_geom::{PrimitiveKind, Track};
use serde::{Deserialize, Serialize};

use crate::error::{ConcreteError, Result};
use crate::exec::Transition;
use crate::program::Program;

/// Where the velocities of a Hermite in-between come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Tangents {
    /// Central differences of the keypoints (Catmull–Rom).
    Keypoints,
    /// The fitted program's velocity (central difference over one frame).
    Program,
}

/// How the pose between two frames is made (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "rule", rename_all = "snake_case")]
#[non_exhaustive]
pub enum InBetween {
    /// The keypoints of the two frames interpolated linearly.
    Linear,
    /// The chord between the keypoints plus the program's bulge away from
    /// its own chord between the two frames, cut to `max_bulge` of the
    /// keypoints' chord (0: the chord; a semicircle bulges 0.5).
    Bulge {
        /// Longest bulge as a fraction of the chord.
        max_bulge: f64,
    },
    /// A cubic Hermite curve through the two keypoints.
    Hermite {
        /// Where the velocities come from.
        tangents: Tangents,
        /// Factor on the velocities (1: Catmull–Rom; 0: ease in and out).
        tension: f64,
        /// Only where the program's primitive over the interval curves
        /// (circle or spline); the chord where it is a line or stationary.
        curved_only: bool,
        /// The curve's distance from the chord is cut to this fraction of
        /// the chord's length (`None`: not cut), so that a neighbouring
        /// keypoint far off (a pose-model jump) cannot throw the curve.
        #[serde(default)]
        max_bulge: Option<f64>,
    },
}

impl Default for InBetween {
    /// Catmull–Rom through the kept keypoints (velocities from the
    /// neighbouring keypoints, tension 1) on every joint, at most half the
    /// chord away from the chord (as far as a semicircle): chosen at 2×, 4×
    /// and 8× on the validation parts of Penn Action, AIST++, the QUVA
    /// reference keypoints and MSR Action3D (`cargo xtask eval inbetween`,
    /// `docs/results/video.md`), where it was closer to the truth than linear
    /// interpolation, than the program's bulge, than the program's
    /// velocities and than the curve on curved primitives only; the cut
    /// at half the chord was as good as one at 0.35 and better than none or
    /// one at 0.1 or 0.2.
    fn default() -> Self {
        InBetween::Hermite {
            tangents: Tangents::Keypoints,
            tension: 1.0,
            curved_only: false,
            max_bulge: Some(0.5),
        }
    }
}

impl InBetween {
    /// Checks the numbers.
    pub fn validate(&self) -> Result<()> {
        match *self {
            InBetween::Linear => Ok(()),
            InBetween::Bulge { max_bulge } => {
                if max_bulge.is_finite() && max_bulge >= 0.0 {
                    Ok(())
                } else {
                    Err(ConcreteError::param(
                        "max_bulge",
                        format!("must be a finite number ≥ 0, got {max_bulge}"),
                    ))
                }
            }
            InBetween::Hermite {
                tension, max_bulge, ..
            } => {
                if !(tension.is_finite() && (0.0..=2.0).contains(&tension)) {
                    return Err(ConcreteError::param(
                        "tension",
                        format!("must be in [0, 2], got {tension}"),
                    ));
                }
                match max_bulge {
                    Some(b) if !(b.is_finite() && b >= 0.0) => Err(ConcreteError::param(
                        "max_bulge",
                        format!("must be a finite number ≥ 0, got {b}"),
                    )),
                    _ => Ok(()),
                }
            }
        }
    }

    /// Whether the rule reads the program.
    pub fn uses_program(&self) -> bool {
        match *self {
            InBetween::Linear => false,
            InBetween::Bulge { .. } => true,
            InBetween::Hermite {
                tangents,
                curved_only,
                ..
            } => tangents == Tangents::Program || curved_only,
        }
    }

    /// Parses `linear`, `bulge[:B]`, `hermite[:keypoints|program][:TENSION][:curved]`
    /// (e.g. `hermite:keypoints:1:curved`; defaults keypoints, 1, everywhere).
    pub fn parse(text: &str) -> Result<Self> {
        let mut parts = text.split(':');
        let bad = |why: String| ConcreteError::param("in-between rule", why);
        let rule = match parts.next().unwrap_or("") {
            "linear" => InBetween::Linear,
            "bulge" => InBetween::Bulge {
                max_bulge: match parts.next() {
                    Some(b) => b
                        .parse()
                        .map_err(|_| bad(format!("{text}: {b} is not a number")))?,
                    None => 0.5,
                },
            },
            "hermite" => {
                let (mut tangents, mut tension, mut curved_only) = (Tangents::Keypoints, 1.0, false);
                let mut max_bulge = None;
                for p in parts.by_ref() {
                    if let Some(b) = p.strip_prefix("bulge=") {
                        max_bulge = Some(
                            b.parse()
                                .map_err(|_| bad(format!("{text}: {b} is not a number")))?,
                        );
                        continue;
                    }
                    match p {
                        "keypoints" => tangents = Tangents::Keypoints,
                        "program" => tangents = Tangents::Program,
                        "curved" => curved_only = true,
                        "everywhere" => curved_only = false,
                        x => {
                            tension = x.parse().map_err(|_| {
                                bad(format!(
                                    "{text}: {x} is neither keypoints, program, curved, everywhere nor a tension"
                                ))
                            })?
                        }
                    }
                }
                InBetween::Hermite {
                    tangents,
                    tension,
                    curved_only,
                    max_bulge,
                }
            }
            other => {
                return Err(bad(format!(
                    "unknown rule {other:?} (linear, bulge[:B], hermite[:keypoints|program][:T][:curved][:bulge=B])"
                )))
            }
        };
        if let Some(extra) = parts.next() {
            return Err(bad(format!("{text}: unexpected {extra:?}")));
        }
        rule.validate()?;
        Ok(rule)
    }

    /// The rule as [`InBetween::parse`] reads it.
    pub fn label(&self) -> String {
        match *self {
            InBetween::Linear => "linear".into(),
            InBetween::Bulge { max_bulge } => format!("bulge:{max_bulge}"),
            InBetween::Hermite {
                tangents,
                tension,
                curved_only,
                max_bulge,
            } => format!(
                "hermite:{}:{tension}{}{}",
                match tangents {
                    Tangents::Keypoints => "keypoints",
                    Tangents::Program => "program",
                },
                if curved_only { ":curved" } else { "" },
                max_bulge.map(|b| format!(":bulge={b}")).unwrap_or_default()
            ),
        }
    }
}

/// In-between poses of one track (see the module docs).
#[derive(Debug, Clone, Copy)]
pub struct InBetweenPoses<'a> {
    track: &'a Track,
    program: Option<&'a Program>,
    rule: InBetween,
    min_confidence: f64,
}

impl<'a> InBetweenPoses<'a> {
    /// The in-betweens of `track` with `rule`; `program` is the program
    /// fitted to `track` (on the same time axis), needed when the rule reads
    /// it ([`InBetween::uses_program`]).
    pub fn new(
        track: &'a Track,
        program: Option<&'a Program>,
        rule: InBetween,
        min_confidence: f64,
    ) -> Result<Self> {
        rule.validate()?;
        if !(min_confidence.is_finite() && (0.0..1.0).contains(&min_confidence)) {
            return Err(ConcreteError::param(
                "min_confidence",
                format!("must be in [0, 1), got {min_confidence}"),
            ));
        }
        match program {
            Some(p) => {
                p.validate()?;
                if p.n_joints() != track.n_joints() || p.dims != track.dims() {
                    return Err(ConcreteError::param(
                        "program",
                        format!(
                            "has {} joints in {}D, the track {} in {}D",
                            p.n_joints(),
                            p.dims,
                            track.n_joints(),
                            track.dims()
                        ),
                    ));
                }
                if p.n_frames() < track.n_frames() {
                    return Err(ConcreteError::param(
                        "program",
                        format!(
                            "lasts {} frames, the track {}",
                            p.n_frames(),
                            track.n_frames()
                        ),
                    ));
                }
            }
            None if rule.uses_program() => {
                return Err(ConcreteError::param(
                    "program",
                    format!("the rule {} needs the fitted program", rule.label()),
                ))
            }
            None => {}
        }
        Ok(InBetweenPoses {
            track,
            program,
            rule,
            min_confidence,
        })
    }

    /// The rule.
    pub fn rule(&self) -> InBetween {
        self.rule
    }

    fn seen(&self, t: usize, j: usize) -> bool {
        t < self.track.n_frames() && self.track.is_valid(t, j, self.min_confidence)
    }

    fn key(&self, t: usize, j: usize) -> Vec<f64> {
        self.track.point(t, j).to_vec()
    }

    /// The pose at time `i + w` (`0 ≤ w ≤ 1`): per joint, `None` where
    /// neither frame `i` nor `i + 1` shows it. `None` past the track's end
    /// (`i + 1` not a frame).
    pub fn pose(&self, i: usize, w: f64) -> Result<Option<Vec<Option<Vec<f64>>>>> {
        if !(w.is_finite() && (0.0..=1.0).contains(&w)) {
            return Err(ConcreteError::param(
                "w",
                format!("must be in [0, 1], got {w}"),
            ));
        }
        let nt = self.track.n_frames();
        if i + 1 >= nt {
            return Ok(None);
        }
        let (nj, d) = (self.track.n_joints(), self.track.dims());
        // Program samples: i, i + w, i + 1 and half a frame around i and i + 1.
        let prog = match self.program {
            Some(p) if self.rule.uses_program() => {
                let last = (p.n_frames() - 1) as f64;
                let (a, b) = (i as f64, (i + 1) as f64);
                let times = [
                    a,
                    a + w,
                    b,
                    (a - 0.5).max(0.0),
                    (a + 0.5).min(last),
                    (b - 0.5).max(0.0),
                    (b + 0.5).min(last),
                ];
                Some((p.sample_frames(&times, Transition::Blend)?, times))
            }
            _ => None,
        };
        let curved: Option<Vec<bool>> = match (self.rule, self.program) {
            (
                InBetween::Hermite {
                    curved_only: true, ..
                },
                Some(p),
            ) => Some(curved_joints(p, i as f64 + 0.5)),
            _ => None,
        };
        let mut out = vec![None; nj];
        for (j, o) in out.iter_mut().enumerate() {
            let (va, vb) = (self.seen(i, j), self.seen(i + 1, j));
            *o = match (va, vb) {
                (false, false) => None,
                (true, false) => Some(self.key(i, j)),
                (false, true) => Some(self.key(i + 1, j)),
                (true, true) => {
                    let (ka, kb) = (self.key(i, j), self.key(i + 1, j));
                    let lin: Vec<f64> = (0..d).map(|k| ka[k] + w * (kb[k] - ka[k])).collect();
                    Some(match self.rule {
                        InBetween::Linear => lin,
                        InBetween::Bulge { max_bulge } => {
                            let (p, _) = prog.as_ref().ok_or_else(no_program)?;
                            let dev: Vec<f64> = (0..d)
                                .map(|k| p[[1, j, k]] - (1.0 - w) * p[[0, j, k]] - w * p[[2, j, k]])
                                .collect();
                            let curve: Vec<f64> = (0..d).map(|k| lin[k] + dev[k]).collect();
                            cap_bulge(&lin, curve, norm(&sub(&kb, &ka)), Some(max_bulge))
                        }
                        InBetween::Hermite {
                            tangents,
                            tension,
                            max_bulge,
                            ..
                        } => {
                            if curved.as_ref().is_some_and(|c| !c[j]) {
                                lin
                            } else {
                                let chord = sub(&kb, &ka);
                                let (ma, mb) = match tangents {
                                    Tangents::Keypoints => (
                                        self.keypoint_tangent(i, j, &chord, tension, true),
                                        self.keypoint_tangent(i + 1, j, &chord, tension, false),
                                    ),
                                    Tangents::Program => {
                                        let (p, t) = prog.as_ref().ok_or_else(no_program)?;
                                        let m = |lo: usize, hi: usize| -> Vec<f64> {
                                            let dt = t[hi] - t[lo];
                                            if dt <= 0.0 {
                                                return chord.clone();
                                            }
                                            (0..d)
                                                .map(|k| {
                                                    tension * (p[[hi, j, k]] - p[[lo, j, k]]) / dt
                                                })
                                                .collect()
                                        };
                                        (m(3, 4), m(5, 6))
                                    }
                                };
                                let curve = hermite(&ka, &kb, &ma, &mb, w);
                                cap_bulge(&lin, curve, norm(&chord), max_bulge)
                            }
                        }
                    })
                }
            };
        }
        Ok(Some(out))
    }

    /// Catmull–Rom velocity of joint `j` at frame `t` (per frame), `tension`
    /// times the central difference; `chord` where a neighbour is missing.
    /// `start`: `t` is the interval's first frame (its outer neighbour is
    /// `t − 1`), else its last (`t + 1`).
    fn keypoint_tangent(
        &self,
        t: usize,
        j: usize,
        chord: &[f64],
        tension: f64,
        start: bool,
    ) -> Vec<f64> {
        let outer = if start { t.checked_sub(1) } else { Some(t + 1) };
        let Some(o) = outer.filter(|&o| self.seen(o, j)) else {
            return chord.to_vec();
        };
        let ko = self.key(o, j);
        // Central difference (k[t+1] − k[t−1]) / 2, the inner neighbour being
        // the interval's other end.
        chord
            .iter()
            .zip(&ko)
            .zip(self.track.point(t, j))
            .map(|((&c, &o), &k)| {
                let outer_step = if start { k - o } else { o - k };
                tension * 0.5 * (c + outer_step)
            })
            .collect()
    }
}

fn no_program() -> ConcreteError {
    ConcreteError::Program("the in-between rule needs the fitted program".into())
}

/// Per joint, whether the program's primitive at frame `frame` curves
/// (circle or spline).
fn curved_joints(program: &Program, frame: f64) -> Vec<bool> {
    let b = program.boundaries();
    let s = b
        .partition_point(|&x| (x as f64) <= frame)
        .saturating_sub(1)
        .min(program.n_segments().saturating_sub(1));
    program.segments[s]
        .primitives
        .iter()
        .map(|p| matches!(p.kind(), PrimitiveKind::Circle | PrimitiveKind::Spline))
        .collect()
}

/// Cubic Hermite curve from `a` (velocity `ma`) to `b` (velocity `mb`) over
/// one unit of time, at `w`.
pub fn hermite(a: &[f64], b: &[f64], ma: &[f64], mb: &[f64], w: f64) -> Vec<f64> {
    let (w2, w3) = (w * w, w * w * w);
    let h00 = 2.0 * w3 - 3.0 * w2 + 1.0;
    let h10 = w3 - 2.0 * w2 + w;
    let h01 = -2.0 * w3 + 3.0 * w2;
    let h11 = w3 - w2;
    (0..a.len())
        .map(|k| h00 * a[k] + h10 * ma[k] + h01 * b[k] + h11 * mb[k])
        .collect()
}

/// `curve` moved towards `lin` (the chord's point) so that it is at most
/// `max_bulge · chord` from it.
fn cap_bulge(lin: &[f64], curve: Vec<f64>, chord: f64, max_bulge: Option<f64>) -> Vec<f64> {
    let Some(b) = max_bulge else {
        return curve;
    };
    let dev = sub(&curve, lin);
    let (len, cap) = (norm(&dev), b * chord);
    if len <= cap || len == 0.0 {
        return curve;
    }
    let s = cap / len;
    lin.iter().zip(&dev).map(|(l, d)| l + s * d).collect()
}

fn sub(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x - y).collect()
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use mp_geom::{Skeleton, Units};
    use ndarray::{Array2, Array3};

    /// One joint at `f(t)` for `t = 0..n`, confidence 1 except `hidden` frames.
    fn track(n: usize, f: impl Fn(f64) -> [f64; 2], hidden: &[usize]) -> Track {
        let mut pos = Array3::zeros((n, 1, 2));
        let mut conf = Array2::ones((n, 1));
        for t in 0..n {
            let p = f(t as f64);
            pos[[t, 0, 0]] = p[0];
            pos[[t, 0, 1]] = p[1];
        }
        for &h in hidden {
            conf[[h, 0]] = 0.0;
        }
        Track::new(pos, Some(conf), 30.0, Units::Pixels, Skeleton::generic(1)).unwrap()
    }

    fn at(poses: &InBetweenPoses<'_>, i: usize, w: f64) -> Option<Vec<f64>> {
        poses.pose(i, w).unwrap().unwrap()[0].clone()
    }

    fn dist(a: &[f64], b: [f64; 2]) -> f64 {
        (a[0] - b[0]).hypot(a[1] - b[1])
    }

    #[test]
    fn catmull_rom_follows_a_thrown_ball_exactly_where_the_chord_misses() {
        // Constant acceleration: a quadratic, which Catmull–Rom's central
        // differences differentiate exactly.
        let f = |t: f64| [10.0 + 20.0 * t, 300.0 - 40.0 * t + 6.0 * t * t];
        let tr = track(8, f, &[]);
        let cr = InBetweenPoses::new(&tr, None, InBetween::default(), 0.3).unwrap();
        let lin = InBetweenPoses::new(&tr, None, InBetween::Linear, 0.3).unwrap();
        for i in 1..6 {
            for w in [0.25, 0.5, 0.75] {
                let truth = f(i as f64 + w);
                assert!(dist(&at(&cr, i, w).unwrap(), truth) < 1e-9);
                // The chord is off by w(1 − w)·a: 1.125 px at the middle.
                let e = dist(&at(&lin, i, w).unwrap(), truth);
                assert!((e - w * (1.0 - w) * 6.0).abs() < 1e-9, "{e}");
            }
        }
        // The kept poses themselves are reproduced.
        assert!(dist(&at(&cr, 3, 0.0).unwrap(), f(3.0)) < 1e-12);
        assert!(dist(&at(&cr, 3, 1.0).unwrap(), f(4.0)) < 1e-12);
    }

    #[test]
    fn on_a_circle_the_curve_stays_near_the_arc_and_the_chord_cuts_the_corner() {
        // 30° per kept frame on a circle of radius 100.
        let f = |t: f64| {
            let a = (30.0 * t).to_radians();
            [200.0 + 100.0 * a.cos(), 200.0 + 100.0 * a.sin()]
        };
        let tr = track(12, f, &[]);
        let cr = InBetweenPoses::new(&tr, None, InBetween::default(), 0.3).unwrap();
        let lin = InBetweenPoses::new(&tr, None, InBetween::Linear, 0.3).unwrap();
        let (mut e_cr, mut e_lin) = (0.0, 0.0);
        for i in 1..10 {
            for w in [0.125, 0.25, 0.5, 0.75, 0.875] {
                e_cr += dist(&at(&cr, i, w).unwrap(), f(i as f64 + w));
                e_lin += dist(&at(&lin, i, w).unwrap(), f(i as f64 + w));
            }
        }
        // The sagitta of a 30° chord is 3.4 px; the curve is within a few
        // tenths of a pixel.
        assert!(e_lin / 45.0 > 2.0, "{e_lin}");
        assert!(e_cr < 0.1 * e_lin, "{e_cr} vs {e_lin}");
    }

    #[test]
    fn a_missing_neighbour_falls_back_to_the_chord_and_a_missing_end_holds() {
        let f = |t: f64| [t * t, 0.0];
        // Frame 1 hidden: the interval 2–3 has no left neighbour (chord
        // velocity there); frame 5 hidden: 4–5 holds at frame 4.
        let tr = track(8, f, &[1, 5]);
        let cr = InBetweenPoses::new(&tr, None, InBetween::default(), 0.3).unwrap();
        let p = at(&cr, 2, 0.5).unwrap();
        // Velocity at 2: the chord 5; at 3: (16 − 4) / 2 = 6.
        let want = hermite(&[4.0, 0.0], &[9.0, 0.0], &[5.0, 0.0], &[6.0, 0.0], 0.5);
        assert!(dist(&p, [want[0], want[1]]) < 1e-12);
        assert_eq!(at(&cr, 4, 0.5).unwrap(), vec![16.0, 0.0]);
        assert_eq!(at(&cr, 5, 0.3).unwrap(), vec![36.0, 0.0]);
        // Hidden in both: no pose; past the end: nothing.
        let tr2 = track(4, f, &[1, 2]);
        let cr2 = InBetweenPoses::new(&tr2, None, InBetween::default(), 0.3).unwrap();
        assert_eq!(at(&cr2, 1, 0.5), None);
        assert!(cr.pose(7, 0.5).unwrap().is_none());
    }

    #[test]
    fn a_jump_in_a_neighbouring_frame_cannot_throw_the_curve_far() {
        // Still at x = 0 for frames 0–2 and 4–5 (frame 3 also at 0), but
        // frame 4 jumps 500 px sideways: the interval 2–3 has a 10-px chord
        // and a wild velocity at frame 3.
        let f = |t: f64| match t as usize {
            3 => [10.0, 0.0],
            4 => [10.0, 500.0],
            _ => [0.0, 0.0],
        };
        let tr = track(6, f, &[]);
        let free = InBetween::parse("hermite:keypoints:1").unwrap();
        let free = InBetweenPoses::new(&tr, None, free, 0.3).unwrap();
        let cut = InBetweenPoses::new(&tr, None, InBetween::default(), 0.3).unwrap();
        let p_free = at(&free, 2, 0.5).unwrap();
        let p_cut = at(&cut, 2, 0.5).unwrap();
        // Without the cut the curve swings 31 px off the 10-px chord; with
        // it, at most half the chord.
        assert!(dist(&p_free, [5.0, 0.0]) > 30.0, "{p_free:?}");
        assert!(dist(&p_cut, [5.0, 0.0]) <= 5.0 + 1e-9, "{p_cut:?}");
    }

    #[test]
    fn bulge_and_program_tangents_read_the_program() {
        let f = |t: f64| [5.0 * t, 2.0 * t];
        let tr = track(10, f, &[]);
        let program = crate::Program::synthesize(&tr, &Default::default()).unwrap();
        for rule in [
            InBetween::Bulge { max_bulge: 0.5 },
            InBetween::parse("hermite:program:1").unwrap(),
            InBetween::parse("hermite:keypoints:1:curved").unwrap(),
        ] {
            assert!(rule.uses_program());
            let err = InBetweenPoses::new(&tr, None, rule, 0.3).unwrap_err();
            assert!(
                err.to_string().contains("needs the fitted program"),
                "{err}"
            );
            // A line: every rule gives the line.
            let p = InBetweenPoses::new(&tr, Some(&program), rule, 0.3).unwrap();
            let q = at(&p, 4, 0.5).unwrap();
            assert!(dist(&q, f(4.5)) < 1e-6, "{} {q:?}", rule.label());
        }
        // A program of another skeleton is refused.
        let other = track(10, f, &[]);
        let mut pos = Array3::zeros((10, 2, 2));
        pos.slice_mut(ndarray::s![.., 0, ..])
            .assign(&other.positions().slice(ndarray::s![.., 0, ..]));
        let two = Track::new(pos, None, 30.0, Units::Pixels, Skeleton::generic(2)).unwrap();
        let p2 = crate::Program::synthesize(&two, &Default::default()).unwrap();
        assert!(InBetweenPoses::new(&tr, Some(&p2), InBetween::default(), 0.3).is_err());
    }

    #[test]
    fn rules_parse_print_and_reject_bad_numbers() {
        for text in [
            "linear",
            "bulge:0.5",
            "hermite:keypoints:1",
            "hermite:program:0.75:curved",
            "hermite:keypoints:1:bulge=0.25",
        ] {
            let r = InBetween::parse(text).unwrap();
            assert_eq!(InBetween::parse(&r.label()).unwrap(), r);
        }
        assert_eq!(
            InBetween::parse("hermite").unwrap(),
            InBetween::Hermite {
                tangents: Tangents::Keypoints,
                tension: 1.0,
                curved_only: false,
                max_bulge: None
            }
        );
        for bad in [
            "spline",
            "bulge:x",
            "bulge:-1",
            "hermite:3",
            "hermite:nan",
            "linear:1",
            "",
        ] {
            assert!(InBetween::parse(bad).is_err(), "{bad}");
        }
        let tr = track(4, |t| [t, t], &[]);
        let p = InBetweenPoses::new(&tr, None, InBetween::Linear, 0.3).unwrap();
        assert!(p.pose(0, 1.5).is_err());
        assert!(p.pose(0, f64::NAN).is_err());
        assert!(InBetweenPoses::new(&tr, None, InBetween::Linear, 1.5).is_err());
    }
}
