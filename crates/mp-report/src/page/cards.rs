//! The summary cards at the top of the report: one figure and one line each,
//! for a recording of any length.

use std::fmt::Write as _;

use mp_abstract::Counts;
use mp_geom::Track;

use crate::page::ProgramView;
use crate::style::kind_color;

/// One summary card at the top of the report.
#[derive(Debug, Clone, PartialEq)]
pub struct Card {
    /// Small caption.
    pub label: String,
    /// The figure.
    pub value: String,
    /// One line under the figure.
    pub sub: String,
    /// Extra HTML under the figure (trusted, produced by this crate).
    pub extra_html: String,
}

impl Card {
    /// A card with a caption, a figure and a note.
    pub fn new(label: impl Into<String>, value: impl Into<String>, sub: impl Into<String>) -> Self {
        Card {
            label: label.into(),
            value: value.into(),
            sub: sub.into(),
            extra_html: String::new(),
        }
    }
}

/// Summary cards every report shows: frames, then with a program its
/// joints, segments, primitives by kind, fit error and size, then the
/// counted repetitions, then with a program the program loops.
pub fn standard_cards(
    track: &Track,
    program: Option<&ProgramView<'_>>,
    counts: &Counts,
) -> Vec<Card> {
    let t = track.n_frames();
    let fps = track.fps();
    let mut cards = vec![Card::new(
        "frames",
        t.to_string(),
        format!("{:.2} s at {} fps", t as f64 / fps, mp_geom::fps_label(fps)),
    )];
    if let Some(pv) = program {
        cards.extend(program_cards(track, pv));
    }
    cards.push(repetitions_card(counts));
    if let Some(pv) = program {
        let n = pv.abstract_program.loop_indices().len();
        cards.push(Card::new(
            "program loops",
            n.to_string(),
            "for statements of the abstract program (its structure)",
        ));
    }
    cards
}

fn program_cards(track: &Track, pv: &ProgramView<'_>) -> Vec<Card> {
    let program = pv.concrete;
    let t = program.n_frames();
    let mut cards = vec![
        Card::new(
            "joints",
            program.n_joints().to_string(),
            format!("skeleton {}, {}D", program.skeleton, program.dims),
        ),
        Card::new(
            "segments",
            program.n_segments().to_string(),
            format!(
                "{:.1} frames each on average",
                t as f64 / program.n_segments().max(1) as f64
            ),
        ),
    ];
    let counts = program.kind_counts();
    let total: usize = counts.iter().map(|(_, n)| *n).sum();
    let mut prim = Card::new(
        "primitives",
        total.to_string(),
        counts
            .iter()
            .filter(|(_, n)| *n > 0)
            .map(|(k, n)| format!("{n} {}", k.as_str()))
            .collect::<Vec<_>>()
            .join(" · "),
    );
    let mut bar = String::from(r#"<div class="kindbar">"#);
    for (k, n) in &counts {
        if *n > 0 {
            let _ = write!(
                bar,
                r#"<span style="width:{:.2}%;background:{}" title="{} {}"></span>"#,
                100.0 * *n as f64 / total.max(1) as f64,
                kind_color(*k),
                n,
                k.as_str()
            );
        }
    }
    bar.push_str("</div>");
    prim.extra_html = bar;
    cards.push(prim);
    let unit = track.units().as_str();
    if let Ok(kd) = mp_geom::kd(track, pv.executed) {
        cards.push(Card::new(
            "fit error (KD)",
            format!("{kd:.2} {unit}"),
            "mean keypoint distance, program vs keypoints",
        ));
    }
    let raw = t * program.n_joints() * program.dims;
    let np = program.n_params();
    cards.push(Card::new(
        "parameters",
        np.to_string(),
        format!(
            "{:.1}× fewer than the {raw} coordinates",
            raw as f64 / np.max(1) as f64
        ),
    ));
    cards
}

/// The repetitions card: the counted total, and in one line the signal,
/// method and confidence that decided and the intervals.
pub(crate) fn repetitions_card(counts: &Counts) -> Card {
    Card::new(
        "repetitions",
        counts.total.to_string(),
        format!(
            "from the {} ({}, confidence {:.2}) · {}",
            counts.signal.as_str(),
            counts.method.as_str(),
            counts.confidence,
            intervals_line(counts.intervals.iter().map(|i| i.count))
        ),
    )
}

/// Intervals named on the repetitions card before "and N more".
pub const CARD_INTERVALS: usize = 3;

/// "in 3 intervals: ×4, ×3, ×3": at most [`CARD_INTERVALS`] of them (those
/// with most repetitions, in time order) and "and N more".
pub(crate) fn intervals_line(counts: impl IntoIterator<Item = usize>) -> String {
    let counts: Vec<usize> = counts.into_iter().collect();
    if counts.is_empty() {
        return "no repetition counted".to_string();
    }
    let mut shown: Vec<usize> = (0..counts.len()).collect();
    shown.sort_by_key(|&i| std::cmp::Reverse(counts[i]));
    shown.truncate(CARD_INTERVALS);
    shown.sort_unstable();
    let list: Vec<String> = shown.iter().map(|&i| format!("×{}", counts[i])).collect();
    let more = counts.len() - shown.len();
    let n = counts.len();
    format!(
        "in {n} interval{}: {}{}",
        if n == 1 { "" } else { "s" },
        list.join(", "),
        if more > 0 {
            format!(" and {more} more")
        } else {
            String::new()
        }
    )
}

/// The cards' HTML.
pub(crate) fn cards_html(cards: &[Card]) -> String {
    let mut s = String::new();
    for c in cards {
        let _ = write!(
            s,
            r#"<div class="card"><div class="l">{}</div><div class="v">{}</div><div class="s">{}</div>{}</div>"#,
            crate::svg::esc(&c.label),
            crate::svg::esc(&c.value),
            crate::svg::esc(&c.sub),
            c.extra_html
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_intervals_line_stays_one_line() {
        assert_eq!(intervals_line([]), "no repetition counted");
        assert_eq!(intervals_line([4]), "in 1 interval: ×4");
        let line = intervals_line((0..300).map(|i| 1 + i % 9));
        assert!(line.starts_with("in 300 intervals: ×9, ×9, ×9"), "{line}");
        assert!(line.ends_with(" and 297 more"), "{line}");
        assert_eq!(line.matches('×').count(), CARD_INTERVALS);
    }
}
