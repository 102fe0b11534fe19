//! Step 5: the output folder — track, programs, counts, pictures, overlay
//! video and report — every file written through the folder's staging area,
//! so a cancelled run leaves only complete files.

use mp_abstract::{Analysis, ProgramLoopJson, RepetitionsJson};
use mp_geom::PersonId;
use mp_geom::{CancelToken, Track};
use mp_pose::{PixelFormat, VideoReader, VideoWriter, Yuv420Frame, X264};
use mp_report::check_cancel;
use mp_report::OutputDir;
use mp_report::Pixmap;
use mp_report::{draw_skeleton, SkeletonStyle, View};
use serde::Serialize;

use crate::error::{PipelineError, Result};
use crate::keypoints::OverlayFrames;
use crate::Outcome;

/// How x264 encodes the overlay video: the `veryfast` preset (about twice
/// as fast as the default preset, and smaller files on this kind of
/// footage), with the quickest sub-pixel refinement, a diamond motion search
/// and no sub-macroblock partitions over it. On three minutes of 640 × 360
/// video these spend 35 % less encoding time than `veryfast` alone for a
/// file 8 % larger and the same likeness to the source (SSIM 0.946 against
/// 0.947, PSNR 27.2 dB for both): the encoder is half the work of the run
/// after the pose stage.
pub(crate) const OVERLAY_X264: X264<'static> = X264 {
    preset: "veryfast",
    params: "subme=1:me=dia:partitions=none",
};

/// The content of `loops.json` (layout [`mp_abstract::RepetitionsJson::LOOPS_VERSION`],
/// documented in `docs/LOOPS_JSON.md`). Every frame range is inclusive
/// (`first_frame`–`last_frame`), in frames of the video.
#[derive(Debug, Clone, Serialize)]
pub struct LoopsFile {
    /// `mp-loops`.
    pub schema: &'static str,
    /// [`mp_abstract::RepetitionsJson::LOOPS_VERSION`].
    pub version: u32,
    /// Frame rate.
    pub fps: f64,
    /// Frames of the recording.
    pub frames: usize,
    /// Whose counts the top level holds: the main person, or the one asked
    /// for; null for a track file and the single-person pipeline.
    pub person: Option<PersonId>,
    /// What was counted.
    pub repetitions: RepetitionsJson,
    /// The `for` statements of the abstract program.
    pub program_loops: Vec<ProgramLoopJson>,
    /// One entry per tracked person (empty for a track file and the
    /// single-person pipeline).
    pub people: Vec<PersonEntry>,
}

/// One tracked person's entry of `loops.json`.
#[derive(Debug, Clone, Serialize)]
pub struct PersonEntry {
    /// The person's id.
    pub id: PersonId,
    /// Whether the top-level results are this person's.
    pub main: bool,
    /// First video frame where the person was tracked.
    pub first_frame: usize,
    /// Last video frame where the person was tracked.
    pub last_frame: usize,
    /// Frames with a pose.
    pub frames_found: usize,
    /// Mean box `[x0, y0, x1, y1]`, px.
    #[serde(rename = "box")]
    pub mean_box: Option<[f64; 4]>,
    /// Whether the person was analysed (seen long enough, and chosen).
    pub analysed: bool,
    /// The person's repetitions; null when not analysed.
    pub repetitions: Option<RepetitionsJson>,
}

impl Outcome {
    /// `loops.json` of the outcome.
    pub fn loops_file(&self) -> LoopsFile {
        let track = &self.keypoints.track;
        LoopsFile {
            schema: mp_abstract::RepetitionsJson::LOOPS_SCHEMA,
            version: mp_abstract::RepetitionsJson::LOOPS_VERSION,
            fps: track.fps(),
            frames: track.n_frames(),
            person: self.keypoints.person,
            repetitions: RepetitionsJson::new(&self.counts),
            program_loops: self
                .analysis
                .as_ref()
                .map(|a| a.intervals.iter().map(ProgramLoopJson::new).collect())
                .unwrap_or_default(),
            people: self
                .people
                .iter()
                .map(|p| PersonEntry {
                    id: p.id,
                    main: p.main,
                    first_frame: p.first_frame,
                    last_frame: p.last_frame,
                    frames_found: p.frames_found,
                    mean_box: p.mean_box,
                    analysed: p.counts.is_some(),
                    repetitions: p.counts.as_ref().map(RepetitionsJson::new),
                })
                .collect(),
        }
    }

    /// [`Outcome::loops_file`] as a JSON value.
    pub fn loops_json(&self) -> serde_json::Value {
        serde_json::to_value(self.loops_file()).unwrap_or(serde_json::Value::Null)
    }
}

/// Writes `track.npz` (with every tracked person along a person axis when
/// people were tracked: `mp_geom::people`), `loops.json` and, when there
/// is an analysis, `program.txt`, `program.json`, `abstract.txt` and
/// `abstract.json`; for every other analysed person the programs go to
/// `people/<id>/` (over the person's own frames, from `first_frame`).
/// Returns the files written.
pub(crate) fn write_analysis(out: &OutputDir, outcome: &Outcome) -> Result<Vec<String>> {
    let track = &outcome.keypoints.track;
    let mut files = Vec::new();
    let mut put = |rel: &str, bytes: &[u8]| -> Result<()> {
        out.write(rel, bytes).map_err(PipelineError::from_report)?;
        files.push(rel.to_string());
        Ok(())
    };
    let top_is_main = match (&outcome.keypoints.people, outcome.keypoints.person) {
        (Some(p), Some(id)) => p.main_person().map(|m| m.id) == Some(id),
        _ => false,
    };
    match &outcome.keypoints.people {
        Some(people) if top_is_main => put(
            "track.npz",
            &mp_geom::people_to_npz_bytes_framed(people, outcome.keypoints.frame_size)?,
        )?,
        _ => put(
            "track.npz",
            &mp_geom::track_to_npz_bytes_framed(track, outcome.keypoints.frame_size)?,
        )?,
    }
    let mut programs = |dir: &str, an: &Analysis| -> Result<()> {
        put(
            &format!("{dir}program.txt"),
            an.concrete.to_dsl().as_bytes(),
        )?;
        put(
            &format!("{dir}program.json"),
            an.concrete.to_json()?.as_bytes(),
        )?;
        put(
            &format!("{dir}abstract.txt"),
            an.program.to_dsl().as_bytes(),
        )?;
        put(
            &format!("{dir}abstract.json"),
            serde_json::to_string_pretty(&an.program)?.as_bytes(),
        )
    };
    if let Some(an) = &outcome.analysis {
        programs("", an)?;
    }
    for p in outcome.people.iter().filter(|p| !p.main) {
        if let Some(an) = &p.analysis {
            programs(&format!("people/{}/", p.id), an)?;
        }
    }
    put(
        "loops.json",
        serde_json::to_string_pretty(&outcome.loops_file())?.as_bytes(),
    )?;
    Ok(files)
}

/// Colours of the people besides the top-level one in the overlay (by id,
/// in turn): Okabe and Ito's colour-blind-safe palette, the colours least
/// like the top-level skeleton's left/right orange and blue first.
pub(crate) const PERSON_COLOURS: [[u8; 3]; 7] = [
    [0, 158, 115],
    [204, 121, 167],
    [240, 228, 66],
    [213, 94, 0],
    [0, 114, 178],
    [86, 180, 233],
    [230, 159, 0],
];

/// The colour of a person's skeleton in the overlay.
pub(crate) fn person_colour(id: mp_geom::PersonId) -> [u8; 3] {
    PERSON_COLOURS[(id as usize).saturating_sub(1) % PERSON_COLOURS.len()]
}

/// Another tracked person as the overlay draws them: their colour, their
/// first frame, and their track over their own frames (from the first on).
pub(crate) type OtherPerson<'a> = ([u8; 3], usize, &'a Track);

/// Every tracked person but the top-level one, each over their own frames
/// (a long video with many people holds each person's poses once, not a
/// copy as long as the video per person), with their colour.
pub(crate) fn other_people(kp: &crate::Keypoints) -> Vec<OtherPerson<'_>> {
    let Some(people) = &kp.people else {
        return Vec::new();
    };
    people
        .people()
        .iter()
        .filter(|p| Some(p.id) != kp.person)
        .map(|p| (person_colour(p.id), p.first_frame, &p.track))
        .collect()
}

/// Encodes every analysed frame with the keypoints and the executed program
/// drawn on it into `overlay.mp4` (the program only between the person's
/// first and last frames: before and after, it holds their first and last
/// pose where nobody is), and the other people (`others`) each in their own
/// colour; `progress` is called after each frame. The video is left in the
/// folder's staging area (the path returned): the caller commits it as
/// `overlay.mp4` once the rest of the run has succeeded, and sets `stop`
/// when it has failed (the encoding then ends at the next frame).
///
/// The frames stay in YUV 4:2:0 from the decoder to the encoder (the
/// codec's own pixels, half the bytes of RGB through each pipe, no colour
/// conversion): the skeletons are drawn on a transparent layer and blended
/// into the frame only where they were drawn.
pub(crate) fn encode_overlay(
    out: &OutputDir,
    src: OverlayFrames,
    track: &Track,
    executed: &Track,
    others: &[OtherPerson<'_>],
    progress: &dyn Fn(usize),
    stop: &std::sync::atomic::AtomicBool,
) -> Result<std::path::PathBuf> {
    let cancel: &CancelToken = out.cancel_token();
    let n = track.n_frames();
    let (width, height, fps) = (src.info.width, src.info.height, src.info.fps);
    let staged = out.staging_file("overlay.mp4");
    let mut writer = VideoWriter::with_format(
        &staged,
        width,
        height,
        fps,
        OVERLAY_X264,
        PixelFormat::Yuv420p,
    )?;
    // One transparent layer, cleared where it was drawn after each frame.
    let mut layer = Pixmap::new(width as u32, height as u32).ok_or_else(|| {
        PipelineError::stage(
            "overlay video",
            format!("cannot allocate a {width}×{height} picture"),
        )
    })?;
    let kp_style = SkeletonStyle::for_frame(width, height);
    let prog_style = SkeletonStyle::program().scaled(SkeletonStyle::frame_scale(width, height));
    let view = View::frame(1.0);
    let span = track.found_span();
    let mut done = 0usize;
    let mut draw = |frame: &mut Yuv420Frame| -> Result<()> {
        check_cancel(cancel).map_err(PipelineError::from_report)?;
        if stop.load(std::sync::atomic::Ordering::Relaxed) {
            return Err(PipelineError::stage("overlay video", "the run failed"));
        }
        let index = frame.index;
        let mut area: Option<[f32; 4]> = None;
        let mut drawn = |a: Option<[f32; 4]>| {
            if let Some(a) = a {
                let u = area.get_or_insert(a);
                *u = [
                    u[0].min(a[0]),
                    u[1].min(a[1]),
                    u[2].max(a[2]),
                    u[3].max(a[3]),
                ];
            }
        };
        for (colour, first, other) in others {
            let Some(own) = index.checked_sub(*first).filter(|&i| i < other.n_frames()) else {
                continue;
            };
            let style = SkeletonStyle {
                color: Some(*colour),
                ..kp_style
            };
            drawn(draw_skeleton(&mut layer, other, own, &view, &style));
        }
        if span.is_some_and(|(a, b)| (a..=b).contains(&index)) {
            drawn(draw_skeleton(
                &mut layer,
                executed,
                index,
                &view,
                &prog_style,
            ));
        }
        drawn(draw_skeleton(&mut layer, track, index, &view, &kp_style));
        if let Some(a) = area {
            let px = |v: f32| v.floor().max(0.0) as usize;
            let rect = [px(a[0]), px(a[1]), px(a[2]) + 1, px(a[3]) + 1];
            frame.blend_layer(layer.data_mut(), rect)?;
        }
        writer.write(&frame.data)?;
        done += 1;
        progress(done);
        Ok(())
    };
    match src.kept {
        Some(frames) => {
            for mut frame in frames.into_iter().take(n) {
                draw(&mut frame)?;
            }
        }
        None => {
            let reader = VideoReader::yuv420(src.info)?;
            for frame in reader.take(n) {
                draw(&mut frame?)?;
            }
        }
    }
    check_cancel(cancel).map_err(PipelineError::from_report)?;
    writer.finish()?;
    Ok(staged)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mp_geom::{Skeleton, Units};
    use ndarray::{Array2, Array3};

    /// A person standing in the middle of a `w × h` picture, every frame.
    fn standing(n: usize, w: f64, h: f64, dx: f64) -> Track {
        let sk = Skeleton::coco17();
        let mut pos = Array3::zeros((n, sk.len(), 2));
        for t in 0..n {
            for j in 0..sk.len() {
                // Head at the top, feet at the bottom, left and right apart.
                let side = if j % 2 == 0 { -1.0 } else { 1.0 };
                pos[[t, j, 0]] = w / 2.0 + dx + side * 0.05 * w;
                pos[[t, j, 1]] = h * (0.2 + 0.6 * j as f64 / sk.len() as f64);
            }
        }
        let conf = Array2::from_elem((n, sk.len()), 0.9);
        Track::new(pos, Some(conf), 10.0, Units::Pixels, sk).unwrap()
    }

    /// The overlay holds the video's frames with the skeletons drawn where
    /// the joints are: pixels on them change, pixels far from them keep the
    /// source's colour (within what H.264 keeps); kept and decoded frames
    /// give the same video; a run that failed beside it stops it.
    #[test]
    fn the_overlay_draws_the_skeletons_on_the_frames() {
        let dir = tempfile::tempdir().unwrap();
        let (w, h, n) = (96usize, 64usize, 4usize);
        let grey = vec![90u8; w * h * 3];
        let src = dir.path().join("src.mp4");
        let mut wr = VideoWriter::create_with_preset(&src, w, h, 10.0, "veryfast").unwrap();
        for _ in 0..n {
            wr.write(&grey).unwrap();
        }
        wr.finish().unwrap();
        let info = mp_pose::probe(&src).unwrap();
        let track = standing(n, w as f64, h as f64, -20.0);
        let other = standing(n - 1, w as f64, h as f64, 25.0);
        let others: Vec<OtherPerson<'_>> = vec![([250, 40, 40], 1, &other)];
        let kept: Vec<Yuv420Frame> = VideoReader::yuv420(info.clone())
            .unwrap()
            .map(|f| f.unwrap())
            .collect();
        let stopped = std::sync::atomic::AtomicBool::new(true);
        let out = OutputDir::create(dir.path().join("stopped")).unwrap();
        let src_frames = OverlayFrames {
            info: info.clone(),
            kept: None,
        };
        let e = encode_overlay(&out, src_frames, &track, &track, &others, &|_| {}, &stopped)
            .unwrap_err()
            .to_string();
        assert!(e.contains("the run failed"), "{e}");
        for (name, kept) in [("decoded", None), ("kept", Some(kept))] {
            let out = OutputDir::create(dir.path().join(name)).unwrap();
            let src = OverlayFrames {
                info: info.clone(),
                kept,
            };
            let go = std::sync::atomic::AtomicBool::new(false);
            let staged = encode_overlay(&out, src, &track, &track, &others, &|_| {}, &go).unwrap();
            out.commit(&staged, "overlay.mp4").unwrap();
            let frames: Vec<Vec<u8>> = VideoReader::open(dir.path().join(name).join("overlay.mp4"))
                .unwrap()
                .map(|f| f.unwrap().rgb)
                .collect();
            assert_eq!(frames.len(), n, "{name}");
            let px = |f: &[u8], x: f64, y: f64| {
                let i = (y as usize * w + x as usize) * 3;
                [f[i], f[i + 1], f[i + 2]]
            };
            let far = |p: [u8; 3]| p.iter().all(|&v| v.abs_diff(90) <= 3);
            for (t, f) in frames.iter().enumerate() {
                // A corner, far from both people, keeps the source's grey.
                assert!(
                    far(px(f, 2.0, 2.0)),
                    "{name} frame {t}: {:?}",
                    px(f, 2.0, 2.0)
                );
                let (x, y) = {
                    let p = track.positions();
                    (p[[t, 6, 0]], p[[t, 6, 1]])
                };
                assert!(
                    !far(px(f, x, y)),
                    "{name} frame {t}: no joint drawn at ({x}, {y})"
                );
                // The other person is drawn in their colour from their first frame.
                let (ox, oy) = {
                    let p = other.positions();
                    (p[[0, 10, 0]], p[[0, 10, 1]] + 4.0)
                };
                let o = px(f, ox, oy);
                if t == 0 {
                    assert!(far(o), "{name}: the other person before their first frame");
                } else {
                    assert!(o[0] > o[1] + 40, "{name} frame {t}: {o:?} is not their red");
                }
            }
        }
    }
}
