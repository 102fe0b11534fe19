//! Printing programs in the paper's notation.

use std::fmt::Write as _;

use mp_geom::Primitive;

use crate::program::{Program, Segment};
use crate::smooth::Continuity;

/// How numbers are printed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum NumberFormat {
    /// Shortest text that parses back to the same `f64` (lossless).
    #[default]
    Exact,
    /// A fixed number of decimals, like the paper's figures (lossy).
    Fixed(usize),
}

impl NumberFormat {
    /// Decimals of [`Program::to_dsl_pretty`] when none are chosen: 2, as the paper's figures.
    pub const PRETTY_DECIMALS: usize = 2;

    /// Decimals that show a program's numbers to about the same precision in
    /// every unit: 2 for pixels (the paper's), 4 for metres (0.1 mm), 3 for
    /// unitless features.
    pub fn pretty_decimals(units: mp_geom::Units) -> usize {
        match units {
            mp_geom::Units::Pixels => Self::PRETTY_DECIMALS,
            mp_geom::Units::Metres => 4,
            mp_geom::Units::Unitless => 3,
        }
    }
}

/// Formats one number.
pub fn fmt_number(x: f64, nf: NumberFormat) -> String {
    match nf {
        NumberFormat::Fixed(p) => {
            let s = format!("{x:.p$}");
            // A value that rounds to zero prints without a sign (`0.00`,
            // not `-0.00`).
            if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
                s[1..].to_string()
            } else {
                s
            }
        }
        NumberFormat::Exact => {
            let a = x.abs();
            if a == 0.0 || (1e-5..1e16).contains(&a) {
                // `Display` is the shortest round-trip representation without exponent.
                format!("{x}")
            } else {
                // `LowerExp` is also shortest round-trip; used to keep extreme values short.
                format!("{x:e}")
            }
        }
    }
}

/// Name of axis `k` of `d`: `x, y, z` for D ≤ 3, `x0, x1, …` otherwise.
pub fn axis_name(k: usize, d: usize) -> String {
    if d <= 3 {
        ["x", "y", "z"][k].to_string()
    } else {
        format!("x{k}")
    }
}

/// Polynomial `c[0]·t^(n-1) + … + c[n-1]` printed highest power first; a
/// negative coefficient after the first is subtracted (`3*t - 4`, which
/// reads back exactly: `- 0` is −0).
fn poly(coeffs: &[f64], nf: NumberFormat) -> String {
    let n = coeffs.len();
    let mut s = String::new();
    for (i, c) in coeffs.iter().enumerate() {
        let pow = n - 1 - i;
        if i == 0 {
            s.push_str(&fmt_number(*c, nf));
        } else if c.is_sign_negative() {
            s.push_str(" - ");
            s.push_str(&fmt_number(-*c, nf));
        } else {
            s.push_str(" + ");
            s.push_str(&fmt_number(*c, nf));
        }
        match pow {
            0 => {}
            1 => s.push_str("*t"),
            p => {
                let _ = write!(s, "*t^{p}");
            }
        }
    }
    s
}

fn tuple(v: &[f64], nf: NumberFormat) -> String {
    let parts: Vec<String> = v.iter().map(|x| fmt_number(*x, nf)).collect();
    format!("({})", parts.join(", "))
}

/// One statement, e.g. `linear_motion(x=1.2*t + 30, y=-0.5*t + 12, duration=8)`.
pub(crate) fn statement(p: &Primitive, duration_frames: usize, nf: NumberFormat) -> String {
    let d = p.dims();
    let mut args: Vec<String> = Vec::new();
    let name = match p {
        Primitive::Stationary { point } => {
            for (k, v) in point.iter().enumerate() {
                args.push(format!("{}={}", axis_name(k, d), fmt_number(*v, nf)));
            }
            "stationary"
        }
        Primitive::Line { start, velocity } => {
            for k in 0..d {
                args.push(format!(
                    "{}={}",
                    axis_name(k, d),
                    poly(&[velocity[k], start[k]], nf)
                ));
            }
            "linear_motion"
        }
        Primitive::Circle {
            center,
            radius,
            angle_start,
            angle_vel,
            angle_acc,
            axes,
        } => {
            args.push(format!("center={}", tuple(center, nf)));
            args.push(format!("radius={}", fmt_number(*radius, nf)));
            let angle = if *angle_acc != 0.0 {
                poly(&[*angle_acc, *angle_vel, *angle_start], nf)
            } else {
                poly(&[*angle_vel, *angle_start], nf)
            };
            args.push(format!("angle={angle}"));
            if axes.len() == 2 {
                args.push(format!("u={}", tuple(&axes[0], nf)));
                args.push(format!("v={}", tuple(&axes[1], nf)));
            }
            "circular_motion"
        }
        Primitive::Spline { coeffs } => {
            for (k, c) in coeffs.iter().enumerate() {
                args.push(format!("{}={}", axis_name(k, d), poly(c, nf)));
            }
            "spline_motion"
        }
    };
    args.push(format!("duration={duration_frames}"));
    format!("{name}({})", args.join(", "))
}

fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

impl Program {
    /// The DSL header line, e.g. `program(fps=30, units=px, dims=2, skeleton="penn13", continuity=c0)`
    /// (`continuity` only when it is not `none`), numbers formatted by `nf`.
    pub fn dsl_header(&self, nf: NumberFormat) -> String {
        let units = match self.units {
            mp_geom::Units::Pixels => "px",
            mp_geom::Units::Metres => "m",
            mp_geom::Units::Unitless => "unitless",
        };
        let continuity = match self.continuity {
            Continuity::None => String::new(),
            c => format!(", continuity={c}"),
        };
        format!(
            "program(fps={}, units={units}, dims={}, skeleton={}{continuity})",
            fmt_number(self.fps, nf),
            self.dims,
            quote(&self.skeleton)
        )
    }

    /// The DSL block of joint `joint`: `joint "name" {`, its statements
    /// with numbers formatted by `nf`, `}`.
    pub fn dsl_joint_block(&self, joint: usize, nf: NumberFormat) -> String {
        let mut s = String::new();
        let name = self.joints.get(joint).map(String::as_str).unwrap_or("?");
        let _ = writeln!(s, "joint {} {{", quote(name));
        for (prim, dur) in self.joint_statements(joint) {
            let _ = writeln!(s, "    {}", statement(prim, dur, nf));
        }
        s.push_str("}\n");
        s
    }
}

impl Segment {
    /// The DSL statement of joint `joint` (its index in the program's
    /// joints) in this segment, numbers formatted by `nf`, e.g.
    /// `linear_motion(x=1.2*t + 30, y=-0.5*t + 12, duration=8)`; `None` when
    /// the segment has no primitive for that joint.
    pub fn dsl_statement(&self, joint: usize, nf: NumberFormat) -> Option<String> {
        self.primitives
            .get(joint)
            .map(|p| statement(p, self.duration_frames, nf))
    }
}

/// The whole program with numbers formatted by `nf`.
fn print_with(p: &Program, nf: NumberFormat) -> String {
    let mut s = p.dsl_header(nf);
    s.push('\n');
    for j in 0..p.joints.len() {
        s.push('\n');
        s.push_str(&p.dsl_joint_block(j, nf));
    }
    s
}

/// Lossless text: `parse(&print(p)) == p` for every valid program.
pub(crate) fn print(p: &Program) -> String {
    print_with(p, NumberFormat::Exact)
}

/// Human-friendly text with `decimals` digits after the point (the paper uses 2).
/// Not lossless.
pub(crate) fn print_pretty(p: &Program, decimals: usize) -> String {
    print_with(p, NumberFormat::Fixed(decimals))
}
