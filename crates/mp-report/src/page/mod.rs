//! The report: `report.html` and its folder `report/` beside it.
//!
//! The page holds the summary cards, the people strip, the panels' frames,
//! its style and its script, and the little data every frame needs (joints,
//! bones, the frame list, who is on the page). Everything that grows with
//! the recording — the frames as JPEG files, each person's keypoints and
//! executed program in chunks of frames, their program listings, timeline,
//! tables and abstract program — lies in `report/` and is loaded as the page
//! plays and scrubs ([`data`] says how, and what bounds the sizes). A 10-s
//! clip and an hour take the same way and look the same.
//!
//! The page needs no network and works opened from disk. Its script records
//! problems in the hidden element `#mp-status` (`data-errors`, `data-ready`,
//! text `ok` when everything ran), which the browser test reads; the stage
//! says which frame's picture it shows (`data-picture`) and which frame's
//! keypoints it drew (`data-drawn`).

pub mod cards;
pub mod data;
mod html;
pub mod panels;

use mp_abstract::{AbstractProgram, CountedInterval, Counts, RepetitiveInterval};
use mp_concrete::Program;
use mp_geom::{PrimitiveKind, Track};
use serde_json::json;

use crate::error::{ReportError, Result};
use crate::frames::FrameStore;
use crate::outdir::OutputDir;
use crate::people::PersonRow;
use crate::plots::check_agree;
use crate::timeline::{timeline_svg, TimelineParams};

pub use cards::{standard_cards, Card};

/// A person's programs, when they have some.
#[derive(Debug, Clone, Copy)]
pub struct ProgramView<'a> {
    /// The concrete program.
    pub concrete: &'a Program,
    /// The program executed at the track's frames.
    pub executed: &'a Track,
    /// The abstract program.
    pub abstract_program: &'a AbstractProgram,
    /// The abstract program's loops (its `for` statements) as frame
    /// intervals of the track.
    pub loops: &'a [RepetitiveInterval],
}

/// One person on the page.
#[derive(Debug, Clone)]
pub struct PersonPage<'a> {
    /// The person's id, when people were tracked.
    pub id: Option<u32>,
    /// The picker's label (`person 3 · 7 repetitions`).
    pub label: String,
    /// Colour of their skeleton over the others' analyses (`None`: the
    /// left/right colours).
    pub colour: Option<[u8; 3]>,
    /// Video frame of the track's first frame.
    pub offset: usize,
    /// Their keypoints (all missing where nobody was found).
    pub track: &'a Track,
    /// Their programs (`None` where nobody was found).
    pub program: Option<ProgramView<'a>>,
    /// Their counted repetitions, in frames of `track`.
    pub repetitions: Vec<CountedInterval>,
}

/// Everything the report shows.
#[derive(Debug, Clone)]
pub struct ReportInput<'a> {
    /// Page title (e.g. the input's file name).
    pub title: &'a str,
    /// Line under the title (source, model, sizes).
    pub subtitle: &'a str,
    /// Everyone the page can show: the main person first (the page opens on
    /// them), then those its picker switches to.
    pub people: Vec<PersonPage<'a>>,
    /// The main person's counts (the repetitions card).
    pub counts: &'a Counts,
    /// Video frames, when the input was a video.
    pub frames: Option<&'a FrameStore>,
    /// A notice at the top of the page (e.g. that nobody was found).
    pub notice: Option<String>,
    /// Cards after the standard ones.
    pub cards: Vec<Card>,
    /// Other output files to link (paths relative to the page).
    pub files: &'a [String],
    /// The people strip's rows (everyone tracked), when people were tracked.
    pub strip: Option<Vec<PersonRow>>,
}

/// The page, not yet written, and the files written for it.
#[derive(Debug, Clone)]
pub struct ReportPage {
    /// `report.html`.
    pub html: String,
    /// The files in `report/` written for it, relative to the output folder.
    pub files: Vec<String>,
}

/// The page's file name.
pub const PAGE: &str = "report.html";

impl ReportPage {
    /// Writes `report.html` (after everything it loads, so that when it
    /// exists they do too).
    pub fn write(&self, out: &OutputDir) -> Result<std::path::PathBuf> {
        out.write(PAGE, self.html.as_bytes())
    }
}

/// Writes the page's folder `report/` into `out` and returns the page (write
/// it last, with [`ReportPage::write`]).
pub fn write_report(out: &OutputDir, input: &ReportInput<'_>) -> Result<ReportPage> {
    let main = input
        .people
        .first()
        .ok_or_else(|| ReportError::Mismatch("the report needs at least one person".into()))?;
    for p in &input.people {
        if let Some(pv) = &p.program {
            check_agree(p.track, pv.concrete)?;
            if pv.executed.positions().dim() != p.track.positions().dim() {
                return Err(ReportError::Mismatch(format!(
                    "person {}: the executed program is {:?}, the keypoints {:?}",
                    p.label,
                    pv.executed.positions().dim(),
                    p.track.positions().dim()
                )));
            }
        }
    }
    let mut files = Vec::new();
    let mut put = |rel: String, bytes: &[u8]| -> Result<()> {
        out.write(&rel, bytes)?;
        files.push(rel);
        Ok(())
    };
    // Frames.
    let pictures = input
        .frames
        .map(|s| data::frames_within_budget(s, data::FRAMES_BUDGET_BYTES))
        .unwrap_or_default();
    for (index, jpg) in &pictures {
        put(data::frame_file(*index), jpg)?;
    }
    // Per-frame data over everyone with a program, at one stride.
    let stride = data::data_stride(
        input
            .people
            .iter()
            .filter(|p| p.program.is_some())
            .map(|p| (p.track.n_frames(), data::values_per_frame(p.track))),
    );
    let mut meta = Vec::new();
    for (k, p) in input.people.iter().enumerate() {
        let dir = format!("{}/p{k}", data::FOLDER);
        let reg =
            |kind: &str, key: String, v: &serde_json::Value| data::registration(kind, &key, v);
        let chunks = match &p.program {
            Some(pv) => {
                let n = data::data_frames(p.track.n_frames(), stride);
                let chunks = n.div_ceil(data::CHUNK_FRAMES);
                for c in 0..chunks {
                    let first = c * data::CHUNK_FRAMES;
                    let len = data::CHUNK_FRAMES.min(n - first);
                    let v = data::chunk(p.track, pv.executed, stride, first, len)?;
                    put(
                        format!("{dir}/data-{c:04}.js"),
                        reg("chunk", format!("{k}/{c}"), &v)?.as_bytes(),
                    )?;
                }
                for ji in 0..p.track.n_joints() {
                    let v = json!({
                        "listing": panels::joint_statements(pv.concrete, ji),
                        "overview": data::overview(p.track, pv.executed, ji),
                    });
                    put(
                        format!("{dir}/joint-{ji:02}.js"),
                        reg("joint", format!("{k}/{ji}"), &v)?.as_bytes(),
                    )?;
                }
                chunks
            }
            None => 0,
        };
        let person = person_content(if k == 0 { input.title } else { "" }, p)?;
        put(
            format!("{dir}/person.js"),
            reg("person", k.to_string(), &person)?.as_bytes(),
        )?;
        meta.push(json!({
            "id": p.id,
            "label": p.label,
            "colour": p.colour.map(crate::style::hex),
            "offset": p.offset,
            "frames": p.track.n_frames(),
            "chunks": chunks,
            "program": p.program.is_some(),
        }));
    }
    let html = html::page(input, main, &pictures, stride, meta)?;
    Ok(ReportPage { html, files })
}

/// A person's structure file: segment boundaries and kinds, the joint the
/// page selects first, counted repetitions, and the HTML of their panels.
/// `title` (the video's file name for the main person, else empty) decides
/// whether the repetitions table offers the `mp edit` command.
fn person_content(title: &str, p: &PersonPage<'_>) -> Result<serde_json::Value> {
    let fps = p.track.fps();
    let reps: Vec<serde_json::Value> = p
        .repetitions
        .iter()
        .map(|iv| {
            json!({
                "start": iv.start_frame, "end": iv.end_frame,
                "boundaries": iv.boundaries, "count": iv.count,
            })
        })
        .collect();
    let mut v = json!({
        "span": p.track.found_span().map(|(a, b)| [a, b]),
        "repetitions": reps,
        "repetitionsHtml": panels::repetitions_table(&p.repetitions, fps, title, p.offset),
    });
    if let (Some(pv), Some(obj)) = (&p.program, v.as_object_mut()) {
        let program = pv.concrete;
        let kinds: Vec<String> = (0..program.n_joints())
            .map(|ji| {
                program
                    .segments
                    .iter()
                    .map(|s| {
                        let k = s
                            .primitives
                            .get(ji)
                            .and_then(|p| PrimitiveKind::ALL.iter().position(|x| *x == p.kind()))
                            .unwrap_or(0);
                        char::from(b'0' + k as u8)
                    })
                    .collect()
            })
            .collect();
        let counted: Vec<RepetitiveInterval> = p
            .repetitions
            .iter()
            .map(CountedInterval::to_interval)
            .collect();
        let (timeline, _) = timeline_svg(
            program,
            &counted,
            pv.loops,
            &TimelineParams {
                title: false,
                ..TimelineParams::default()
            },
        )?;
        obj.insert("bounds".into(), json!(program.boundaries()));
        obj.insert("kinds".into(), json!(kinds));
        obj.insert("defaultJoint".into(), json!(most_moving_joint(p.track)));
        obj.insert(
            "header".into(),
            json!(program.dsl_header(mp_concrete::NumberFormat::Fixed(2))),
        );
        obj.insert("timeline".into(), json!(timeline));
        obj.insert(
            "abstractHtml".into(),
            json!(panels::abstract_panel(pv, fps, p.offset)),
        );
    }
    Ok(v)
}

/// The joint that moves most (largest spread of its valid positions).
pub(crate) fn most_moving_joint(track: &Track) -> usize {
    let (t, j, d) = track.positions().dim();
    let mut best = (0usize, -1.0f64);
    for ji in 0..j {
        let mut spread = 0.0;
        for k in 0..d {
            let vals: Vec<f64> = (0..t)
                .filter(|&ti| track.confidence()[[ti, ji]] > 0.3)
                .map(|ti| track.positions()[[ti, ji, k]])
                .filter(|v| v.is_finite())
                .collect();
            if vals.len() < 2 {
                continue;
            }
            let m = vals.iter().sum::<f64>() / vals.len() as f64;
            spread += vals.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / vals.len() as f64;
        }
        if spread > best.1 {
            best = (ji, spread);
        }
    }
    best.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use mp_abstract::{CountFeatures, CountMethod, CountSignal};

    fn counts(frames: usize, intervals: Vec<CountedInterval>) -> Counts {
        Counts {
            total: intervals.iter().map(|i| i.count).sum(),
            intervals,
            signal: CountSignal::Frames,
            method: CountMethod::Period,
            confidence: 0.5,
            periodicity: 0.5,
            features: CountFeatures::default(),
            frames,
            fps: 30.0,
        }
    }

    fn read(dir: &std::path::Path, rel: &str) -> (String, String, serde_json::Value) {
        let text = std::fs::read_to_string(dir.join(rel)).unwrap();
        data::registered(&text).unwrap_or_else(|| panic!("{rel} is not a registration"))
    }

    #[test]
    fn the_page_loads_its_data_from_the_folder() {
        let (track, program) = crate::plots::tests::tiny();
        let exec = program.execute().unwrap();
        let (abs, _, _) = mp_abstract::AbstractProgram::from_concrete(
            &program,
            &mp_abstract::LoopParams::default(),
        )
        .unwrap();
        let reps = vec![CountedInterval {
            start_frame: 2,
            end_frame: 12,
            period_frames: 5,
            cycles: 2.0,
            count: 2,
            boundaries: vec![2, 7, 12],
            signal: mp_abstract::CountSignal::Keypoints,
            periodicity: 0.9,
        }];
        let c = counts(16, reps.clone());
        let tmp = tempfile::tempdir().unwrap();
        let out = OutputDir::create(tmp.path()).unwrap();
        let input = ReportInput {
            title: "tiny <test>",
            subtitle: "sub",
            people: vec![PersonPage {
                id: None,
                label: "the person".into(),
                colour: None,
                offset: 0,
                track: &track,
                program: Some(ProgramView {
                    concrete: &program,
                    executed: &exec,
                    abstract_program: &abs,
                    loops: &[],
                }),
                repetitions: reps,
            }],
            counts: &c,
            frames: None,
            notice: None,
            cards: Vec::new(),
            files: &["program.txt".into()],
            strip: None,
        };
        let page = write_report(&out, &input).unwrap();
        page.write(&out).unwrap();
        let html = std::fs::read_to_string(tmp.path().join(PAGE)).unwrap();
        assert!(html.contains("tiny &lt;test&gt;"));
        assert!(!html.contains("https://") && !html.contains("data:image"));
        // One card each for the repetitions and the program loops.
        assert_eq!(
            html.matches(r#"<div class="l">repetitions</div>"#).count(),
            1
        );
        assert_eq!(
            html.matches(r#"<div class="l">program loops</div>"#)
                .count(),
            1
        );
        assert!(!html.contains(r#"<div class="l">count</div>"#));
        assert_eq!(
            page.files,
            [
                "report/p0/data-0000.js",
                "report/p0/joint-00.js",
                "report/p0/joint-01.js",
                "report/p0/person.js"
            ]
        );
        let (kind, key, person) = read(tmp.path(), "report/p0/person.js");
        assert_eq!((kind.as_str(), key.as_str()), ("person", "0"));
        assert_eq!(person["bounds"], json!([0, 10, 16]));
        assert_eq!(person["kinds"][1], "12"); // line, circle
        let reps_html = person["repetitionsHtml"].as_str().unwrap();
        assert!(reps_html.contains("<td>2–11</td>"), "{reps_html}");
        assert!(
            reps_html.contains("repetition 2: frames 7–11"),
            "{reps_html}"
        );
        assert!(!reps_html.contains("primitives"), "{reps_html}");
        let (_, _, joint) = read(tmp.path(), "report/p0/joint-01.js");
        let listing = joint["listing"].as_array().unwrap();
        assert_eq!(listing.len(), 2);
        assert!(listing[1].as_str().unwrap().starts_with("circular_motion("));
        assert_eq!(joint["overview"]["step"], 1);
        // The chunk holds the keypoints, to 0.1 px.
        let (_, _, chunk) = read(tmp.path(), "report/p0/data-0000.js");
        assert_eq!(chunk["n"], 16);
        let kp = data::unpack(chunk["kp"].as_str().unwrap(), 4).unwrap();
        assert_eq!(kp.len(), 16 * 2 * 2);
        for (i, v) in kp.iter().enumerate() {
            let (t, j, k) = (i / 4, (i / 2) % 2, i % 2);
            assert!((*v as f64 * 0.1 - track.positions()[[t, j, k]]).abs() <= 0.05 + 1e-9);
        }
        // The page's own data.
        let start = html.find("id=\"mp-data\">").unwrap() + "id=\"mp-data\">".len();
        let end = start + html[start..].find("</script>").unwrap();
        let d: serde_json::Value = serde_json::from_str(&html[start..end]).unwrap();
        assert_eq!(d["people"][0]["frames"], 16);
        assert_eq!(d["people"][0]["chunks"], 1);
        assert_eq!(d["stride"], 1);
    }

    #[test]
    fn a_recording_without_anybody_gets_frames_and_counts() {
        let (track, _) = crate::plots::tests::tiny();
        let nobody = Track::new(
            ndarray::Array3::from_elem(track.positions().dim(), f64::NAN),
            None,
            30.0,
            track.units(),
            track.skeleton().clone(),
        )
        .unwrap();
        let mut store = FrameStore::new(40, 30, Some(16), &Default::default()).unwrap();
        for i in 0..16 {
            store.push(i, &vec![(i * 12) as u8; 40 * 30 * 3]).unwrap();
        }
        let c = counts(16, Vec::new());
        let tmp = tempfile::tempdir().unwrap();
        let out = OutputDir::create(tmp.path()).unwrap();
        let input = ReportInput {
            title: "empty.mp4",
            subtitle: "",
            people: vec![PersonPage {
                id: None,
                label: "nobody".into(),
                colour: None,
                offset: 0,
                track: &nobody,
                program: None,
                repetitions: Vec::new(),
            }],
            counts: &c,
            frames: Some(&store),
            notice: Some("No person was found in this video".into()),
            cards: Vec::new(),
            files: &[],
            strip: None,
        };
        let page = write_report(&out, &input).unwrap();
        assert!(page
            .html
            .contains(r#"id="notice">No person was found in this video"#));
        for panel in [
            "id=\"program\"",
            "id=\"timeline\"",
            "id=\"abstract\"",
            "program loops",
        ] {
            assert!(!page.html.contains(panel), "{panel}");
        }
        assert!(page.html.contains(r#"id="repetitions""#));
        assert!(page.html.contains(r#"<div class="l">repetitions</div>"#));
        assert_eq!(page.files.len(), 16 + 1, "{:?}", page.files);
        assert!(page.files.contains(&"report/frames/000015.jpg".to_string()));
        let (_, _, person) = read(tmp.path(), "report/p0/person.js");
        assert!(person["repetitionsHtml"]
            .as_str()
            .unwrap()
            .contains("No repetition was counted"));
        assert!(person.get("bounds").is_none());
    }
}
