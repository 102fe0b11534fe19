//! The report's several people: a card per person, the person picker's
//! analyses and the people strip's rows.

use mp_abstract::RepetitiveInterval;
use mp_geom::Track;
use mp_report::Card;

use crate::{output, Keypoints, PersonOutcome, PipelineError, Result};

/// One report card per analysed person: their count, frames and the colour
/// of their skeleton in the overlay (the top-level person keeps the
/// left/right colours of the plots).
pub(crate) fn person_cards(people: &[PersonOutcome], fps: f64) -> Vec<Card> {
    if people.len() < 2 {
        return Vec::new();
    }
    // Everyone appears in the people strip; the cards are for the people
    // seen long enough to be analysed.
    people
        .iter()
        .filter(|p| p.counts.is_some())
        .map(|p| {
            let value = p
                .counts
                .as_ref()
                .map_or("–".to_string(), |c| c.total.to_string());
            let colour = if p.main {
                "left/right colours".to_string()
            } else {
                let [r, g, b] = output::person_colour(p.id);
                format!("colour #{r:02x}{g:02x}{b:02x}")
            };
            Card::new(
                format!("person {}{}", p.id, if p.main { " (main)" } else { "" }),
                value,
                format!(
                    "{} · {:.1}–{:.1} s · overlay {colour}",
                    "repetitions",
                    p.first_frame as f64 / fps,
                    p.last_frame as f64 / fps,
                ),
            )
        })
        .collect()
}

/// What the report's person picker needs beyond the outcome: each other
/// person's executed program and loops in their own frames, and the rows of
/// the people strip.
pub(crate) struct PeopleViews<'a> {
    main: &'a PersonOutcome,
    others: Vec<(&'a PersonOutcome, &'a Track, Track, Vec<RepetitiveInterval>)>,
    rows: Vec<mp_report::PersonRow>,
}

impl PeopleViews<'_> {
    pub(crate) fn view(&self) -> Result<mp_report::PeopleView<'_>> {
        let others = self
            .others
            .iter()
            .map(|(p, track, executed, intervals)| {
                let an = p.analysis.as_ref().ok_or_else(|| {
                    PipelineError::stage("the report", format!("person {} has no analysis", p.id))
                })?;
                let a = mp_report::Analysed {
                    track,
                    program: &an.concrete,
                    executed,
                    abstract_program: &an.program,
                    intervals,
                    frames: None,
                    frame_size: None,
                    title: "",
                };
                mp_report::person_view(
                    p.id,
                    person_label(p),
                    output::person_colour(p.id),
                    p.offset,
                    &a,
                )
                .map_err(PipelineError::from_report)
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(mp_report::PeopleView {
            main_id: self.main.id,
            main_label: person_label(self.main),
            others,
            rows: self.rows.clone(),
        })
    }
}

/// `person 3 (main) · 7 repetitions`.
fn person_label(p: &PersonOutcome) -> String {
    format!(
        "person {}{} · {}",
        p.id,
        if p.main { " (main)" } else { "" },
        match &p.counts {
            Some(c) if c.total == 1 => "1 repetition".to_string(),
            Some(c) => format!("{} repetitions", c.total),
            None => "seen briefly".to_string(),
        }
    )
}

/// The report's people (`None` with fewer than two people).
pub(crate) fn people_views<'a>(
    kp: &'a Keypoints,
    people: &'a [PersonOutcome],
    n_frames: usize,
) -> Result<Option<PeopleViews<'a>>> {
    let (Some(all), Some(main)) = (&kp.people, people.iter().find(|p| p.main)) else {
        return Ok(None);
    };
    if people.len() < 2 {
        return Ok(None);
    }
    let mut others = Vec::new();
    for p in people.iter().filter(|p| !p.main) {
        let (Some(an), Some(person), Some(c)) = (&p.analysis, all.get(p.id), &p.counts) else {
            continue;
        };
        let executed = an
            .concrete
            .execute()
            .map_err(|e| PipelineError::stage("executing the program", e))?;
        if executed.n_frames() != person.track.n_frames() {
            continue;
        }
        let intervals: Vec<RepetitiveInterval> = c
            .repetitive_intervals()
            .into_iter()
            .map(|mut iv| {
                iv.start_frame = iv.start_frame.saturating_sub(p.offset);
                iv.end_frame = iv.end_frame.saturating_sub(p.offset);
                for b in &mut iv.boundaries {
                    *b = b.saturating_sub(p.offset);
                }
                iv
            })
            .collect();
        others.push((p, &person.track, executed, intervals));
    }
    let rows = people
        .iter()
        .map(|p| {
            let pick = if p.main {
                Some(0)
            } else {
                others.iter().position(|o| o.0.id == p.id).map(|k| k + 1)
            };
            let found = all
                .get(p.id)
                .map(|person| mp_report::people::found_runs(&person.track, person.first_frame))
                .unwrap_or_default();
            let repetitions = p
                .counts
                .iter()
                .flat_map(|c| c.repetitive_intervals())
                .flat_map(|iv| {
                    iv.boundaries
                        .windows(2)
                        .map(|w| [w[0], w[1].min(n_frames)])
                        .collect::<Vec<_>>()
                })
                .collect();
            mp_report::PersonRow {
                id: p.id,
                label: person_label(p),
                colour: if p.main {
                    MAIN_COLOUR
                } else {
                    output::person_colour(p.id)
                },
                found,
                repetitions,
                pick,
            }
        })
        .collect();
    Ok(Some(PeopleViews { main, others, rows }))
}

/// The main person's colour in the people strip (the overlay draws them in
/// the left/right orange and blue; orange is their left).
const MAIN_COLOUR: [u8; 3] = [255, 159, 28];
