//! The page itself: the panels' frames around what the script loads, the
//! cards, the people strip, the style, the script and the page's own data.

use std::fmt::Write as _;

use mp_geom::PrimitiveKind;
use serde_json::json;

use crate::draw::View;
use crate::error::Result;
use crate::page::cards::{cards_html, standard_cards};
use crate::page::{data, PersonPage, ReportInput};
use crate::people::people_strip_svg;
use crate::plots::axis_label;
use crate::style::{kind_color, side};
use crate::svg::esc;

const CSS: &str = include_str!("../../assets/report.css");
const JS: &str = include_str!("../../assets/report.js");

/// The canvas size and view the page draws skeletons with: the frames' when
/// there are frames, else the main person's motion fitted to 640 × 480.
pub(crate) fn stage_view(input: &ReportInput<'_>, main: &PersonPage<'_>) -> ((usize, usize), View) {
    match input.frames {
        Some(fs) => (fs.size, View::frame(fs.scale())),
        None => {
            let (w, h) = (640usize, 480usize);
            let mut tracks = vec![main.track];
            if let Some(pv) = &main.program {
                tracks.push(pv.executed);
            }
            ((w, h), View::fit(&tracks, w as f64, h as f64, 36.0))
        }
    }
}

fn json_for_script(v: &serde_json::Value) -> Result<String> {
    Ok(serde_json::to_string(v)?.replace('<', "\\u003c"))
}

/// The page.
pub(super) fn page(
    input: &ReportInput<'_>,
    main: &PersonPage<'_>,
    pictures: &[(usize, &[u8])],
    stride: usize,
    people: Vec<serde_json::Value>,
) -> Result<String> {
    let track = main.track;
    let ((cw, ch), view) = stage_view(input, main);
    let with_program = main.program.is_some();
    let data = page_data(input, main, pictures, stride, people, (cw, ch), &view);
    let mut cards = standard_cards(track, main.program.as_ref(), input.counts);
    cards.extend(input.cards.iter().cloned());
    let notice = notice_panel(input);
    let people_panel = people_panel(input, track);
    let motion = motion_panel(with_program, cw, ch);
    let body = if with_program {
        program_panels(&track.skeleton().joints, &motion)
    } else {
        format!(
            r#"<div class="grid2">
{motion}
{REPETITIONS_PANEL}
</div>"#
        )
    };
    let mut files = String::new();
    for f in input.files {
        let _ = write!(files, r#"<li><a href="{0}">{0}</a></li>"#, esc(f));
    }

    let mut h = String::with_capacity(JS.len() + CSS.len() + 64 * 1024);
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
{notice}
{people_panel}
{body}
<section class="panel" id="files">
<h2>Files <span class="hint">next to this page</span></h2>
<ul class="files">{files}</ul>
</section>
<footer>mp {version} · this page shows the frames and data of the folder {folder}/ beside it: keep the two together</footer>
</main>
<div id="mp-status" data-errors="0" data-ready="0">loading</div>
<script type="application/json" id="mp-data">{data}</script>
<script>
{JS}
</script>
</body>
</html>
"#,
        title = esc(input.title),
        subtitle = esc(input.subtitle),
        cards = cards_html(&cards),
        version = env!("CARGO_PKG_VERSION"),
        folder = data::FOLDER,
        data = json_for_script(&data)?,
    );
    Ok(h)
}

/// The page's data for its script: the skeleton, the stage's view, the
/// primitive kinds' colours, where the data folder's chunks and pictures are,
/// and the people.
fn page_data(
    input: &ReportInput<'_>,
    main: &PersonPage<'_>,
    pictures: &[(usize, &[u8])],
    stride: usize,
    people: Vec<serde_json::Value>,
    (cw, ch): (usize, usize),
    view: &View,
) -> serde_json::Value {
    let track = main.track;
    let (_, j, d) = track.positions().dim();
    let joints = &track.skeleton().joints;
    let bones: Vec<[usize; 2]> = track
        .skeleton()
        .bones
        .iter()
        .filter(|(a, b)| *a < j && *b < j)
        .map(|(a, b)| [*a, *b])
        .collect();
    let sides: Vec<i32> = joints.iter().map(|n| side(n)).collect();
    let with_program = main.program.is_some();
    json!({
        "title": input.title,
        "fps": track.fps(),
        "dims": d,
        "units": track.units().as_str(),
        "joints": joints,
        "bones": bones,
        "sides": sides,
        "canvas": {"w": cw, "h": ch},
        "view": {"scale": view.scale, "dx": view.dx, "dy": view.dy, "flip": view.flip_y},
        "minConf": 0.3,
        "kindNames": PrimitiveKind::ALL.iter().map(|k| k.as_str()).collect::<Vec<_>>(),
        "kindColors": PrimitiveKind::ALL.iter().map(|k| kind_color(*k)).collect::<Vec<_>>(),
        "axisLabels": (0..d).map(|k| axis_label(k, d, track.units())).collect::<Vec<_>>(),
        "base": format!("{}/", data::FOLDER),
        "chunk": data::CHUNK_FRAMES,
        "stride": stride,
        "pictures": pictures.iter().map(|(i, _)| *i).collect::<Vec<_>>(),
        "people": people,
        "program": with_program,
    })
}

/// The notice panel, when the input has one.
fn notice_panel(input: &ReportInput<'_>) -> String {
    input
        .notice
        .as_ref()
        .map(|n| {
            format!(
                r#"<section class="panel notice" id="notice">{}</section>"#,
                esc(n)
            )
        })
        .unwrap_or_default()
}

/// The strip of everyone tracked, when there is more than one person or row.
fn people_panel(input: &ReportInput<'_>, track: &mp_geom::Track) -> String {
    match &input.strip {
        Some(rows) if input.people.len() > 1 || rows.len() > 1 => {
            let mut options = String::new();
            for (k, p) in input.people.iter().enumerate() {
                let _ = write!(options, r#"<option value="{k}">{}</option>"#, esc(&p.label));
            }
            format!(
                r#"<section class="panel" id="people"><h2>People <span class="hint">everyone tracked, in their overlay colour, with their repetitions · pick whom the page shows</span> <select id="person" aria-label="person">{options}</select></h2><div class="strip-wrap">{}</div></section>"#,
                people_strip_svg(rows, track.n_frames(), track.fps())
            )
        }
        _ => String::new(),
    }
}

/// The motion player: the stage, its controls and, with a program, the
/// layers' switches.
fn motion_panel(with_program: bool, cw: usize, ch: usize) -> String {
    let motion_hint = if with_program {
        "keypoints in colour, the executed program in pink · click a joint to select it · space plays, ←/→ step"
    } else {
        "the video's frames · space plays, ←/→ step"
    };
    let layers = if with_program {
        r##"<div class="controls">
<label><input type="checkbox" id="show-kp" checked><span class="sw" style="background:#ff9f1c"></span><span class="sw" style="background:#38bdf8"></span>keypoints</label>
<label><input type="checkbox" id="show-prog" checked><span class="sw" style="background:#f43f90"></span>program</label>
<span class="readout" id="readout"></span>
</div>"##
    } else {
        r#"<div class="controls"><span class="readout" id="readout"></span></div>"#
    };
    format!(
        r#"<section class="panel" id="motion">
<h2>Motion <span class="hint">{motion_hint}</span></h2>
<div class="player">
<div class="stage"><div class="screen"><div class="picture" id="picture"></div><canvas id="stage" width="{cw}" height="{ch}"></canvas></div><div class="badge" id="badge">frame 0</div><div class="rep" id="rep"></div></div>
<div class="controls">
<button type="button" id="prev" title="previous frame">◀</button>
<button type="button" id="play" class="primary">▶ Play</button>
<button type="button" id="next" title="next frame">▶</button>
<input type="range" id="scrub" min="0" max="0" value="0" aria-label="frame">
<select id="speed" aria-label="speed"><option value="0.25">¼×</option><option value="0.5">½×</option><option value="1" selected>1×</option><option value="2">2×</option></select>
<label><input type="checkbox" id="loop" checked>loop</label>
</div>
{layers}
</div>
</section>"#
    )
}

/// The repetitions panel (filled by the script).
const REPETITIONS_PANEL: &str = r#"<section class="panel" id="repetitions">
<h2>Repetitions <span class="hint">what was counted: each interval's frames, count and period, and each repetition's frames · click one to jump there</span></h2>
<div id="repetitions-body" class="loading">loading…</div>
</section>"#;

/// The panels of a page with a program: the motion and the program listing,
/// the timeline, the trajectory and the repetitions, the abstract program.
fn program_panels(joints: &[String], motion: &str) -> String {
    let mut joint_buttons = String::new();
    for (ji, name) in joints.iter().enumerate() {
        let _ = write!(
            joint_buttons,
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
    let repetitions = REPETITIONS_PANEL;
    format!(
        r#"<div class="grid2">
{motion}
<section class="panel" id="program">
<h2>Program <span class="hint">per joint, in the paper's notation · the running statement is highlighted · click one to jump there</span></h2>
<div class="joints" id="joints">{joint_buttons}</div>
<div class="listing-head"><span id="listing-header"></span> · <b class="jn"></b></div>
<div class="listing-box" id="listing-box"></div>
<div class="legend" style="margin-top:8px">{legend}</div>
</section>
</div>
<section class="panel" id="timeline">
<h2>Timeline <span class="hint">every joint's primitives by kind, the counted repetitions and the program loops · click to jump</span></h2>
<div class="timeline-wrap" id="timeline-body"></div>
</section>
<div class="grid2">
<section class="panel" id="trajectory">
<h2><span>Trajectory of <span class="jn"></span></span> <span class="hint">keypoints as dots, the program coloured by primitive kind, repetitions shaded · click to jump</span></h2>
<div class="plot-wrap"><canvas id="plot"></canvas></div>
<div class="legend" style="margin-top:6px"><span><span class="sw dot" style="background:#475569"></span>keypoints</span>{legend}<span><span class="sw" style="background:rgba(20,184,166,.3)"></span>repetitions</span></div>
</section>
{repetitions}
</div>
<section class="panel" id="abstract">
<h2>Abstract program <span class="hint">its program loops (for statements) and probabilistic primitives (means shown)</span></h2>
<div id="abstract-body"></div>
</section>"#
    )
}
