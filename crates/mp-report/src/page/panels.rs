//! The contents of the report's panels for one person: the program listing's
//! statements, the counted repetitions, the program loops and the abstract
//! program. Frame ranges are written as [`mp_geom::frames_label`] writes
//! them (first–last, inclusive), in frames of the video.

use std::fmt::Write as _;

use mp_abstract::CountedInterval;
use mp_abstract::PrintOptions;
use mp_concrete::NumberFormat;
use mp_concrete::Program;
use mp_geom::frames_label;

use crate::page::ProgramView;
use crate::svg::esc;

/// Lines of the abstract program the page shows; the whole program is in
/// `abstract.txt`.
pub const ABSTRACT_PAGE_LINES: usize = 600;

/// Joint `ji`'s statements in the paper's notation, in segment order (the
/// page adds their frames from the segment boundaries).
pub fn joint_statements(program: &Program, ji: usize) -> Vec<String> {
    program
        .segments
        .iter()
        .filter_map(|s| s.dsl_statement(ji, NumberFormat::Fixed(2)))
        .collect()
}

/// `mp edit` command lines offered for each counted interval when the input
/// is a video (`--interval` is the interval's number as the table shows it,
/// from 1).
pub(crate) fn edit_command(title: &str, number: usize) -> Option<String> {
    const VIDEO: [&str; 6] = ["mp4", "mov", "avi", "webm", "mkv", "m4v"];
    let (stem, ext) = title.rsplit_once('.')?;
    if !VIDEO.contains(&ext.to_ascii_lowercase().as_str()) {
        return None;
    }
    let quote = |s: &str| {
        if s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "._-/".contains(c))
        {
            s.to_string()
        } else {
            format!("'{}'", s.replace('\'', r"'\''"))
        }
    };
    Some(format!(
        "mp edit {} --interval {number} --add 1 -o {}",
        quote(title),
        quote(&format!("{stem}_interval{number}_plus1.mp4"))
    ))
}

/// The counted repetitions: per interval its frames, seconds, count, period
/// and each repetition's frames (frames of the person's track, shown from
/// video frame `offset`); `title` (the video's file name, or empty) decides
/// whether the `mp edit` command is offered.
pub(crate) fn repetitions_table(
    intervals: &[CountedInterval],
    fps: f64,
    title: &str,
    offset: usize,
) -> String {
    if intervals.is_empty() {
        return r#"<div class="empty">No repetition was counted in this recording.</div>"#.into();
    }
    let editable = edit_command(title, 1).is_some();
    let mut s = String::from(
        r#"<table class="reps"><thead><tr><th>interval</th><th>frames</th><th>seconds</th><th>count</th><th>period</th><th>repetitions</th>"#,
    );
    if editable {
        s.push_str(r#"<th>repeat once more (copy)</th>"#);
    }
    s.push_str("</tr></thead><tbody>");
    for (i, iv) in intervals.iter().enumerate() {
        let mut chips = String::from(r#"<div class="iters">"#);
        for (k, w) in iv.boundaries.windows(2).enumerate() {
            let _ = write!(
                chips,
                r#"<span title="repetition {}: frames {}">{}</span>"#,
                k + 1,
                frames_label(w[0] + offset, w[1] + offset),
                k + 1
            );
        }
        chips.push_str("</div>");
        let (a, b) = (iv.start_frame + offset, iv.end_frame + offset);
        let _ = write!(
            s,
            r#"<tr><td>{}</td><td>{}</td><td>{:.2}–{:.2}</td><td class="count">×{}</td><td>{:.2} s</td><td>{chips}</td>"#,
            i + 1,
            frames_label(a, b),
            a as f64 / fps,
            b as f64 / fps,
            iv.count,
            iv.period_frames as f64 / fps,
        );
        if let Some(cmd) = edit_command(title, i + 1) {
            let _ = write!(s, r#"<td><code class="cmd">{}</code></td>"#, esc(&cmd));
        }
        s.push_str("</tr>");
    }
    s.push_str("</tbody></table>");
    s
}

/// The program loops (the abstract program's `for` statements) with their
/// frames, iterations and body, then the abstract program itself (at most
/// [`ABSTRACT_PAGE_LINES`] lines).
pub(crate) fn abstract_panel(pv: &ProgramView<'_>, fps: f64, offset: usize) -> String {
    let mut s = String::new();
    if pv.loops.is_empty() {
        s.push_str(r#"<div class="empty">The abstract program has no loop.</div>"#);
    } else {
        s.push_str(
            r#"<table class="ploops"><thead><tr><th>program loop</th><th>frames</th><th>seconds</th><th>iterations</th><th>body</th></tr></thead><tbody>"#,
        );
        for (i, lp) in pv.loops.iter().enumerate() {
            let (a, b) = (lp.start_frame + offset, lp.end_frame + offset);
            let _ = write!(
                s,
                r#"<tr><td>{}</td><td>{}</td><td>{:.2}–{:.2}</td><td>×{}</td><td>{} primitive{}</td></tr>"#,
                i + 1,
                frames_label(a, b),
                a as f64 / fps,
                b as f64 / fps,
                lp.iterations,
                lp.body_size,
                if lp.body_size == 1 { "" } else { "s" }
            );
        }
        s.push_str("</tbody></table>");
    }
    let text = pv.abstract_program.to_dsl_with(&PrintOptions::summary());
    let lines: Vec<&str> = text.lines().collect();
    let shown = lines.len().min(ABSTRACT_PAGE_LINES);
    let mut code = lines[..shown].join("\n");
    if shown < lines.len() {
        let _ = write!(
            code,
            "\n… {} more lines: the whole program is in abstract.txt",
            lines.len() - shown
        );
    }
    let _ = write!(s, r#"<pre class="code">{}</pre>"#, esc(&code));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn interval() -> CountedInterval {
        CountedInterval {
            start_frame: 0,
            end_frame: 30,
            period_frames: 15,
            cycles: 2.0,
            count: 2,
            boundaries: vec![0, 15, 30],
            signal: mp_abstract::CountSignal::Keypoints,
            periodicity: 0.9,
        }
    }

    #[test]
    fn video_intervals_offer_the_edit_command() {
        assert_eq!(
            edit_command("squats.mp4", 1).unwrap(),
            "mp edit squats.mp4 --interval 1 --add 1 -o squats_interval1_plus1.mp4"
        );
        assert_eq!(
            edit_command("my clip.MOV", 2).unwrap(),
            "mp edit 'my clip.MOV' --interval 2 --add 1 -o 'my clip_interval2_plus1.mp4'"
        );
        assert!(edit_command("track.npz", 1).is_none());
        let table = repetitions_table(&[interval()], 30.0, "a.mp4", 0);
        // The command names the interval by the number in the table's first
        // column; frames are inclusive; the period is in seconds.
        assert!(
            table.contains("<tr><td>1</td><td>0–29</td><td>0.00–1.00</td><td class=\"count\">×2</td><td>0.50 s</td>"),
            "{table}"
        );
        assert!(table.contains("repetition 2: frames 15–29"), "{table}");
        assert!(table.contains("mp edit a.mp4 --interval 1 "), "{table}");
        // Frames of the video for a person who appears later.
        let later = repetitions_table(&[interval()], 30.0, "", 100);
        assert!(later.contains("<td>100–129</td>"), "{later}");
        assert!(!later.contains("mp edit"));
    }
}
