//! The terminal view of `mp live`: a few lines redrawn in place (ANSI cursor
//! movement) with each person's repetitions and how the run keeps up.

use std::collections::BTreeMap;
use std::io::Write;

use mp_live::Event;

/// What the view shows, updated by each event.
#[derive(Debug, Default)]
pub struct LiveView {
    /// Stream time of the last event, seconds.
    t: f64,
    /// The last status: frames analysed per second, frames dropped, seconds behind.
    status: Option<(f64, usize, f64)>,
    /// Each person's running total and whether they are still in view.
    people: BTreeMap<u32, (usize, bool)>,
    /// Lines drawn last time (moved over before drawing again).
    drawn: usize,
}

impl LiveView {
    /// Takes an event into account.
    pub fn update(&mut self, e: &Event) {
        match e {
            Event::Enter { person, t } => {
                self.t = *t;
                self.people.entry(*person).or_insert((0, true)).1 = true;
            }
            Event::Rep {
                person, count, t, ..
            } => {
                self.t = *t;
                self.people.entry(*person).or_insert((0, true)).0 = *count;
            }
            Event::Leave { person, t } => {
                self.t = *t;
                if let Some(p) = self.people.get_mut(person) {
                    p.1 = false;
                }
            }
            Event::Status {
                t,
                fps,
                dropped,
                delay,
                ..
            } => {
                self.t = *t;
                self.status = Some((*fps, *dropped, *delay));
            }
            _ => {}
        }
    }

    /// The view's lines: the stream time and how the run keeps up, then one
    /// line per person seen.
    pub fn lines(&self) -> Vec<String> {
        let mut out = vec![match self.status {
            Some((fps, dropped, delay)) => format!(
                "{:8.2} s  {fps:.1} fps  {dropped} frames dropped  {delay:.2} s behind",
                self.t
            ),
            None => format!("{:8.2} s", self.t),
        }];
        if self.people.is_empty() {
            out.push("nobody in view yet".into());
        }
        for (id, (reps, here)) in &self.people {
            let who = if *id == Event::SCENE {
                "the scene (no person counted)".to_string()
            } else {
                format!("person {id}")
            };
            out.push(format!(
                "{who}: {reps} repetition{}{}",
                if *reps == 1 { "" } else { "s" },
                if *here { "" } else { " (left)" }
            ));
        }
        out
    }

    /// Draws the lines over those drawn before (cursor up, each line cleared).
    pub fn draw(&mut self, w: &mut dyn Write) -> std::io::Result<()> {
        let lines = self.lines();
        let mut s = String::new();
        if self.drawn > 0 {
            s.push_str(&format!("\x1b[{}F", self.drawn));
        }
        for l in &lines {
            s.push_str("\x1b[2K");
            s.push_str(l);
            s.push('\n');
        }
        // Lines left over from a longer drawing are cleared.
        for _ in lines.len()..self.drawn {
            s.push_str("\x1b[2K\n");
        }
        let extra = self.drawn.saturating_sub(lines.len());
        if extra > 0 {
            s.push_str(&format!("\x1b[{extra}F"));
        }
        self.drawn = lines.len();
        w.write_all(s.as_bytes())?;
        w.flush()
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use mp_live::{PersonTotal, Summary};

    #[test]
    fn events_give_the_lines() {
        let mut v = LiveView::default();
        assert_eq!(v.lines(), vec!["    0.00 s", "nobody in view yet"]);
        let events = [
            Event::Enter { person: 1, t: 0.5 },
            Event::Enter { person: 3, t: 0.9 },
            Event::Status {
                t: 2.0,
                fps: 28.04,
                frames: 60,
                posed: 60,
                dropped: 2,
                delay: 0.126,
            },
            Event::Rep {
                person: 1,
                count: 1,
                start: 0.6,
                end: 1.7,
                t: 2.2,
            },
            Event::Rep {
                person: 1,
                count: 2,
                start: 1.7,
                end: 2.8,
                t: 3.3,
            },
            Event::Leave { person: 3, t: 3.5 },
        ];
        for e in &events {
            v.update(e);
        }
        assert_eq!(
            v.lines(),
            vec![
                "    3.50 s  28.0 fps  2 frames dropped  0.13 s behind",
                "person 1: 2 repetitions",
                "person 3: 0 repetitions (left)",
            ]
        );
        v.update(&Event::Rep {
            person: 3,
            count: 1,
            start: 3.0,
            end: 3.4,
            t: 3.6,
        });
        v.update(&Event::Summary(Summary {
            frames: 100,
            dropped: 2,
            t: 3.6,
            people: vec![PersonTotal {
                id: 1,
                total_repetitions: 2,
            }],
            ..Default::default()
        }));
        assert_eq!(v.lines()[2], "person 3: 1 repetition (left)");
    }

    #[test]
    fn drawing_again_moves_over_the_previous_lines() {
        let mut v = LiveView::default();
        let mut out = Vec::new();
        v.draw(&mut out).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "\x1b[2K    0.00 s\n\x1b[2Knobody in view yet\n"
        );
        v.update(&Event::Enter { person: 2, t: 1.0 });
        v.update(&Event::Enter { person: 4, t: 1.5 });
        let mut out = Vec::new();
        v.draw(&mut out).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            "\x1b[2F\x1b[2K    1.50 s\n\x1b[2Kperson 2: 0 repetitions\n\x1b[2Kperson 4: 0 repetitions\n"
        );
    }

    #[test]
    fn the_scene_is_named_as_such() {
        let mut v = LiveView::default();
        v.update(&Event::Rep {
            person: Event::SCENE,
            count: 2,
            start: 1.0,
            end: 2.0,
            t: 2.5,
        });
        assert_eq!(v.lines()[1], "the scene (no person counted): 2 repetitions");
    }
}
