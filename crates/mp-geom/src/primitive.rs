//! Motion primitives: the parametric curves that concrete programs are made of.
//!
//! Time `t` is measured in frames from the start of the segment (`t = 0` is
//! the segment's first frame) and may be fractional: executing at fractional
//! times is how programs render at any time resolution.
//!
//! Angles of circles are in **degrees** (as printed in the paper's notation);
//! positions are in the track's units (pixels or metres).

use serde::{Deserialize, Serialize};

/// The kind of a primitive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
#[serde(rename_all = "lowercase")]
pub enum PrimitiveKind {
    /// Holds one point.
    Stationary,
    /// Constant velocity along a straight line.
    Line,
    /// Motion on a circle with angle linear (optionally quadratic) in time.
    Circle,
    /// Cubic polynomial per axis.
    Spline,
}

impl PrimitiveKind {
    /// All kinds, in the order used for tie-breaking (simplest first).
    pub const ALL: [PrimitiveKind; 4] = [
        PrimitiveKind::Stationary,
        PrimitiveKind::Line,
        PrimitiveKind::Circle,
        PrimitiveKind::Spline,
    ];
    /// Name used in the DSL and in reports.
    pub fn as_str(&self) -> &'static str {
        match self {
            PrimitiveKind::Stationary => "stationary",
            PrimitiveKind::Line => "line",
            PrimitiveKind::Circle => "circle",
            PrimitiveKind::Spline => "spline",
        }
    }
}

impl std::fmt::Display for PrimitiveKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for PrimitiveKind {
    type Err = String;

    /// The DSL name of a kind (`stationary`, `line`, `circle`, `spline`).
    fn from_str(s: &str) -> Result<Self, String> {
        PrimitiveKind::ALL
            .into_iter()
            .find(|k| k.as_str() == s.trim())
            .ok_or_else(|| {
                format!("unknown primitive kind `{s}` (stationary, line, circle or spline)")
            })
    }
}

/// A motion primitive of one joint, in D = 2 or 3 dimensions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum Primitive {
    /// `p(t) = point`.
    Stationary {
        /// The held position (length D).
        point: Vec<f64>,
    },
    /// `p(t) = start + velocity · t`.
    Line {
        /// Position at t = 0 (length D).
        start: Vec<f64>,
        /// Velocity per frame (length D).
        velocity: Vec<f64>,
    },
    /// `θ(t) = angle_acc·t² + angle_vel·t + angle_start` (degrees);
    /// 2D: `p = center + radius·(cos θ, sin θ)`;
    /// 3D: `p = center + radius·(cos θ · u + sin θ · v)` with `axes = [u, v]` orthonormal.
    Circle {
        /// Centre (length D).
        center: Vec<f64>,
        /// Radius (> 0).
        radius: f64,
        /// Angle at t = 0, degrees.
        angle_start: f64,
        /// Angular velocity, degrees per frame.
        angle_vel: f64,
        /// Angular acceleration term, degrees per frame² (0 for the plain model).
        #[serde(default)]
        angle_acc: f64,
        /// In 3D, the plane's orthonormal basis `[u, v]` (each of length 3); empty in 2D.
        #[serde(default)]
        axes: Vec<Vec<f64>>,
    },
    /// Per axis `a t³ + b t² + c t + d`; `coeffs[k] = [a, b, c, d]` for axis k.
    Spline {
        /// Cubic coefficients per axis.
        coeffs: Vec<[f64; 4]>,
    },
}

impl Primitive {
    /// The kind of this primitive.
    pub fn kind(&self) -> PrimitiveKind {
        match self {
            Primitive::Stationary { .. } => PrimitiveKind::Stationary,
            Primitive::Line { .. } => PrimitiveKind::Line,
            Primitive::Circle { .. } => PrimitiveKind::Circle,
            Primitive::Spline { .. } => PrimitiveKind::Spline,
        }
    }

    /// Number of spatial dimensions D.
    pub fn dims(&self) -> usize {
        match self {
            Primitive::Stationary { point } => point.len(),
            Primitive::Line { start, .. } => start.len(),
            Primitive::Circle { center, .. } => center.len(),
            Primitive::Spline { coeffs } => coeffs.len(),
        }
    }

    /// Number of free parameters (used to compare program size with raw poses;
    /// the segment's duration is counted by the program, not here).
    pub fn n_params(&self) -> usize {
        let d = self.dims();
        match self {
            Primitive::Stationary { .. } => d,
            Primitive::Line { .. } => 2 * d,
            Primitive::Circle { angle_acc, .. } => {
                // centre + radius + angle (start, vel [, acc]) + plane orientation in 3D (3 angles)
                let plane = if d == 3 { 3 } else { 0 };
                d + 1 + 2 + usize::from(*angle_acc != 0.0) + plane
            }
            Primitive::Spline { .. } => 4 * d,
        }
    }

    /// Position at (fractional) frame `t`, written into `out` (length D).
    pub fn eval_into(&self, t: f64, out: &mut [f64]) {
        match self {
            Primitive::Stationary { point } => out.copy_from_slice(point),
            Primitive::Line { start, velocity } => {
                for k in 0..out.len() {
                    out[k] = start[k] + velocity[k] * t;
                }
            }
            Primitive::Circle {
                center,
                radius,
                angle_start,
                angle_vel,
                angle_acc,
                axes,
            } => {
                let th = (angle_acc * t * t + angle_vel * t + angle_start).to_radians();
                let (s, c) = th.sin_cos();
                if center.len() == 2 || axes.len() < 2 {
                    out[0] = center[0] + radius * c;
                    out[1] = center[1] + radius * s;
                    let n = out.len();
                    out[2..].copy_from_slice(&center[2..n]);
                } else {
                    for k in 0..out.len() {
                        out[k] = center[k] + radius * (c * axes[0][k] + s * axes[1][k]);
                    }
                }
            }
            Primitive::Spline { coeffs } => {
                for (k, [a, b, c, d]) in coeffs.iter().enumerate() {
                    out[k] = ((a * t + b) * t + c) * t + d;
                }
            }
        }
    }

    /// The same primitive moved by `delta` (one value per dimension): every
    /// point it passes through, at every time, shifted by `delta`.
    pub fn translated(&self, delta: &[f64]) -> Primitive {
        let add = |v: &mut Vec<f64>| v.iter_mut().zip(delta).for_each(|(x, d)| *x += d);
        let mut q = self.clone();
        match &mut q {
            Primitive::Stationary { point } => add(point),
            Primitive::Line { start, .. } => add(start),
            Primitive::Circle { center, .. } => add(center),
            Primitive::Spline { coeffs } => {
                coeffs.iter_mut().zip(delta).for_each(|(c, d)| c[3] += d)
            }
        }
        q
    }

    /// Position at (fractional) frame `t`.
    pub fn eval(&self, t: f64) -> Vec<f64> {
        let mut out = vec![0.0; self.dims()];
        self.eval_into(t, &mut out);
        out
    }

    /// Whether every parameter is finite.
    pub fn is_finite(&self) -> bool {
        let all = |v: &[f64]| v.iter().all(|x| x.is_finite());
        match self {
            Primitive::Stationary { point } => all(point),
            Primitive::Line { start, velocity } => all(start) && all(velocity),
            Primitive::Circle {
                center,
                radius,
                angle_start,
                angle_vel,
                angle_acc,
                axes,
            } => {
                all(center)
                    && radius.is_finite()
                    && angle_start.is_finite()
                    && angle_vel.is_finite()
                    && angle_acc.is_finite()
                    && axes.iter().all(|a| all(a))
            }
            Primitive::Spline { coeffs } => coeffs.iter().all(|c| all(c)),
        }
    }
}

#[cfg(test)]
mod tests {

    #[test]
    fn translated_moves_every_point_by_delta() {
        let d = [3.0, -2.0];
        let prims = [
            Primitive::Stationary {
                point: vec![1.0, 2.0],
            },
            Primitive::Line {
                start: vec![0.0, 1.0],
                velocity: vec![0.5, -0.25],
            },
            Primitive::Circle {
                center: vec![4.0, 5.0],
                radius: 2.0,
                angle_start: 10.0,
                angle_vel: 7.0,
                angle_acc: 0.1,
                axes: Vec::new(),
            },
            Primitive::Spline {
                coeffs: vec![[0.01, -0.2, 1.0, 3.0], [0.0, 0.1, -1.0, 2.0]],
            },
        ];
        for p in &prims {
            let q = p.translated(&d);
            for t in [0.0, 1.5, 7.0] {
                let (a, b) = (p.eval(t), q.eval(t));
                for k in 0..2 {
                    assert!((b[k] - a[k] - d[k]).abs() < 1e-9, "{p:?} at {t}");
                }
            }
        }
    }
    use super::*;

    #[test]
    fn eval_basic() {
        let l = Primitive::Line {
            start: vec![1.0, 2.0],
            velocity: vec![0.5, -1.0],
        };
        assert_eq!(l.eval(2.0), vec![2.0, 0.0]);
        let c = Primitive::Circle {
            center: vec![0.0, 0.0],
            radius: 2.0,
            angle_start: 90.0,
            angle_vel: 0.0,
            angle_acc: 0.0,
            axes: vec![],
        };
        let p = c.eval(0.0);
        assert!(p[0].abs() < 1e-12 && (p[1] - 2.0).abs() < 1e-12);
        let s = Primitive::Spline {
            coeffs: vec![[1.0, 0.0, 0.0, 1.0]],
        };
        assert_eq!(s.eval(2.0), vec![9.0]);
        assert_eq!(l.n_params(), 4);
    }
}
