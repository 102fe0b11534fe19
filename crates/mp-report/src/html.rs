//! The report: one self-contained HTML page (inline CSS, JavaScript and
//! SVG; frames embedded as base64 JPEG) with the frames and the skeleton
//! animated in sync, play/pause and a scrubber, the program listing with the
//! running statement highlighted, the loop timeline with a moving cursor,
//! the repetition counts and a per-joint trajectory plot.
//!
//! The page needs no network. Its script records problems in the hidden
//! element `#mp-status` (`data-errors`, `data-ready`, text `ok` when
//! everything ran), which the browser test reads.

use std::fmt::Write as _;

use mp_abstract::RepetitiveInterval;
use mp_concrete::dsl::{header, statement, NumberFormat};
use mp_concrete::Program;
use mp_geom::{PrimitiveKind, Track, Units};
use serde_json::json;

use crate::b64;
use crate::draw::View;
use crate::error::{ReportError, Result};
use crate::frames::FrameStore;
use crate::people::{people_strip_svg, PeopleView};
use crate::plots::{axis_label, check_agree};
use crate::style::{kind_color, side};
use crate::svg::esc;

const CSS: &str = include_str!("../assets/report.css");
const JS: &str = include_str!("../assets/report.js");

/// One summary card at the top of the report.
#[derive(Debug, Clone, PartialEq)]
pub struct Card {
    /// Small caption.
    pub label: String,
    /// The figure.
    pub value: String,
    /// A line under the figure.
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

/// Everything the report shows.
#[derive(Debug, Clone, Copy)]
pub struct ReportInput<'a> {
    /// Page title (e.g. the input's file name).
    pub title: &'a str,
    /// Line under the title (source, model, sizes).
    pub subtitle: &'a str,
    /// The keypoints.
    pub track: &'a Track,
    /// The concrete program fitted to them.
    pub program: &'a Program,
    /// The program executed at the track's frames.
    pub executed: &'a Track,
    /// The abstract program in the paper's notation.
    pub abstract_text: &'a str,
    /// Detected loops.
    pub intervals: &'a [RepetitiveInterval],
    /// Video frames, when the input was a video.
    pub frames: Option<&'a FrameStore>,
    /// The timeline picture (from [`crate::timeline::timeline_svg`]).
    pub timeline_svg: &'a str,
    /// Summary cards.
    pub cards: &'a [Card],
    /// Other output files to link (paths relative to the report).
    pub files: &'a [String],
    /// Several people: the others, whom the page's picker switches to, and
    /// the people strip. `None` for one person.
    pub people: Option<&'a PeopleView<'a>>,
}

fn kind_index(k: PrimitiveKind) -> usize {
    PrimitiveKind::ALL.iter().position(|x| *x == k).unwrap_or(0)
}

fn round_to(v: f64, step: f64) -> f64 {
    if v.is_finite() {
        (v / step).round() * step
    } else {
        0.0
    }
}

/// Summary cards every report shows: frames, joints, segments, primitives by
/// kind, fit error, size, loops and repetitions.
pub fn standard_cards(
    track: &Track,
    program: &Program,
    executed: &Track,
    intervals: &[RepetitiveInterval],
) -> Vec<Card> {
    let t = program.n_frames();
    let mut cards = vec![
        Card::new(
            "frames",
            t.to_string(),
            format!(
                "{:.2} s at {} fps",
                t as f64 / program.fps,
                mp_geom::fps_label(program.fps)
            ),
        ),
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
    if let Ok(kd) = mp_geom::metrics::kd(track, executed) {
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
    let reps: usize = intervals.iter().map(|i| i.count).sum();
    cards.push(Card::new(
        "repetitions",
        reps.to_string(),
        repetitions_line(intervals),
    ));
    cards
}

/// Intervals shown on the repetitions card before "and N more": the line
/// stays one line for any length of recording.
const CARD_INTERVALS: usize = 6;

/// "in 3 intervals: ×4, ×3, ×3", at most [`CARD_INTERVALS`] of them (the
/// ones with most repetitions, in time order) and "and N more".
fn repetitions_line(intervals: &[RepetitiveInterval]) -> String {
    if intervals.is_empty() {
        return "no repetition detected".to_string();
    }
    let mut shown: Vec<usize> = (0..intervals.len()).collect();
    shown.sort_by_key(|&i| std::cmp::Reverse(intervals[i].count));
    shown.truncate(CARD_INTERVALS);
    shown.sort_unstable();
    let list: Vec<String> = shown
        .iter()
        .map(|&i| format!("×{}", intervals[i].count))
        .collect();
    let more = intervals.len() - shown.len();
    let n = intervals.len();
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

fn listing_html(program: &Program, default_joint: usize, offset: usize) -> String {
    let bounds = program.boundaries();
    let mut s = String::new();
    for (j, name) in program.joints.iter().enumerate() {
        let _ = write!(
            s,
            r#"<ol class="listing" data-joint="{j}"{}><li class="jh">joint "{}" {{</li>"#,
            if j == default_joint { "" } else { " hidden" },
            esc(name)
        );
        for (si, (p, dur)) in program.joint_statements(j).into_iter().enumerate() {
            let text = statement(p, dur, NumberFormat::Fixed(2));
            let (fname, rest) = text.split_at(text.find('(').unwrap_or(text.len()));
            let a = bounds.get(si).copied().unwrap_or(0) + offset;
            let _ = write!(
                s,
                r#"<li class="st k-{}" data-seg="{si}"><span class="fr">{}–{}</span><code><span class="fn">{}</span>{}</code></li>"#,
                p.kind().as_str(),
                a,
                a + dur - 1,
                esc(fname),
                esc(rest)
            );
        }
        s.push_str(r#"<li class="jt">}</li></ol>"#);
    }
    s
}

/// `mp edit` command lines offered for each loop when the input is a video
/// (`--loop` is the loop's number as the table shows it, from 1).
fn edit_command(title: &str, loop_number: usize) -> Option<String> {
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
        "mp edit {} --loop {loop_number} --add 1 -o {}",
        quote(title),
        quote(&format!("{stem}_loop{loop_number}_plus1.mp4"))
    ))
}

/// The loops (frames shown from video frame `offset`).
fn loops_table(intervals: &[RepetitiveInterval], fps: f64, title: &str, offset: usize) -> String {
    if intervals.is_empty() {
        return r#"<div class="empty">No repetition was detected in this motion.</div>"#.into();
    }
    let editable = edit_command(title, 1).is_some();
    let mut s = String::from(
        r#"<table class="loops"><thead><tr><th>loop</th><th>frames</th><th>seconds</th><th>body</th><th>iterations</th><th>count</th>"#,
    );
    if editable {
        s.push_str(r#"<th>repeat once more (copy)</th>"#);
    }
    s.push_str("</tr></thead><tbody>");
    for (i, iv) in intervals.iter().enumerate() {
        let mut iters = String::from(r#"<div class="iters">"#);
        for k in 0..iv.iterations {
            let (a, b) = (
                iv.boundaries.get(k).copied().unwrap_or(0) + offset,
                iv.boundaries.get(k + 1).copied().unwrap_or(0) + offset,
            );
            let _ = write!(
                iters,
                r#"<span title="frames {a}–{}">{}</span>"#,
                b.saturating_sub(1),
                k + 1
            );
        }
        iters.push_str("</div>");
        let _ = write!(
            s,
            r#"<tr><td>{}</td><td>{}–{}</td><td>{:.2}–{:.2}</td><td>{} primitives</td><td>{iters}</td><td class="count">×{}</td>"#,
            i + 1,
            iv.start_frame + offset,
            (iv.end_frame + offset).saturating_sub(1),
            (iv.start_frame + offset) as f64 / fps,
            (iv.end_frame + offset) as f64 / fps,
            iv.body_size,
            iv.count
        );
        if let Some(cmd) = edit_command(title, i + 1) {
            let _ = write!(s, r#"<td><code class="cmd">{}</code></td>"#, esc(&cmd));
        }
        s.push_str("</tr>");
    }
    s.push_str("</tbody></table>");
    s
}

/// The joint that moves most (largest spread of its valid positions).
pub fn most_moving_joint(track: &Track) -> usize {
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

fn json_for_script(v: &serde_json::Value) -> Result<String> {
    Ok(serde_json::to_string(v)?.replace('<', "\\u003c"))
}

/// The canvas size and view the report draws skeletons with.
pub fn stage_view(input: &ReportInput<'_>) -> ((usize, usize), View) {
    match input.frames {
        Some(fs) => (fs.size, View::frame(fs.scale())),
        None => {
            let (w, h) = (640usize, 480usize);
            (
                (w, h),
                View::fit(&[input.track, input.executed], w as f64, h as f64, 36.0),
            )
        }
    }
}

/// The arrays the page's script draws one person with: keypoints,
/// confidences, the executed program, segment boundaries and kinds, loops
/// (frames of `track`), and the joint the page selects first (the one that
/// moves most).
fn motion_data(
    track: &Track,
    program: &Program,
    executed: &Track,
    intervals: &[RepetitiveInterval],
) -> Result<(serde_json::Value, usize)> {
    check_agree(track, program)?;
    if executed.n_frames() != track.n_frames() || executed.n_joints() != track.n_joints() {
        return Err(ReportError::Mismatch(format!(
            "the executed program has {} frames × {} joints, the track {} × {}",
            executed.n_frames(),
            executed.n_joints(),
            track.n_frames(),
            track.n_joints()
        )));
    }
    let (t, j, d) = track.positions().dim();
    let step = if track.units() == Units::Pixels {
        0.1
    } else {
        1e-4
    };
    let mut kp = Vec::with_capacity(t * j * d);
    let mut prog = Vec::with_capacity(t * j * d);
    let mut conf = Vec::with_capacity(t * j);
    for ti in 0..t {
        for ji in 0..j {
            let c = track.confidence()[[ti, ji]];
            conf.push(round_to(c, 0.01));
            for k in 0..d {
                kp.push(round_to(track.positions()[[ti, ji, k]], step));
                prog.push(round_to(executed.positions()[[ti, ji, k]], step));
            }
        }
    }
    let kinds: Vec<String> = (0..j)
        .map(|ji| {
            program
                .segments
                .iter()
                .map(|s| {
                    let k = s
                        .primitives
                        .get(ji)
                        .map(|p| kind_index(p.kind()))
                        .unwrap_or(0);
                    char::from(b'0' + k as u8)
                })
                .collect()
        })
        .collect();
    let default_joint = most_moving_joint(track);
    let data = json!({
        "frames": t,
        "kp": kp,
        "conf": conf,
        "prog": prog,
        "span": track.found_span().map(|(a, b)| [a, b]),
        "bounds": program.boundaries(),
        "kinds": kinds,
        "intervals": intervals.iter().map(|iv| json!({
            "start": iv.start_frame, "end": iv.end_frame, "boundaries": iv.boundaries,
            "count": iv.count, "iterations": iv.iterations, "body": iv.body_size,
        })).collect::<Vec<_>>(),
        "defaultJoint": default_joint,
    });
    Ok((data, default_joint))
}

/// The report page.
pub fn report_html(input: &ReportInput<'_>) -> Result<String> {
    let ReportInput {
        track,
        program,
        intervals,
        ..
    } = *input;
    let (motion, default_joint) = motion_data(track, program, input.executed, intervals)?;
    let (_, j, d) = track.positions().dim();
    let sk = track.skeleton();
    let bones: Vec<[usize; 2]> = sk
        .bones
        .iter()
        .filter(|(a, b)| *a < j && *b < j)
        .map(|(a, b)| [*a, *b])
        .collect();
    let sides: Vec<i32> = program.joints.iter().map(|n| side(n)).collect();
    let ((cw, ch), view) = stage_view(input);
    let mut data = json!({
        "title": input.title,
        "fps": program.fps,
        "dims": d,
        "units": track.units().as_str(),
        "joints": program.joints,
        "bones": bones,
        "sides": sides,
        "canvas": {"w": cw, "h": ch},
        "view": {"scale": view.scale, "dx": view.dx, "dy": view.dy, "flip": view.flip_y},
        "minConf": 0.3,
        "kindNames": PrimitiveKind::ALL.iter().map(|k| k.as_str()).collect::<Vec<_>>(),
        "kindColors": PrimitiveKind::ALL.iter().map(|k| kind_color(*k)).collect::<Vec<_>>(),
        "axisLabels": (0..d).map(|k| axis_label(k, d, track.units())).collect::<Vec<_>>(),
        "frameIdx": input.frames.map(|f| f.frames.iter().map(|(i, _)| *i).collect::<Vec<_>>()).unwrap_or_default(),
    });
    if let (Some(obj), serde_json::Value::Object(m)) = (data.as_object_mut(), motion) {
        obj.extend(m);
    }
    // Several people: the others' arrays, listings, timelines and loops.
    let mut person_blocks = String::new();
    let mut listings = listing_html(program, default_joint, 0);
    let mut timelines = input.timeline_svg.to_string();
    let mut repetitions = format!(
        r#"{}<h2 style="margin-top:16px">Abstract program <span class="hint">loops of probabilistic primitives (means shown)</span></h2><pre class="code">{}</pre>"#,
        loops_table(intervals, program.fps, input.title, 0),
        esc(input.abstract_text)
    );
    let mut people_panel = String::new();
    if let Some(pv) = input.people {
        let wrap = |k: usize, html: &str| {
            format!(
                r#"<div class="pp" data-person="{k}"{}>{html}</div>"#,
                if k == 0 { "" } else { " hidden" }
            )
        };
        listings = wrap(0, &listings);
        timelines = wrap(0, &timelines);
        repetitions = wrap(0, &repetitions);
        let mut options = format!(r#"<option value="0">{}</option>"#, esc(&pv.main_label));
        let mut meta = vec![json!({"id": pv.main_id, "offset": 0, "colour": null})];
        for (k, p) in pv.others.iter().enumerate() {
            let k = k + 1;
            let (mut m, dj) = motion_data(p.track, p.program, p.executed, &p.intervals)?;
            if let Some(o) = m.as_object_mut() {
                o.insert("offset".into(), json!(p.offset));
            }
            let _ = write!(
                person_blocks,
                r#"<script type="application/json" class="mp-person" data-person="{k}">{}</script>"#,
                json_for_script(&m)?
            );
            let [r, g, b] = p.colour;
            meta.push(json!({"id": p.id, "offset": p.offset, "colour": format!("#{r:02x}{g:02x}{b:02x}")}));
            let _ = write!(options, r#"<option value="{k}">{}</option>"#, esc(&p.label));
            listings.push_str(&wrap(k, &listing_html(p.program, dj, p.offset)));
            timelines.push_str(&wrap(k, &p.timeline_svg));
            repetitions.push_str(&wrap(
                k,
                &format!(
                    r#"{}<h2 style="margin-top:16px">Abstract program <span class="hint">loops of probabilistic primitives (means shown)</span></h2><pre class="code">{}</pre>"#,
                    loops_table(&p.intervals, program.fps, "", p.offset),
                    esc(&p.abstract_text)
                ),
            ));
        }
        if let Some(o) = data.as_object_mut() {
            o.insert("people".into(), json!(meta));
        }
        let n_frames = track.n_frames();
        let _ = write!(
            people_panel,
            r#"<section class="panel" id="people"><h2>People <span class="hint">everyone tracked, in their overlay colour, with their repetitions · pick whom the page shows</span> <select id="person" aria-label="person">{options}</select></h2><div class="timeline-wrap">{}</div></section>"#,
            people_strip_svg(&pv.rows, n_frames, program.fps)
        );
    }
    let frames_json: Vec<String> = input
        .frames
        .map(|f| {
            f.frames
                .iter()
                .map(|(_, jpg)| b64::data_uri("image/jpeg", jpg))
                .collect()
        })
        .unwrap_or_default();

    let mut cards = String::new();
    for c in input.cards {
        let _ = write!(
            cards,
            r#"<div class="card"><div class="l">{}</div><div class="v">{}</div><div class="s">{}</div>{}</div>"#,
            esc(&c.label),
            esc(&c.value),
            esc(&c.sub),
            c.extra_html
        );
    }
    let mut joints = String::new();
    for (ji, name) in program.joints.iter().enumerate() {
        let _ = write!(
            joints,
            r#"<button type="button" data-joint="{ji}">{}</button>"#,
            esc(name)
        );
    }
    let mut legend = String::new();
    for k in PrimitiveKind::ALL {
        let _ = write!(
            legend,
            r#"<span><span class="sw" style="background:{}"></span>{}</span>"#,
            kind_color(k),
            k.as_str()
        );
    }
    let mut files = String::new();
    for f in input.files {
        let _ = write!(files, r#"<li><a href="{0}">{0}</a></li>"#, esc(f));
    }

    let mut h = String::with_capacity(frames_json.iter().map(String::len).sum::<usize>() + 400_000);
    let _ = write!(
        h,
        r#"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>mp report — {title}</title>
<style>
{CSS}
</style>
</head>
<body>
<header class="top"><h1><span class="brand">mp</span>{title}</h1><div class="sub">{subtitle}</div></header>
<main>
<div class="cards">{cards}</div>
{people_panel}
<div class="grid2">
<section class="panel" id="motion">
<h2>Motion <span class="hint">keypoints in colour, the executed program in pink · click a joint to select it · space plays, ←/→ step</span></h2>
<div class="player">
<div class="stage"><canvas id="stage" width="{cw}" height="{ch}"></canvas><div class="badge" id="badge">frame 0</div><div class="rep" id="rep"></div></div>
<div class="controls">
<button type="button" id="prev" title="previous frame">◀</button>
<button type="button" id="play" class="primary">▶ Play</button>
<button type="button" id="next" title="next frame">▶</button>
<input type="range" id="scrub" min="0" max="0" value="0" aria-label="frame">
<select id="speed" aria-label="speed"><option value="0.25">¼×</option><option value="0.5">½×</option><option value="1" selected>1×</option><option value="2">2×</option></select>
<label><input type="checkbox" id="loop" checked>loop</label>
</div>
<div class="controls">
<label><input type="checkbox" id="show-kp" checked><span class="sw" style="background:#ff9f1c"></span><span class="sw" style="background:#38bdf8"></span>keypoints</label>
<label><input type="checkbox" id="show-prog" checked><span class="sw" style="background:#f43f90"></span>program</label>
<span class="readout" id="readout"></span>
</div>
</div>
</section>
<section class="panel" id="program">
<h2>Program <span class="hint">per joint, in the paper's notation · the running statement is highlighted · click one to jump there</span></h2>
<div class="joints" id="joints">{joints}</div>
<div class="listing-head">{header} · <b class="jn"></b></div>
<div class="listing-box" id="listing-box">{listing}</div>
<div class="legend" style="margin-top:8px">{legend}</div>
</section>
</div>
<section class="panel" id="timeline">
<h2>Timeline <span class="hint">every joint's primitives by kind, detected loops with their iterations · click to jump</span></h2>
<div class="timeline-wrap">{timeline}</div>
</section>
<div class="grid2">
<section class="panel" id="trajectory">
<h2><span>Trajectory of <span class="jn"></span></span> <span class="hint">keypoints as dots, the program coloured by primitive kind, loops shaded · click to jump</span></h2>
<div class="plot-wrap"><canvas id="plot"></canvas></div>
<div class="legend" style="margin-top:6px"><span><span class="sw dot" style="background:#475569"></span>keypoints</span>{legend}<span><span class="sw" style="background:rgba(20,184,166,.3)"></span>loop</span></div>
</section>
<section class="panel" id="repetitions">
<h2>Repetitions <span class="hint">loops found in the program, with their iteration count</span></h2>
{repetitions}
</section>
</div>
<section class="panel" id="files">
<h2>Files <span class="hint">next to this page</span></h2>
<ul class="files">{files}</ul>
</section>
<footer>mp {version} · a self-contained page: everything it shows is inside it</footer>
</main>
<div id="mp-status" data-errors="0" data-ready="0">loading</div>
<script type="application/json" id="mp-data">{data}</script>
<script type="application/json" id="mp-frames">{frames}</script>
{person_blocks}
<script>
{JS}
</script>
</body>
</html>
"#,
        title = esc(input.title),
        subtitle = esc(input.subtitle),
        header = esc(&header(program, NumberFormat::Fixed(2))),
        listing = listings,
        timeline = timelines,
        version = env!("CARGO_PKG_VERSION"),
        data = json_for_script(&data)?,
        frames = json_for_script(&serde_json::Value::from(frames_json))?,
    );
    Ok(h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_repetitions_card_stays_one_line() {
        let iv = |count: usize| RepetitiveInterval {
            start_frame: 0,
            end_frame: 10,
            body_size: 0,
            iterations: count,
            boundaries: Vec::new(),
            count,
            score: 1.0,
        };
        assert_eq!(repetitions_line(&[]), "no repetition detected");
        assert_eq!(repetitions_line(&[iv(4)]), "in 1 interval: ×4");
        let many: Vec<_> = (0..300).map(|i| iv(1 + i % 9)).collect();
        let line = repetitions_line(&many);
        assert!(line.starts_with("in 300 intervals: ×9, ×9"), "{line}");
        assert!(line.ends_with(" and 294 more"), "{line}");
        assert_eq!(line.matches('×').count(), CARD_INTERVALS);
    }

    #[test]
    fn page_is_self_contained_and_lists_every_statement() {
        let (track, program) = crate::plots::tests::tiny();
        let exec = program.execute().unwrap();
        let (tl, _) = crate::timeline::timeline_svg(&program, &[], &Default::default()).unwrap();
        let cards = standard_cards(&track, &program, &exec, &[]);
        let html = report_html(&ReportInput {
            title: "tiny <test>",
            subtitle: "sub",
            track: &track,
            program: &program,
            executed: &exec,
            abstract_text: "for i in range(2) {}",
            intervals: &[],
            frames: None,
            timeline_svg: &tl,
            cards: &cards,
            files: &["program.txt".into()],
            people: None,
        })
        .unwrap();
        assert!(html.contains("tiny &lt;test&gt;"));
        assert_eq!(html.matches("class=\"st k-").count(), 4);
        assert!(html.contains("circular_motion"));
        assert!(
            !html.contains("http://")
                || html.matches("http://").count()
                    == html.matches("http://www.w3.org/2000/svg").count()
        );
        assert!(!html.contains("https://"));
        // The data block parses back.
        let start = html.find("id=\"mp-data\">").unwrap() + "id=\"mp-data\">".len();
        let end = start + html[start..].find("</script>").unwrap();
        let v: serde_json::Value = serde_json::from_str(&html[start..end]).unwrap();
        assert_eq!(v["frames"], 16);
        assert_eq!(v["kp"].as_array().unwrap().len(), 16 * 2 * 2);
        assert_eq!(v["kinds"][1], "12"); // line, circle
    }

    #[test]
    fn video_loops_offer_the_edit_command() {
        assert_eq!(
            edit_command("squats.mp4", 1).unwrap(),
            "mp edit squats.mp4 --loop 1 --add 1 -o squats_loop1_plus1.mp4"
        );
        assert_eq!(
            edit_command("my clip.MOV", 2).unwrap(),
            "mp edit 'my clip.MOV' --loop 2 --add 1 -o 'my clip_loop2_plus1.mp4'"
        );
        assert!(edit_command("track.npz", 1).is_none());
        let table = loops_table(
            &[RepetitiveInterval {
                start_frame: 0,
                end_frame: 30,
                body_size: 2,
                iterations: 2,
                boundaries: vec![0, 15, 30],
                count: 2,
                score: 1.0,
            }],
            30.0,
            "a.mp4",
            0,
        );
        // The command names the loop by the number in the table's first column.
        assert!(table.contains("<tr><td>1</td><td>0–29</td>"), "{table}");
        assert!(table.contains("mp edit a.mp4 --loop 1 "), "{table}");
    }
}
