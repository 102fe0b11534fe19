//! Per-joint trajectory plots: each coordinate against time, the detected
//! keypoints as dots and the executed program drawn over them, each
//! primitive coloured by its kind; detected loops shaded behind.

use mp_abstract::RepetitiveInterval;
use mp_concrete::Program;
use mp_geom::{PrimitiveKind, Track, Units};

use crate::error::{ReportError, Result};
use crate::style::{self, kind_color};
use crate::svg::{num, tick_label, ticks, Anchor, Svg};

/// One primitive of the plotted joint: its kind and (frame, position) samples.
type Curve = (PrimitiveKind, Vec<(f64, Vec<f64>)>);

/// Size of a trajectory plot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlotParams {
    /// Width of the picture in pixels. Default 920.
    pub width_px: f64,
    /// Height of each coordinate's panel in pixels. Default 180.
    pub panel_height_px: f64,
    /// Samples per frame when drawing the program (smooth circles and splines). Default 4.
    pub samples_per_frame: usize,
}

impl Default for PlotParams {
    fn default() -> Self {
        PlotParams {
            width_px: 920.0,
            panel_height_px: 180.0,
            samples_per_frame: 4,
        }
    }
}

impl PlotParams {
    /// Checks the sizes.
    pub fn validate(&self) -> Result<()> {
        if !(self.width_px.is_finite() && self.width_px >= 200.0) {
            return Err(ReportError::param(
                "width_px",
                format!("must be ≥ 200, got {}", self.width_px),
            ));
        }
        if !(self.panel_height_px.is_finite() && self.panel_height_px >= 60.0) {
            return Err(ReportError::param(
                "panel_height_px",
                format!("must be ≥ 60, got {}", self.panel_height_px),
            ));
        }
        if self.samples_per_frame == 0 || self.samples_per_frame > 64 {
            return Err(ReportError::param(
                "samples_per_frame",
                format!("must be in 1..=64, got {}", self.samples_per_frame),
            ));
        }
        Ok(())
    }
}

/// Checks that a program describes a track: same joints count, dimensions and frame count.
pub(crate) fn check_agree(track: &Track, program: &Program) -> Result<()> {
    if track.n_joints() != program.n_joints() || track.dims() != program.dims {
        return Err(ReportError::Mismatch(format!(
            "the track has {} joints × {} dimensions, the program {} × {}",
            track.n_joints(),
            track.dims(),
            program.n_joints(),
            program.dims
        )));
    }
    if track.n_frames() != program.n_frames() {
        return Err(ReportError::Mismatch(format!(
            "the track has {} frames, the program {}",
            track.n_frames(),
            program.n_frames()
        )));
    }
    Ok(())
}

/// Axis label of coordinate `k` (of `d`) in `units`; image y is drawn upside down.
pub(crate) fn axis_label(k: usize, d: usize, units: Units) -> String {
    let name = mp_concrete::axis_name(k, d);
    let u = match units {
        Units::Pixels => "px",
        Units::Metres => "m",
        Units::Unitless => "",
    };
    if units == Units::Pixels && k == 1 {
        format!("{name} ({u}, up ↑)")
    } else if u.is_empty() {
        name
    } else {
        format!("{name} ({u})")
    }
}

/// The trajectory plot of one joint as an SVG document: a title and
/// legend, then one panel per axis with the counted intervals,
/// the grid, the segment boundaries, the keypoints and the program, and the
/// time axis under the last.
pub fn joint_trajectory_svg(
    track: &Track,
    program: &Program,
    intervals: &[RepetitiveInterval],
    joint: usize,
    params: &PlotParams,
) -> Result<String> {
    params.validate()?;
    check_agree(track, program)?;
    let name = program.joints.get(joint).ok_or_else(|| {
        ReportError::Mismatch(format!(
            "joint {joint} is out of range (the program has {})",
            program.n_joints()
        ))
    })?;
    let d = program.dims;
    let (left, right, top, gap, bottom) = (70.0, 24.0, 64.0, 18.0, 46.0);
    let w = params.width_px;
    let ph = params.panel_height_px;
    let h = top + d as f64 * ph + (d as f64 - 1.0) * gap + bottom;
    let axis = TimeX {
        x0: left,
        x1: w - right,
        span: (program.n_frames().saturating_sub(1)).max(1) as f64,
    };
    let bounds = program.boundaries();
    let curves = program_curves(program, &bounds, joint, params);
    let mut svg = Svg::new(w, h, style::PAPER);
    title_and_legend(&mut svg, &axis, name, program, &curves);
    for k in 0..d {
        let py0 = top + k as f64 * (ph + gap);
        let (lo, hi) = value_range(track, joint, k, &curves);
        let panel = Panel {
            k,
            py0,
            py1: py0 + ph,
            ph,
            lo,
            hi,
            invert: track.units() == Units::Pixels && k == 1,
        };
        svg.rect(
            axis.x0,
            py0,
            axis.x1 - axis.x0,
            ph,
            "#f8fafc",
            r##"stroke="#cbd5e1" stroke-width="1""##,
        );
        // Loops behind everything.
        intervals_layer(&mut svg, &axis, &panel, intervals, program.n_frames());
        grid_layer(&mut svg, &axis, &panel, &bounds, d, track.units());
        keypoints_layer(&mut svg, &axis, &panel, track, joint);
        program_layer(&mut svg, &axis, &panel, &curves);
        if k + 1 == d {
            time_axis_layer(&mut svg, &axis, panel.py1, program);
        }
    }
    Ok(svg.finish())
}

/// The time axis of the panels: frame `f` at `x0 + f / span · (x1 − x0)`.
struct TimeX {
    x0: f64,
    x1: f64,
    span: f64,
}

impl TimeX {
    fn fx(&self, f: f64) -> f64 {
        self.x0 + f / self.span * (self.x1 - self.x0)
    }
}

/// One axis's panel: its top and bottom, and its value range.
struct Panel {
    k: usize,
    py0: f64,
    py1: f64,
    /// Its height (`py1 − py0`).
    ph: f64,
    lo: f64,
    hi: f64,
    /// Image y grows downwards: drawn upside down.
    invert: bool,
}

impl Panel {
    fn fy(&self, v: f64) -> f64 {
        let a = (v - self.lo) / (self.hi - self.lo);
        if self.invert {
            self.py0 + a * self.ph
        } else {
            self.py1 - a * self.ph
        }
    }
}

/// Program samples per segment (frame, value per axis).
fn program_curves(
    program: &Program,
    bounds: &[usize],
    joint: usize,
    params: &PlotParams,
) -> Vec<Curve> {
    let mut curves: Vec<Curve> = Vec::new();
    for (si, seg) in program.segments.iter().enumerate() {
        let Some(p) = seg.primitives.get(joint) else {
            continue;
        };
        let start = bounds.get(si).copied().unwrap_or(0) as f64;
        let n = (seg.duration_frames.saturating_sub(1)) * params.samples_per_frame;
        let pts: Vec<(f64, Vec<f64>)> = (0..=n)
            .map(|i| {
                let t = i as f64 / params.samples_per_frame as f64;
                (start + t, p.eval(t))
            })
            .collect();
        curves.push((p.kind(), pts));
    }
    curves
}

/// The joint's name, the summary line and the legend.
fn title_and_legend(svg: &mut Svg, axis: &TimeX, name: &str, program: &Program, curves: &[Curve]) {
    let (x0, x1) = (axis.x0, axis.x1);
    svg.text(
        x0,
        26.0,
        name,
        17.0,
        style::INK,
        Anchor::Start,
        r#"font-weight="bold""#,
    );
    let counts: Vec<String> = PrimitiveKind::ALL
        .iter()
        .filter_map(|k| {
            let n = curves.iter().filter(|(kk, _)| kk == k).count();
            (n > 0).then(|| format!("{n} {}", k.as_str()))
        })
        .collect();
    svg.text(
        x0,
        46.0,
        &format!(
            "{} frames at {} fps · {} primitives: {}",
            program.n_frames(),
            mp_geom::fps_label(program.fps),
            curves.len(),
            counts.join(", ")
        ),
        11.5,
        style::MUTED,
        Anchor::Start,
        "",
    );
    let mut lx = x1;
    let mut legend: Vec<(String, &str, bool)> = PrimitiveKind::ALL
        .iter()
        .rev()
        .map(|k| (k.as_str().to_string(), kind_color(*k), false))
        .collect();
    legend.push(("keypoints".into(), style::KEYPOINT_DOT, true));
    for (label, colour, dot) in legend {
        let tw = 7.0 * label.chars().count() as f64;
        svg.text(lx, 26.0, &label, 11.5, style::INK, Anchor::End, "");
        lx -= tw + 8.0;
        if dot {
            svg.circle(lx, 22.0, 3.5, colour, r#"fill-opacity="0.7""#);
        } else {
            svg.line(
                lx - 7.0,
                22.0,
                lx + 3.0,
                22.0,
                colour,
                3.5,
                r#"stroke-linecap="round""#,
            );
        }
        lx -= 20.0;
    }
}

/// Value range of axis `k` over the valid keypoints and the program, padded.
fn value_range(track: &Track, joint: usize, k: usize, curves: &[Curve]) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for t in 0..track.n_frames() {
        if track.confidence()[[t, joint]] > 0.0 {
            let v = track.positions()[[t, joint, k]];
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    for (_, pts) in curves {
        for (_, v) in pts {
            if let Some(&v) = v.get(k) {
                if v.is_finite() {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        (lo, hi) = (0.0, 1.0);
    }
    if hi - lo < 1e-9 {
        (lo, hi) = (lo - 1.0, hi + 1.0);
    }
    let pad = 0.08 * (hi - lo);
    (lo - pad, hi + pad)
}

/// The counted intervals, shaded, with their repetitions' boundaries.
fn intervals_layer(
    svg: &mut Svg,
    axis: &TimeX,
    panel: &Panel,
    intervals: &[RepetitiveInterval],
    t_total: usize,
) {
    let (py0, py1) = (panel.py0, panel.py1);
    for iv in intervals {
        let (a, b) = (
            axis.fx(iv.start_frame as f64),
            axis.fx(iv.end_frame.saturating_sub(1) as f64),
        );
        svg.rect(
            a,
            py0,
            b - a,
            panel.ph,
            style::LOOP_FILL,
            r#"fill-opacity="0.10""#,
        );
        for &bf in iv.boundaries.iter() {
            let x = axis.fx((bf.min(t_total.saturating_sub(1))) as f64);
            svg.line(
                x,
                py0,
                x,
                py1,
                style::LOOP_DARK,
                1.0,
                r#"stroke-opacity="0.45" stroke-dasharray="4 3""#,
            );
        }
    }
}

/// Grid lines with value labels, segment boundaries and the axis's name.
fn grid_layer(
    svg: &mut Svg,
    axis: &TimeX,
    panel: &Panel,
    bounds: &[usize],
    d: usize,
    units: Units,
) {
    let (x0, x1, py0, py1) = (axis.x0, axis.x1, panel.py0, panel.py1);
    for v in ticks(panel.lo, panel.hi, 4) {
        let y = panel.fy(v);
        svg.line(x0, y, x1, y, style::GRID, 1.0, "");
        svg.text(
            x0 - 8.0,
            y + 4.0,
            &tick_label(v),
            11.0,
            style::MUTED,
            Anchor::End,
            "",
        );
    }
    for &b in bounds.iter().skip(1).take(bounds.len().saturating_sub(2)) {
        let x = axis.fx(b as f64 - 0.5);
        svg.line(x, py0, x, py1, "#cbd5e1", 0.6, "");
    }
    let label = axis_label(panel.k, d, units);
    svg.text(
        18.0,
        (py0 + py1) / 2.0,
        &label,
        12.0,
        style::INK,
        Anchor::Middle,
        &format!(r#"transform="rotate(-90 18 {})""#, num((py0 + py1) / 2.0)),
    );
}

/// The keypoints as dots, more opaque where more confident.
fn keypoints_layer(svg: &mut Svg, axis: &TimeX, panel: &Panel, track: &Track, joint: usize) {
    svg.open_group(&format!(r#"fill="{}""#, style::KEYPOINT_DOT));
    for t in 0..track.n_frames() {
        let c = track.confidence()[[t, joint]];
        let v = track.positions()[[t, joint, panel.k]];
        if c > 0.0 && v.is_finite() {
            let op = 0.25 + 0.45 * c.clamp(0.0, 1.0);
            svg.raw(&format!(
                "<circle cx=\"{}\" cy=\"{}\" r=\"2.3\" fill-opacity=\"{}\"/>\n",
                num(axis.fx(t as f64)),
                num(panel.fy(v)),
                num(op)
            ));
        }
    }
    svg.close_group();
}

/// The program's primitives, coloured by kind.
fn program_layer(svg: &mut Svg, axis: &TimeX, panel: &Panel, curves: &[Curve]) {
    for (kind, pts) in curves {
        let colour = kind_color(*kind);
        let line: Vec<(f64, f64)> = pts
            .iter()
            .filter_map(|(f, v)| v.get(panel.k).map(|&v| (axis.fx(*f), panel.fy(v))))
            .collect();
        if line.len() == 1 {
            svg.circle(line[0].0, line[0].1, 2.6, colour, "");
        } else {
            svg.polyline(&line, colour, 2.6, "");
        }
    }
}

/// Frame ticks under the last panel, and the axis label.
fn time_axis_layer(svg: &mut Svg, axis: &TimeX, py1: f64, program: &Program) {
    let fps = program.fps;
    for f in ticks(0.0, axis.span, 10) {
        let x = axis.fx(f);
        svg.line(x, py1, x, py1 + 5.0, style::MUTED, 1.0, "");
        svg.text(
            x,
            py1 + 18.0,
            &tick_label(f),
            11.0,
            style::MUTED,
            Anchor::Middle,
            "",
        );
    }
    svg.text(
        (axis.x0 + axis.x1) / 2.0,
        py1 + 38.0,
        &format!(
            "frame ({} fps; {} s in all)",
            mp_geom::fps_label(fps),
            tick_label(program.n_frames() as f64 / fps)
        ),
        12.0,
        style::INK,
        Anchor::Middle,
        "",
    );
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use mp_concrete::Segment;
    use mp_geom::{Primitive, Skeleton};
    use ndarray::Array3;

    pub(crate) fn tiny() -> (Track, Program) {
        let program = Program {
            fps: 30.0,
            units: Units::Pixels,
            dims: 2,
            skeleton: "generic".into(),
            joints: vec!["j0".into(), "left_wrist".into()],
            continuity: mp_concrete::Continuity::None,
            segments: vec![
                Segment {
                    duration_frames: 10,
                    primitives: vec![
                        Primitive::Stationary {
                            point: vec![5.0, 5.0],
                        },
                        Primitive::Line {
                            start: vec![0.0, 0.0],
                            velocity: vec![1.0, 2.0],
                        },
                    ],
                },
                Segment {
                    duration_frames: 6,
                    primitives: vec![
                        Primitive::Stationary {
                            point: vec![5.0, 5.0],
                        },
                        Primitive::Circle {
                            center: vec![10.0, 20.0],
                            radius: 3.0,
                            angle_start: 0.0,
                            angle_vel: 30.0,
                            angle_acc: 0.0,
                            axes: vec![],
                        },
                    ],
                },
            ],
        };
        let exec = program.execute().unwrap();
        let pos: Array3<f64> = exec.positions().to_owned();
        let track = Track::new(
            pos,
            None,
            30.0,
            Units::Pixels,
            Skeleton::custom("generic", program.joints.clone(), vec![(0, 1)], None),
        )
        .unwrap();
        (track, program)
    }

    #[test]
    fn plot_has_kind_colours_and_parses() {
        let (track, program) = tiny();
        let iv = RepetitiveInterval {
            start_frame: 0,
            end_frame: 10,
            body_size: 1,
            iterations: 2,
            boundaries: vec![0, 5, 10],
            count: 2,
            score: 1.0,
        };
        let svg = joint_trajectory_svg(&track, &program, &[iv], 1, &PlotParams::default()).unwrap();
        assert!(svg.contains(kind_color(PrimitiveKind::Line)));
        assert!(svg.contains(kind_color(PrimitiveKind::Circle)));
        assert!(svg.contains("left_wrist"));
        // 16 keypoints per axis.
        assert_eq!(svg.matches("r=\"2.3\"").count(), 32);
        crate::raster::svg_to_png("plot", &svg, 1.0).unwrap();
    }

    #[test]
    fn mismatched_program_is_an_error() {
        let (track, mut program) = tiny();
        program.segments.pop();
        let e = joint_trajectory_svg(&track, &program, &[], 0, &PlotParams::default()).unwrap_err();
        assert!(e.to_string().contains("16 frames"), "{e}");
        let (track, program) = tiny();
        assert!(joint_trajectory_svg(&track, &program, &[], 5, &PlotParams::default()).is_err());
    }
}
