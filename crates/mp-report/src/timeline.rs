//! The timeline: one row per joint with its primitives coloured by kind, a
//! row with the mix of kinds per segment, the counted repetitions with their
//! boundaries and counts, and the abstract program's loops, over a common
//! time axis. Its size is bounded whatever the recording's length: long
//! programs are drawn per column of the time axis.

use mp_abstract::RepetitiveInterval;
use mp_concrete::Program;
use mp_geom::PrimitiveKind;

use crate::error::{ReportError, Result};
use crate::style::{self, kind_color};
use crate::svg::{num, tick_label, ticks, Anchor, Svg};

/// Size of the timeline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimelineParams {
    /// Width of the picture in pixels. Default 1000.
    pub width_px: f64,
    /// Height of one joint's row in pixels. Default 12.
    pub row_height_px: f64,
    /// Draw the title and the summary line at the top. Default true.
    pub title: bool,
}

impl Default for TimelineParams {
    fn default() -> Self {
        TimelineParams {
            width_px: 1000.0,
            row_height_px: 12.0,
            title: true,
        }
    }
}

/// Where the time axis of a timeline lies, for placing a cursor over it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeAxis {
    /// x of the start of frame 0, pixels.
    pub x0_px: f64,
    /// x of the end of the last frame, pixels.
    pub x1_px: f64,
    /// Top of the rows, pixels.
    pub top_px: f64,
    /// Bottom of the rows, pixels.
    pub bottom_px: f64,
    /// Number of frames.
    pub frames: usize,
}

/// Columns per pixel of the time axis: programs with at most as many
/// segments as columns have every segment drawn on its own; longer ones are
/// drawn per column (the kind covering most of its frames), so the
/// picture's size is bounded whatever the length.
const COLUMNS_PER_PX: f64 = 0.5;

/// The smallest width, in pixels, of a segment or a repetition whose
/// boundary lines are drawn (narrower ones would only paint the rows over).
const MIN_LINE_GAP_PX: f64 = 3.0;

/// Kind index (in [`PrimitiveKind::ALL`]) of every segment and joint.
fn kind_indices(program: &Program) -> Vec<Vec<usize>> {
    program
        .segments
        .iter()
        .map(|seg| {
            seg.primitives
                .iter()
                .map(|p| {
                    PrimitiveKind::ALL
                        .iter()
                        .position(|k| *k == p.kind())
                        .unwrap_or(0)
                })
                .collect()
        })
        .collect()
}

/// Frames of each kind per column and joint, for `columns` equal columns
/// over the program's frames: `[column][joint][kind]`.
fn column_kinds(program: &Program, columns: usize) -> Vec<Vec<[usize; 4]>> {
    let t_total = program.n_frames().max(1);
    let j = program.n_joints();
    let kinds = kind_indices(program);
    let mut out = vec![vec![[0usize; 4]; j]; columns];
    let mut f = 0usize;
    for (si, seg) in program.segments.iter().enumerate() {
        for t in f..f + seg.duration_frames {
            let c = (t * columns / t_total).min(columns - 1);
            for (ji, k) in kinds[si].iter().enumerate().take(j) {
                out[c][ji][(*k).min(3)] += 1;
            }
        }
        f += seg.duration_frames;
    }
    out
}

/// The timeline as an SVG document and its time axis. `repetitions` are the
/// counted repetitions, `program_loops` the abstract program's loops (its
/// `for` statements), both in frames of the program. The root element
/// carries `data-x0`, `data-x1`, `data-top`, `data-bottom` and `data-frames`.
pub fn timeline_svg(
    program: &Program,
    repetitions: &[RepetitiveInterval],
    program_loops: &[RepetitiveInterval],
    params: &TimelineParams,
) -> Result<(String, TimeAxis)> {
    if !(params.width_px.is_finite() && params.width_px >= 300.0) {
        return Err(ReportError::param(
            "width_px",
            format!("must be ≥ 300, got {}", params.width_px),
        ));
    }
    if !(params.row_height_px.is_finite() && params.row_height_px >= 4.0) {
        return Err(ReportError::param(
            "row_height_px",
            format!("must be ≥ 4, got {}", params.row_height_px),
        ));
    }
    if program.n_frames() == 0 {
        return Err(ReportError::Mismatch("the program has no frames".into()));
    }
    let lay = Layout::new(program, params);
    let bounds = program.boundaries();
    let cols = (program.n_segments() > lay.columns).then(|| column_kinds(program, lay.columns));
    let mut svg = Svg::new(params.width_px, lay.h, style::PAPER);
    header(&mut svg, &lay, program, repetitions, program_loops, params);
    kinds_row(&mut svg, &lay, program, &bounds, cols.as_deref());
    repetitions_row(&mut svg, &lay, repetitions);
    program_loops_row(&mut svg, &lay, program_loops);
    joint_rows(&mut svg, &lay, program, &bounds, cols.as_deref());
    boundaries(&mut svg, &lay, program, &bounds, repetitions);
    time_axis(&mut svg, &lay, program);
    let (x0, x1, t_total) = (lay.x0, lay.x1, lay.t_total);
    let (loops_top, rows_bottom) = (lay.loops_top, lay.rows_bottom);
    let axis = TimeAxis {
        x0_px: x0,
        x1_px: x1,
        top_px: loops_top,
        bottom_px: rows_bottom,
        frames: t_total,
    };
    let attrs = format!(
        r#"class="mp-timeline" data-x0="{}" data-x1="{}" data-top="{}" data-bottom="{}" data-frames="{}""#,
        num(x0),
        num(x1),
        num(axis.top_px),
        num(axis.bottom_px),
        t_total
    );
    Ok((svg.finish_with(&attrs), axis))
}

/// Where each part of the timeline goes: the label column, the time axis
/// from `x0` to `x1`, and the rows from the top.
#[derive(Debug, Clone, Copy)]
struct Layout {
    t_total: usize,
    j: usize,
    rh: f64,
    label_w: f64,
    x0: f64,
    x1: f64,
    px_per_frame: f64,
    mix_top: f64,
    mix_h: f64,
    loops_top: f64,
    loop_h: f64,
    plo_top: f64,
    plo_h: f64,
    rows_top: f64,
    rows_bottom: f64,
    h: f64,
    /// Columns of the time axis when the program is drawn per column.
    columns: usize,
}

impl Layout {
    fn new(program: &Program, params: &TimelineParams) -> Self {
        let t_total = program.n_frames();
        let j = program.n_joints();
        let rh = params.row_height_px;
        let label_w = 118.0;
        let (x0, x1) = (label_w + 12.0, params.width_px - 18.0);
        // The legend's line, then the summary's (the title, when drawn, beside the legend).
        let title_h = 50.0;
        let mix_top = title_h;
        let mix_h = 30.0;
        let loops_top = mix_top + mix_h + 10.0;
        let loop_h = 40.0;
        let plo_top = loops_top + loop_h + 6.0;
        let plo_h = 18.0;
        let rows_top = plo_top + plo_h + 10.0;
        let rows_bottom = rows_top + j as f64 * rh;
        Layout {
            t_total,
            j,
            rh,
            label_w,
            x0,
            x1,
            px_per_frame: (x1 - x0) / t_total as f64,
            mix_top,
            mix_h,
            loops_top,
            loop_h,
            plo_top,
            plo_h,
            rows_top,
            rows_bottom,
            h: rows_bottom + 46.0,
            columns: ((x1 - x0) * COLUMNS_PER_PX).floor().max(1.0) as usize,
        }
    }

    /// The x of frame `f`.
    fn fx(&self, f: f64) -> f64 {
        self.x0 + f / self.t_total as f64 * (self.x1 - self.x0)
    }
}

/// The title, the summary line and the legend.
fn header(
    svg: &mut Svg,
    lay: &Layout,
    program: &Program,
    repetitions: &[RepetitiveInterval],
    program_loops: &[RepetitiveInterval],
    params: &TimelineParams,
) {
    let reps: usize = repetitions.iter().map(|i| i.count).sum();
    if params.title {
        svg.text(
            18.0,
            24.0,
            "Timeline",
            17.0,
            style::INK,
            Anchor::Start,
            r#"font-weight="bold""#,
        );
    }
    let plural =
        |n: usize, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
    svg.text(
        18.0,
        42.0,
        &format!(
            "{} segments × {} joints · {} in {} · {}",
            program.n_segments(),
            lay.j,
            plural(reps, "repetition", "repetitions"),
            plural(repetitions.len(), "interval", "intervals"),
            plural(program_loops.len(), "program loop", "program loops"),
        ),
        11.5,
        style::MUTED,
        Anchor::Start,
        "",
    );
    // Legend.
    let mut lx = lay.x1;
    for k in PrimitiveKind::ALL.iter().rev() {
        let label = k.as_str();
        svg.text(lx, 24.0, label, 11.5, style::INK, Anchor::End, "");
        lx -= 7.0 * label.len() as f64 + 8.0;
        svg.rect(lx - 12.0, 15.0, 12.0, 11.0, kind_color(*k), r#"rx="2""#);
        lx -= 26.0;
    }
    for (label, colour) in [
        ("program loop", style::PROGRAM_LOOP),
        ("repetition", style::LOOP_FILL),
    ] {
        svg.text(lx, 24.0, label, 11.5, style::INK, Anchor::End, "");
        lx -= 7.0 * label.len() as f64 + 8.0;
        svg.rect(lx - 12.0, 15.0, 12.0, 11.0, colour, r#"rx="2""#);
        lx -= 26.0;
    }
}

/// The mix of kinds per segment (per column for long programs).
fn kinds_row(
    svg: &mut Svg,
    lay: &Layout,
    program: &Program,
    bounds: &[usize],
    cols: Option<&[Vec<[usize; 4]>]>,
) {
    // Mix of kinds per segment (per column for long programs).
    svg.text(
        lay.label_w,
        lay.mix_top + lay.mix_h / 2.0 + 4.0,
        "kinds per segment",
        11.0,
        style::INK,
        Anchor::End,
        "",
    );
    let stack = |svg: &mut Svg, a: f64, b: f64, per_kind: [usize; 4]| {
        let n = per_kind.iter().sum::<usize>().max(1) as f64;
        let mut y = lay.mix_top;
        for (ki, k) in PrimitiveKind::ALL.iter().enumerate() {
            let c = per_kind.get(ki).copied().unwrap_or(0) as f64;
            if c > 0.0 {
                let hh = lay.mix_h * c / n;
                svg.rect(a, y, (b - a).max(0.5), hh, kind_color(*k), "");
                y += hh;
            }
        }
    };
    match &cols {
        None => {
            let kinds = kind_indices(program);
            for si in 0..program.n_segments() {
                let (a, b) = (lay.fx(bounds[si] as f64), lay.fx(bounds[si + 1] as f64));
                let mut per_kind = [0usize; 4];
                for &k in &kinds[si] {
                    per_kind[k.min(3)] += 1;
                }
                stack(svg, a, b, per_kind);
                if b - a >= MIN_LINE_GAP_PX {
                    svg.line(
                        b,
                        lay.mix_top,
                        b,
                        lay.mix_top + lay.mix_h,
                        style::PAPER,
                        0.8,
                        "",
                    );
                }
            }
        }
        Some(cols) => {
            // Columns with the same mix (in whole joints) are drawn as one.
            let w = (lay.x1 - lay.x0) / lay.columns as f64;
            let mix = |c: usize| -> [usize; 4] {
                let mut m = [0usize; 4];
                for joint in &cols[c] {
                    for (ki, n) in joint.iter().enumerate() {
                        m[ki] += n;
                    }
                }
                let total = m.iter().sum::<usize>().max(1);
                m.map(|n| (n * lay.j.max(1) + total / 2) / total)
            };
            let mut c = 0;
            while c < lay.columns {
                let m = mix(c);
                let mut e = c + 1;
                while e < lay.columns && mix(e) == m {
                    e += 1;
                }
                stack(svg, lay.x0 + c as f64 * w, lay.x0 + e as f64 * w, m);
                c = e;
            }
        }
    }
}

/// A row's label and its background band, `h` high from `top`.
fn band(svg: &mut Svg, lay: &Layout, top: f64, h: f64, label: &str) {
    svg.text(
        lay.label_w,
        top + h / 2.0 + 4.0,
        label,
        11.0,
        style::INK,
        Anchor::End,
        "",
    );
    svg.rect(lay.x0, top, lay.x1 - lay.x0, h, "#f1f5f9", r#"rx="3""#);
}

/// The counted repetitions: intervals, boundaries, numbers and counts.
fn repetitions_row(svg: &mut Svg, lay: &Layout, repetitions: &[RepetitiveInterval]) {
    band(svg, lay, lay.loops_top, lay.loop_h, "repetitions");
    for (li, iv) in repetitions.iter().enumerate() {
        let (a, b) = (lay.fx(iv.start_frame as f64), lay.fx(iv.end_frame as f64));
        svg.rect(
            a,
            lay.loops_top + 3.0,
            (b - a).max(0.5),
            lay.loop_h - 6.0,
            style::LOOP_FILL,
            r#"fill-opacity="0.85" rx="3""#,
        );
        for w in iv.boundaries.windows(2).skip(1) {
            let x = lay.fx(w[0] as f64);
            if (w[0] - iv.boundaries[0]) as f64 * lay.px_per_frame >= MIN_LINE_GAP_PX
                && (w[1] - w[0]) as f64 * lay.px_per_frame >= MIN_LINE_GAP_PX
            {
                svg.line(
                    x,
                    lay.loops_top + 3.0,
                    x,
                    lay.loops_top + lay.loop_h - 3.0,
                    style::PAPER,
                    1.5,
                    "",
                );
            }
        }
        // Repetition numbers, where they fit.
        for (k, w) in iv.boundaries.windows(2).enumerate() {
            let (ia, ib) = (lay.fx(w[0] as f64), lay.fx(w[1] as f64));
            if ib - ia >= 14.0 {
                svg.text(
                    (ia + ib) / 2.0,
                    lay.loops_top + lay.loop_h - 7.0,
                    &(k + 1).to_string(),
                    9.5,
                    "#ffffff",
                    Anchor::Middle,
                    r#"fill-opacity="0.85""#,
                );
            }
        }
        // The count in a dark label in the middle of the interval, or
        // above it where it is narrow (not at all where it is a sliver).
        let label = format!("×{}", iv.count);
        let cx = (a + b) / 2.0;
        let lw = 12.0 + 8.5 * label.chars().count() as f64;
        if b - a >= lw + 4.0 {
            svg.rect(
                cx - lw / 2.0,
                lay.loops_top + 6.0,
                lw,
                19.0,
                style::LOOP_DARK,
                r#"rx="9""#,
            );
            svg.text(
                cx,
                lay.loops_top + 20.0,
                &label,
                13.0,
                "#ffffff",
                Anchor::Middle,
                r#"font-weight="bold""#,
            );
        } else if b - a >= 10.0 {
            svg.text(
                cx,
                lay.loops_top - 2.0,
                &label,
                11.0,
                style::LOOP_DARK,
                Anchor::Middle,
                r#"font-weight="bold""#,
            );
        }
        svg.raw(&format!(
            "<title>interval {}: frames {}, {} repetitions</title>\n",
            li + 1,
            mp_geom::frames_label(iv.start_frame, iv.end_frame),
            iv.count
        ));
    }
    if repetitions.is_empty() {
        svg.text(
            (lay.x0 + lay.x1) / 2.0,
            lay.loops_top + lay.loop_h / 2.0 + 4.0,
            "no repetition counted",
            11.0,
            style::MUTED,
            Anchor::Middle,
            "",
        );
    }
}

/// The abstract program's `for` statements.
fn program_loops_row(svg: &mut Svg, lay: &Layout, program_loops: &[RepetitiveInterval]) {
    band(svg, lay, lay.plo_top, lay.plo_h, "program loops");
    for (li, lp) in program_loops.iter().enumerate() {
        let (a, b) = (lay.fx(lp.start_frame as f64), lay.fx(lp.end_frame as f64));
        svg.rect(
            a,
            lay.plo_top + 2.0,
            (b - a).max(0.5),
            lay.plo_h - 4.0,
            style::PROGRAM_LOOP,
            r#"fill-opacity="0.85" rx="2""#,
        );
        let label = format!("×{}", lp.iterations);
        if b - a >= 10.0 + 7.0 * label.chars().count() as f64 {
            svg.text(
                (a + b) / 2.0,
                lay.plo_top + lay.plo_h - 5.0,
                &label,
                10.5,
                "#ffffff",
                Anchor::Middle,
                r#"font-weight="bold""#,
            );
        }
        svg.raw(&format!(
            "<title>program loop {}: frames {}, {} iterations of {} primitives</title>\n",
            li + 1,
            mp_geom::frames_label(lp.start_frame, lp.end_frame),
            lp.iterations,
            lp.body_size
        ));
    }
}

/// One row per joint with its primitives' kinds.
fn joint_rows(
    svg: &mut Svg,
    lay: &Layout,
    program: &Program,
    bounds: &[usize],
    cols: Option<&[Vec<[usize; 4]>]>,
) {
    // One row per joint.
    for ji in 0..lay.j {
        let y = lay.rows_top + ji as f64 * lay.rh;
        let name = program.joints.get(ji).map(String::as_str).unwrap_or("?");
        svg.text(
            lay.label_w,
            y + lay.rh * 0.8,
            name,
            (lay.rh * 0.78).min(11.0),
            style::INK,
            Anchor::End,
            "",
        );
        match &cols {
            None => {
                // Consecutive segments of one kind as one rectangle (the
                // segment boundaries are drawn over the rows).
                let kind = |si: usize| program.segments[si].primitives.get(ji).map(|p| p.kind());
                let mut si = 0;
                while si < program.n_segments() {
                    let k = kind(si);
                    let mut e = si + 1;
                    while e < program.n_segments() && kind(e) == k {
                        e += 1;
                    }
                    if let Some(k) = k {
                        let (a, b) = (lay.fx(bounds[si] as f64), lay.fx(bounds[e] as f64));
                        svg.rect(
                            a,
                            y + 0.5,
                            (b - a).max(0.5),
                            lay.rh - 1.0,
                            kind_color(k),
                            "",
                        );
                    }
                    si = e;
                }
            }
            Some(cols) => {
                // The kind covering most of each column; runs of one kind as one.
                let w = (lay.x1 - lay.x0) / lay.columns as f64;
                let major = |c: usize| -> usize {
                    let k = &cols[c][ji];
                    (0..4)
                        .max_by_key(|&i| (k[i], std::cmp::Reverse(i)))
                        .unwrap_or(0)
                };
                let mut c = 0;
                while c < lay.columns {
                    let k = major(c);
                    let mut e = c + 1;
                    while e < lay.columns && major(e) == k {
                        e += 1;
                    }
                    svg.rect(
                        lay.x0 + c as f64 * w,
                        y + 0.5,
                        (e - c) as f64 * w,
                        lay.rh - 1.0,
                        kind_color(PrimitiveKind::ALL[k.min(PrimitiveKind::ALL.len() - 1)]),
                        "",
                    );
                    c = e;
                }
            }
        }
    }
}

/// Segment and repetition boundaries over the rows, where wide enough to show.
fn boundaries(
    svg: &mut Svg,
    lay: &Layout,
    program: &Program,
    bounds: &[usize],
    repetitions: &[RepetitiveInterval],
) {
    // Segment boundaries over the rows, between segments wide enough to show.
    for si in 1..program.n_segments() {
        let wide =
            |s: usize| (bounds[s + 1] - bounds[s]) as f64 * lay.px_per_frame >= MIN_LINE_GAP_PX;
        if wide(si - 1) && wide(si) {
            let x = lay.fx(bounds[si] as f64);
            svg.line(x, lay.rows_top, x, lay.rows_bottom, style::PAPER, 0.8, "");
        }
    }
    // Repetition boundaries over the rows, where the repetitions are wide enough.
    for iv in repetitions {
        for (k, &bf) in iv.boundaries.iter().enumerate() {
            let before = k.checked_sub(1).map(|p| bf - iv.boundaries[p]);
            let after = iv.boundaries.get(k + 1).map(|n| n - bf);
            let wide = before
                .into_iter()
                .chain(after)
                .all(|n| n as f64 * lay.px_per_frame >= MIN_LINE_GAP_PX);
            if !wide {
                continue;
            }
            let x = lay.fx(bf as f64);
            svg.line(
                x,
                lay.loops_top + lay.loop_h,
                x,
                lay.rows_bottom,
                style::LOOP_DARK,
                1.2,
                r#"stroke-dasharray="3 2" stroke-opacity="0.8""#,
            );
        }
    }
}

/// Ticks in seconds and the axis label.
fn time_axis(svg: &mut Svg, lay: &Layout, program: &Program) {
    // Time axis.
    let fps = program.fps;
    let secs = lay.t_total as f64 / fps;
    for s in ticks(0.0, secs, 10) {
        let x = lay.fx(s * fps);
        svg.line(
            x,
            lay.rows_bottom,
            x,
            lay.rows_bottom + 5.0,
            style::MUTED,
            1.0,
            "",
        );
        svg.text(
            x,
            lay.rows_bottom + 18.0,
            &format!("{} s", tick_label(s)),
            11.0,
            style::MUTED,
            Anchor::Middle,
            "",
        );
    }
    svg.text(
        (lay.x0 + lay.x1) / 2.0,
        lay.rows_bottom + 36.0,
        &format!(
            "time ({} frames at {} fps)",
            lay.t_total,
            mp_geom::fps_label(fps)
        ),
        12.0,
        style::INK,
        Anchor::Middle,
        "",
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timeline_rows_and_loops() {
        let (_, program) = crate::plots::tests::tiny();
        let iv = RepetitiveInterval {
            start_frame: 0,
            end_frame: 16,
            body_size: 1,
            iterations: 2,
            boundaries: vec![0, 10, 16],
            count: 2,
            score: 1.0,
        };
        let lp = RepetitiveInterval {
            body_size: 1,
            ..iv.clone()
        };
        let (svg, axis) = timeline_svg(&program, &[iv], &[lp], &TimelineParams::default()).unwrap();
        assert!(svg.contains("×2"));
        assert!(svg.contains("program loop 1: frames 0–15, 2 iterations of 1 primitives"));
        assert!(svg.contains("interval 1: frames 0–15, 2 repetitions"));
        assert!(svg.contains("left_wrist"));
        assert!(svg.contains("data-frames=\"16\""));
        assert_eq!(axis.frames, 16);
        assert!(axis.x1_px > axis.x0_px);
        crate::raster::svg_to_png("timeline", &svg, 1.0).unwrap();
        let (svg, _) = timeline_svg(&program, &[], &[], &TimelineParams::default()).unwrap();
        assert!(svg.contains("no repetition counted"));
    }
}
