//! The pictures of an analysis written into an output folder: one
//! trajectory plot per joint (SVG + PNG), the timeline (SVG + PNG) and a
//! contact sheet of twelve frames.

use mp_abstract::{AbstractProgram, RepetitiveInterval};
use mp_concrete::Program;
use mp_geom::Track;
use rayon::prelude::*;

use crate::draw::{
    blank_canvas, contact_sheet, draw_skeleton, frame_tile, SkeletonStyle, Tile, View,
};
use crate::error::{ReportError, Result};
use crate::frames::FrameStore;
use crate::outdir::{check_cancel, OutputDir};
use crate::plots::{joint_trajectory_svg, PlotParams};
use crate::raster::{pixmap_to_png, svg_to_png};
use crate::timeline::{timeline_svg, TimelineParams};

/// Tiles of the contact sheet.
pub(crate) const CONTACT_SHEET_TILES: usize = 12;

/// What the pictures and the report show.
pub struct Analysed<'a> {
    /// The keypoints.
    pub track: &'a Track,
    /// The concrete program.
    pub program: &'a Program,
    /// The program executed at the track's frames.
    pub executed: &'a Track,
    /// The abstract program.
    pub abstract_program: &'a AbstractProgram,
    /// Counted repetitions, as intervals.
    pub intervals: &'a [RepetitiveInterval],
    /// The abstract program's loops (its `for` statements) as frame intervals.
    pub program_loops: &'a [RepetitiveInterval],
    /// Reduced video frames, when the input was a video.
    pub frames: Option<&'a FrameStore>,
    /// Video frame size (width, height), when known.
    pub frame_size: Option<(usize, usize)>,
    /// Title.
    pub title: &'a str,
}

/// A file-system-safe stem (letters, digits, `_`, `-`; anything else `_`).
pub(crate) fn file_stem_safe(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// "rep i/n" for a frame inside a counted interval.
pub(crate) fn repetition_caption(intervals: &[RepetitiveInterval], f: usize) -> Option<String> {
    intervals
        .iter()
        .find(|iv| f >= iv.start_frame && f < iv.end_frame)
        .map(|iv| {
            let it = iv
                .boundaries
                .windows(2)
                .position(|w| f >= w[0] && f < w[1])
                .unwrap_or(0);
            format!("rep {}/{}", it + 1, iv.count)
        })
}

/// Writes the plots (`plots/NN_joint.svg/.png`), `timeline.svg/.png` and
/// `contact_sheet.png`; `progress` is called after each picture
/// (`joints + 2` calls). Returns the files written, relative to the folder.
pub fn write_pictures(
    out: &OutputDir,
    a: &Analysed<'_>,
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<String>> {
    let cancel = out.cancel_token();
    let mut files = Vec::new();
    let plot_params = PlotParams::default();
    // Plots are drawn in parallel and written in joint order.
    let rendered: Vec<Result<(String, String, Vec<u8>)>> = a
        .program
        .joints
        .par_iter()
        .enumerate()
        .map(|(ji, name)| {
            check_cancel(cancel)?;
            let svg = joint_trajectory_svg(a.track, a.program, a.intervals, ji, &plot_params)?;
            let png = svg_to_png(name, &svg, 1.0)?;
            progress();
            Ok((
                format!("plots/{:02}_{}", ji, file_stem_safe(name)),
                svg,
                png,
            ))
        })
        .collect();
    for r in rendered {
        let (stem, svg, png) = r?;
        out.write(&format!("{stem}.svg"), svg.as_bytes())?;
        out.write(&format!("{stem}.png"), &png)?;
        files.push(format!("{stem}.svg"));
        files.push(format!("{stem}.png"));
    }
    let (tl_svg, _) = timeline_svg(
        a.program,
        a.intervals,
        a.program_loops,
        &TimelineParams::default(),
    )?;
    out.write("timeline.svg", tl_svg.as_bytes())?;
    out.write("timeline.png", &svg_to_png("timeline", &tl_svg, 1.0)?)?;
    files.push("timeline.svg".into());
    files.push("timeline.png".into());
    progress();
    let sheet = contact_sheet_of(a, cancel)?;
    out.write(
        "contact_sheet.png",
        &pixmap_to_png("contact sheet", &sheet)?,
    )?;
    files.push("contact_sheet.png".into());
    progress();
    Ok(files)
}

/// Twelve evenly spaced frames with the keypoints and the executed program
/// drawn on them (on the video frame when there is one), drawn in parallel.
fn contact_sheet_of(
    a: &Analysed<'_>,
    cancel: &mp_geom::CancelToken,
) -> Result<resvg::tiny_skia::Pixmap> {
    let n_frames = a.track.n_frames();
    if n_frames == 0 {
        return Err(ReportError::Mismatch("the track has no frames".into()));
    }
    let n_tiles = CONTACT_SHEET_TILES.min(n_frames);
    let picks: Vec<usize> = (0..n_tiles)
        .map(|i| ((i as f64 + 0.5) * n_frames as f64 / n_tiles as f64) as usize)
        .map(|f| f.min(n_frames - 1))
        .collect();
    let kp_style = SkeletonStyle::default().scaled(0.8);
    let prog_style = SkeletonStyle::program().scaled(0.8);
    let tiles: Vec<Tile> = picks
        .par_iter()
        .map(|&f| -> Result<Tile> {
            check_cancel(cancel)?;
            let secs = f as f64 / a.track.fps();
            let caption = match repetition_caption(a.intervals, f) {
                Some(l) => format!("frame {f} · {secs:.2} s · {l}"),
                None => format!("frame {f} · {secs:.2} s"),
            };
            let pixmap = match (a.frames, a.frame_size) {
                (Some(store), Some(size)) => {
                    let pos = store.nearest(f).ok_or_else(|| {
                        ReportError::Mismatch(format!("no stored frame near {f}"))
                    })?;
                    let rgb = store.rgb(pos)?;
                    // The stored frame is reduced: the view maps the video's pixels.
                    let tile_w = 240u32;
                    frame_tile(&rgb, store.size, tile_w, |tile, _| {
                        let view = View::frame(tile_w as f64 / size.0 as f64);
                        draw_skeleton(tile, a.executed, f, &view, &prog_style);
                        draw_skeleton(tile, a.track, f, &view, &kp_style);
                    })?
                }
                _ => {
                    let (tw, th) = (240u32, 240u32);
                    let mut tile = blank_canvas(tw, th)?;
                    let view = View::fit(&[a.track, a.executed], tw as f64, th as f64, 16.0);
                    draw_skeleton(&mut tile, a.executed, f, &view, &prog_style);
                    draw_skeleton(&mut tile, a.track, f, &view, &kp_style);
                    tile
                }
            };
            Ok(Tile { pixmap, caption })
        })
        .collect::<Result<_>>()?;
    check_cancel(cancel)?;
    contact_sheet(
        &tiles,
        4,
        &format!("{} — keypoints and program (pink)", a.title),
    )
}
