//! The timeline: one row per joint with its primitives coloured by kind, a
//! row with the mix of kinds per segment, and the detected loops with their
//! iteration boundaries and repetition counts, over a common time axis.

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

/// The timeline as an SVG document and its time axis. The root element
/// carries `data-x0`, `data-x1`, `data-top`, `data-bottom` and `data-frames`.
pub fn timeline_svg(
    program: &Program,
    intervals: &[RepetitiveInterval],
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
    let t_total = program.n_frames();
    if t_total == 0 {
        return Err(ReportError::Mismatch("the program has no frames".into()));
    }
    let j = program.n_joints();
    let rh = params.row_height_px;
    let label_w = 118.0;
    let (x0, x1) = (label_w + 12.0, params.width_px - 18.0);
    let fx = |f: f64| x0 + f / t_total as f64 * (x1 - x0);
    let title_h = if params.title { 50.0 } else { 34.0 };
    let mix_top = title_h;
    let mix_h = 30.0;
    let loops_top = mix_top + mix_h + 10.0;
    let loop_h = 40.0;
    let rows_top = loops_top + loop_h + 14.0;
    let rows_bottom = rows_top + j as f64 * rh;
    let h = rows_bottom + 46.0;
    let bounds = program.boundaries();

    let mut svg = Svg::new(params.width_px, h, style::PAPER);
    let reps: usize = intervals.iter().map(|i| i.count).sum();
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
    svg.text(
        18.0,
        if params.title { 42.0 } else { 24.0 },
        &format!(
            "{} segments × {} joints · {} loop{} · {} repetitions",
            program.n_segments(),
            j,
            intervals.len(),
            if intervals.len() == 1 { "" } else { "s" },
            reps
        ),
        11.5,
        style::MUTED,
        Anchor::Start,
        "",
    );
    // Legend.
    let mut lx = x1;
    for k in PrimitiveKind::ALL.iter().rev() {
        let label = k.as_str();
        svg.text(lx, 24.0, label, 11.5, style::INK, Anchor::End, "");
        lx -= 7.0 * label.len() as f64 + 8.0;
        svg.rect(lx - 12.0, 15.0, 12.0, 11.0, kind_color(*k), r#"rx="2""#);
        lx -= 26.0;
    }
    svg.text(lx, 24.0, "loop", 11.5, style::INK, Anchor::End, "");
    lx -= 36.0;
    svg.rect(lx - 12.0, 15.0, 12.0, 11.0, style::LOOP_FILL, r#"rx="2""#);

    // Mix of kinds per segment.
    svg.text(
        label_w,
        mix_top + mix_h / 2.0 + 4.0,
        "kinds per segment",
        11.0,
        style::INK,
        Anchor::End,
        "",
    );
    for (si, seg) in program.segments.iter().enumerate() {
        let (a, b) = (fx(bounds[si] as f64), fx(bounds[si + 1] as f64));
        let n = seg.primitives.len().max(1) as f64;
        let mut y = mix_top;
        for k in PrimitiveKind::ALL {
            let c = seg.primitives.iter().filter(|p| p.kind() == k).count() as f64;
            if c > 0.0 {
                let hh = mix_h * c / n;
                svg.rect(a, y, (b - a).max(0.5), hh, kind_color(k), "");
                y += hh;
            }
        }
        svg.line(b, mix_top, b, mix_top + mix_h, style::PAPER, 0.8, "");
    }

    // Loops.
    svg.text(
        label_w,
        loops_top + loop_h / 2.0 + 4.0,
        "loops",
        11.0,
        style::INK,
        Anchor::End,
        "",
    );
    svg.rect(x0, loops_top, x1 - x0, loop_h, "#f1f5f9", r#"rx="3""#);
    for (li, iv) in intervals.iter().enumerate() {
        let (a, b) = (fx(iv.start_frame as f64), fx(iv.end_frame as f64));
        svg.rect(
            a,
            loops_top + 3.0,
            b - a,
            loop_h - 6.0,
            style::LOOP_FILL,
            r#"fill-opacity="0.85" rx="3""#,
        );
        let inner = iv.boundaries.len().saturating_sub(2);
        for &bf in iv.boundaries.iter().skip(1).take(inner) {
            let x = fx(bf as f64);
            svg.line(
                x,
                loops_top + 3.0,
                x,
                loops_top + loop_h - 3.0,
                style::PAPER,
                1.5,
                "",
            );
        }
        // Iteration numbers, where they fit.
        for (k, w) in iv.boundaries.windows(2).enumerate() {
            let (ia, ib) = (fx(w[0] as f64), fx(w[1] as f64));
            if ib - ia >= 14.0 {
                svg.text(
                    (ia + ib) / 2.0,
                    loops_top + loop_h - 7.0,
                    &(k + 1).to_string(),
                    9.5,
                    "#ffffff",
                    Anchor::Middle,
                    r#"fill-opacity="0.85""#,
                );
            }
        }
        // The count in a dark label in the middle of the loop.
        let label = format!("×{}", iv.count);
        let cx = (a + b) / 2.0;
        let lw = 12.0 + 8.5 * label.chars().count() as f64;
        if b - a >= lw + 4.0 {
            svg.rect(
                cx - lw / 2.0,
                loops_top + 6.0,
                lw,
                19.0,
                style::LOOP_DARK,
                r#"rx="9""#,
            );
            svg.text(
                cx,
                loops_top + 20.0,
                &label,
                13.0,
                "#ffffff",
                Anchor::Middle,
                r#"font-weight="bold""#,
            );
        } else {
            svg.text(
                cx,
                loops_top - 2.0,
                &label,
                11.0,
                style::LOOP_DARK,
                Anchor::Middle,
                r#"font-weight="bold""#,
            );
        }
        svg.raw(&format!(
            "<title>loop {}: frames {}, {} iterations of {} primitives</title>\n",
            li + 1,
            mp_geom::frames_label(iv.start_frame, iv.end_frame),
            iv.iterations,
            iv.body_size
        ));
    }
    if intervals.is_empty() {
        svg.text(
            (x0 + x1) / 2.0,
            loops_top + loop_h / 2.0 + 4.0,
            "no repetition detected",
            11.0,
            style::MUTED,
            Anchor::Middle,
            "",
        );
    }

    // One row per joint.
    for ji in 0..j {
        let y = rows_top + ji as f64 * rh;
        let name = program.joints.get(ji).map(String::as_str).unwrap_or("?");
        svg.text(
            label_w,
            y + rh * 0.8,
            name,
            (rh * 0.78).min(11.0),
            style::INK,
            Anchor::End,
            "",
        );
        for (si, seg) in program.segments.iter().enumerate() {
            let Some(p) = seg.primitives.get(ji) else {
                continue;
            };
            let (a, b) = (fx(bounds[si] as f64), fx(bounds[si + 1] as f64));
            svg.rect(
                a,
                y + 0.5,
                (b - a).max(0.5),
                rh - 1.0,
                kind_color(p.kind()),
                "",
            );
        }
    }
    // Segment boundaries over the rows.
    for &b in bounds.iter().skip(1).take(bounds.len().saturating_sub(2)) {
        let x = fx(b as f64);
        svg.line(x, rows_top, x, rows_bottom, style::PAPER, 0.8, "");
    }
    // Loop iteration boundaries over the rows.
    for iv in intervals {
        for &bf in &iv.boundaries {
            let x = fx(bf as f64);
            svg.line(
                x,
                loops_top + loop_h,
                x,
                rows_bottom,
                style::LOOP_DARK,
                1.2,
                r#"stroke-dasharray="3 2" stroke-opacity="0.8""#,
            );
        }
    }
    // Time axis.
    let fps = program.fps;
    let secs = t_total as f64 / fps;
    for s in ticks(0.0, secs, 10) {
        let x = fx(s * fps);
        svg.line(x, rows_bottom, x, rows_bottom + 5.0, style::MUTED, 1.0, "");
        svg.text(
            x,
            rows_bottom + 18.0,
            &format!("{} s", tick_label(s)),
            11.0,
            style::MUTED,
            Anchor::Middle,
            "",
        );
    }
    svg.text(
        (x0 + x1) / 2.0,
        rows_bottom + 36.0,
        &format!("time ({t_total} frames at {} fps)", mp_geom::fps_label(fps)),
        12.0,
        style::INK,
        Anchor::Middle,
        "",
    );
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
        let (svg, axis) = timeline_svg(&program, &[iv], &TimelineParams::default()).unwrap();
        assert!(svg.contains("×2"));
        assert!(svg.contains("left_wrist"));
        assert!(svg.contains("data-frames=\"16\""));
        assert_eq!(axis.frames, 16);
        assert!(axis.x1_px > axis.x0_px);
        crate::raster::svg_to_png("timeline", &svg, 1.0).unwrap();
        let (svg, _) = timeline_svg(&program, &[], &TimelineParams::default()).unwrap();
        assert!(svg.contains("no repetition detected"));
    }
}
