//! The report's several people: the people card, everyone the person
//! picker can show and the people strip's rows.

use mp_abstract::CountedInterval;
use mp_geom::Track;
use mp_report::{Card, PersonPage, ProgramView};

use crate::{output, Keypoints, PersonOutcome, PipelineError, Result};

/// The people card (with two people or more): how many were tracked and how
/// many analysed, in one line whatever their number.
pub(crate) fn people_card(people: &[PersonOutcome]) -> Option<Card> {
    if people.len() < 2 {
        return None;
    }
    let analysed = people.iter().filter(|p| p.counts.is_some()).count();
    Some(Card::new(
        "people",
        people.len().to_string(),
        format!("tracked · {analysed} analysed · pick one in the People panel"),
    ))
}

/// What the report's person picker needs beyond the outcome: each other
/// analysed person's executed program and counted repetitions in their own
/// frames, and the rows of the people strip.
pub(crate) struct PeopleViews<'a> {
    main: &'a PersonOutcome,
    others: Vec<(&'a PersonOutcome, &'a Track, Track, Vec<CountedInterval>)>,
    pub(crate) rows: Vec<mp_report::PersonRow>,
}

impl PeopleViews<'_> {
    /// The main person's label in the picker.
    pub(crate) fn main_label(&self) -> String {
        person_label(self.main)
    }

    /// The people besides the main one, in the picker's order (from 1).
    pub(crate) fn pages(&self) -> Result<Vec<PersonPage<'_>>> {
        self.others
            .iter()
            .map(|(p, track, executed, repetitions)| {
                let an = p.analysis.as_ref().ok_or_else(|| {
                    PipelineError::stage("the report", format!("person {} has no analysis", p.id))
                })?;
                Ok(PersonPage {
                    id: Some(p.id),
                    label: person_label(p),
                    colour: Some(output::person_colour(p.id)),
                    offset: p.offset,
                    track,
                    program: Some(ProgramView {
                        concrete: &an.concrete,
                        executed,
                        abstract_program: &an.program,
                        loops: &an.intervals,
                    }),
                    repetitions: repetitions.clone(),
                })
            })
            .collect()
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
        // The counts are in video frames; the page wants the person's own.
        let repetitions: Vec<CountedInterval> = c
            .intervals
            .iter()
            .map(|iv| {
                let mut iv = iv.clone();
                iv.start_frame = iv.start_frame.saturating_sub(p.offset);
                iv.end_frame = iv.end_frame.saturating_sub(p.offset);
                for b in &mut iv.boundaries {
                    *b = b.saturating_sub(p.offset);
                }
                iv
            })
            .collect();
        others.push((p, &person.track, executed, repetitions));
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
                .map(|person| mp_report::found_runs(&person.track, person.first_frame))
                .unwrap_or_default();
            let repetitions = p
                .counts
                .iter()
                .flat_map(|c| c.intervals.iter())
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_people_card_of_one_line_for_any_crowd() {
        let person = |id: u32, analysed: bool| PersonOutcome {
            id,
            main: id == 1,
            first_frame: 0,
            last_frame: 10,
            frames_found: 11,
            mean_box: None,
            offset: 0,
            analysis: None,
            counts: analysed.then(|| {
                mp_abstract::count_repetitions(
                    &mp_geom::Track::new(
                        ndarray::Array3::zeros((8, 1, 2)),
                        None,
                        30.0,
                        mp_geom::Units::Pixels,
                        mp_geom::Skeleton::generic(1),
                    )
                    .unwrap(),
                    mp_abstract::CountSignal::Keypoints,
                    &Default::default(),
                )
                .unwrap()
            }),
        };
        assert!(people_card(&[person(1, true)]).is_none());
        let crowd: Vec<PersonOutcome> = (1..=300).map(|id| person(id, id % 3 == 0)).collect();
        let card = people_card(&crowd).unwrap();
        assert_eq!(card.value, "300");
        assert_eq!(
            card.sub,
            "tracked · 100 analysed · pick one in the People panel"
        );
    }
}
