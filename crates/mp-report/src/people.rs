//! Several people on the report page: the people strip — one row per person
//! over the video's time axis, in the person's overlay colour, with their
//! repetitions.

use std::fmt::Write as _;

use mp_geom::Track;

use crate::svg::esc;

/// One row of the people strip.
#[derive(Debug, Clone, PartialEq)]
pub struct PersonRow {
    /// The person's id.
    pub id: u32,
    /// Row label.
    pub label: String,
    /// Colour of the row's bars.
    pub colour: [u8; 3],
    /// Runs of video frames with a pose, `[first, last]`.
    pub found: Vec<[usize; 2]>,
    /// Counted repetitions as video frame ranges `[start, end)`.
    pub repetitions: Vec<[usize; 2]>,
    /// Index of the person in the page's picker (0: the main person), when
    /// the page can show their analysis.
    pub pick: Option<usize>,
}

/// Runs of frames where `track` has any joint with confidence > 0, as
/// `[first, last]` video frames (`offset` is the track's first frame).
pub fn found_runs(track: &Track, offset: usize) -> Vec<[usize; 2]> {
    let conf = track.confidence();
    let mut runs: Vec<[usize; 2]> = Vec::new();
    for t in 0..track.n_frames() {
        if !conf.row(t).iter().any(|&c| c > 0.0) {
            continue;
        }
        let f = t + offset;
        match runs.last_mut() {
            Some(r) if r[1] + 1 == f => r[1] = f,
            _ => runs.push([f, f]),
        }
    }
    runs
}

/// Pixel spans `[a, b)` of frame ranges on the strip, those less than a
/// pixel apart joined into one when either is narrower than `keep_px`
/// (wider ones keep their own outline): a row has at most a span per
/// `keep_px` pixels of the time axis, whatever the recording's length.
fn spans(ranges: impl IntoIterator<Item = (f64, f64)>, keep_px: f64) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    for (a, b) in ranges {
        match out.last_mut() {
            Some(last) if a - last.1 < 1.0 && (last.1 - last.0 < keep_px || b - a < keep_px) => {
                last.1 = last.1.max(b)
            }
            _ => out.push((a, b)),
        }
    }
    out
}

/// The people strip: a row per person (label, the frames they were seen as
/// bars in their colour, each counted repetition as a darker tick-bounded
/// block; spans less than a pixel apart drawn as one), over `n_frames`
/// frames at `fps`. Rows with an analysis carry `data-person` (the picker's
/// index) for the page's script.
pub(crate) fn people_strip_svg(rows: &[PersonRow], n_frames: usize, fps: f64) -> String {
    let (left, right, row_h, top) = (215.0, 16.0, 22.0, 8.0);
    let width = 1100.0;
    let axis_h = 24.0;
    let height = top + row_h * rows.len() as f64 + axis_h;
    let span = n_frames.max(1) as f64;
    let x = |f: usize| left + (width - left - right) * f as f64 / span;
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg class="mp-people" xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {width} {height}" data-x0="{left}" data-x1="{}" data-top="{top}" data-bottom="{}" font-family="system-ui, 'DejaVu Sans', sans-serif" font-size="12">"#,
        width - right,
        top + row_h * rows.len() as f64
    );
    for (i, r) in rows.iter().enumerate() {
        let y = top + row_h * i as f64;
        let [cr, cg, cb] = r.colour;
        let colour = format!("#{cr:02x}{cg:02x}{cb:02x}");
        let pick = r
            .pick
            .map(|k| format!(r#" data-person="{k}" style="cursor:pointer""#))
            .unwrap_or_default();
        let _ = write!(
            s,
            r#"<g class="row"{pick}><title>{}</title>"#,
            esc(&r.label)
        );
        let _ = write!(
            s,
            r##"<rect x="0" y="{y}" width="{width}" height="{row_h}" fill="{}"/>"##,
            if i % 2 == 0 { "#f8fafc" } else { "#ffffff" }
        );
        let _ = write!(
            s,
            r##"<text x="8" y="{}" fill="#0f172a">{}</text>"##,
            y + row_h * 0.68,
            esc(&r.label)
        );
        for (a, b) in spans(
            r.found.iter().map(|run| (x(run[0]), x(run[1] + 1))),
            f64::INFINITY,
        ) {
            let _ = write!(
                s,
                r#"<rect x="{a:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{colour}" fill-opacity="0.45"/>"#,
                y + 5.0,
                (b - a).max(1.0),
                row_h - 10.0
            );
        }
        for (a, b) in spans(r.repetitions.iter().map(|rep| (x(rep[0]), x(rep[1]))), 2.0) {
            let _ = write!(
                s,
                r##"<rect x="{a:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{colour}" stroke="#0f172a" stroke-width="0.8"/>"##,
                y + 3.0,
                (b - a).max(1.0),
                row_h - 6.0
            );
        }
        s.push_str("</g>");
    }
    // Time axis in seconds.
    let y_axis = top + row_h * rows.len() as f64;
    let seconds = n_frames as f64 / fps.max(1e-9);
    let step = [1.0, 2.0, 5.0, 10.0, 15.0, 30.0, 60.0, 120.0, 300.0, 600.0]
        .into_iter()
        .find(|st| seconds / st <= 12.0)
        .unwrap_or(1200.0);
    let mut t = 0.0;
    while t <= seconds + 1e-9 {
        let xf = x((t * fps).round() as usize);
        let _ = write!(
            s,
            r##"<line x1="{xf:.1}" y1="{top}" x2="{xf:.1}" y2="{:.1}" stroke="#cbd5e1" stroke-width="0.6"/><text x="{xf:.1}" y="{:.1}" text-anchor="middle" fill="#64748b">{t} s</text>"##,
            y_axis + 4.0,
            y_axis + 17.0
        );
        t += step;
    }
    s.push_str("</svg>");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_strip_has_a_row_per_person_with_their_runs_and_repetitions() {
        let rows = vec![
            PersonRow {
                id: 1,
                label: "person 1 (main) · 2".into(),
                colour: [255, 159, 28],
                found: vec![[0, 49], [60, 99]],
                repetitions: vec![[10, 30], [30, 50]],
                pick: Some(0),
            },
            PersonRow {
                id: 2,
                label: "person 2 <b>".into(),
                colour: [0, 158, 115],
                found: vec![[20, 40]],
                repetitions: vec![],
                pick: None,
            },
        ];
        let svg = people_strip_svg(&rows, 100, 10.0);
        assert_eq!(svg.matches(r#"<g class="row""#).count(), 2);
        assert_eq!(svg.matches(r#"data-person="0""#).count(), 1);
        assert!(svg.contains("person 2 &lt;b&gt;"));
        assert!(svg.contains("#009e73"), "the second person's colour");
        // Two runs and two repetitions for the first person, one run for the second.
        assert_eq!(svg.matches(r#"fill-opacity="0.45""#).count(), 3);
        assert_eq!(svg.matches(r##"stroke="#0f172a""##).count(), 2);
        assert!(svg.contains(">10 s</text>"));
        // An hour of one-second repetitions stays one block per pixel at most.
        let hour = vec![PersonRow {
            id: 1,
            label: "person 1".into(),
            colour: [255, 159, 28],
            found: (0..3600).map(|s| [s * 30, s * 30 + 20]).collect(),
            repetitions: (0..3600).map(|s| [s * 30, s * 30 + 30]).collect(),
            pick: Some(0),
        }];
        let svg = people_strip_svg(&hour, 108_000, 30.0);
        assert!(svg.len() < 200_000, "{} bytes", svg.len());
    }

    #[test]
    fn runs_of_found_frames_are_in_video_frames() {
        let mut p = ndarray::Array3::from_elem((6, 1, 2), f64::NAN);
        for t in [0usize, 1, 3, 4, 5] {
            p[[t, 0, 0]] = 1.0;
            p[[t, 0, 1]] = 1.0;
        }
        let tr = Track::new(
            p,
            None,
            30.0,
            mp_geom::Units::Pixels,
            mp_geom::Skeleton::generic(1),
        )
        .unwrap();
        assert_eq!(found_runs(&tr, 10), vec![[10, 11], [13, 15]]);
    }
}
