//! `mp run`: a video or a keypoint track in, programs, counts, pictures and a
//! report out — argument parsing and printing around `mp_pipeline::run`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;
use mp_pipeline::{Input, Params, RunSummary};

use crate::progress::{ctrl_c_token, Bars};

/// Arguments of `mp run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    /// A video (mp4, mov, avi, webm, mkv, …) or a keypoint track (npz, json, csv, npy, bvh, mpt, c3d, parquet, pose, OpenPose folder).
    pub input: PathBuf,
    /// Output folder (created if needed).
    #[arg(long, short)]
    pub out: PathBuf,
    #[command(flatten)]
    pub pose: PoseOpts,
    #[command(flatten)]
    pub people: PeopleOpts,
    /// Largest side of the video frame in pixels, for track input (scale = frame / 512); default: from the motion's extent.
    #[arg(long)]
    pub frame_size: Option<f64>,
    #[command(flatten)]
    pub rate: crate::track_arg::RateOpt,
    /// Do not write the overlay video.
    #[arg(long)]
    pub no_video: bool,
    /// Every setting of the run from a JSON file (`mp params` prints them); the options given here apply on top.
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// No progress bars and no summary.
    #[arg(long, short)]
    pub quiet: bool,
}

/// Options of keypoint extraction from video.
#[derive(Args, Debug, Clone)]
pub struct PoseOpts {
    #[command(flatten)]
    pub model: PoseModelOpts,
    /// ONNX Runtime threads.
    #[arg(long, default_value_t = Params::default().pose.threads)]
    pub threads: usize,
}

/// The pose options that `mp run` and `mp batch` share.
#[derive(Args, Debug, Clone)]
pub struct PoseModelOpts {
    /// Pose model for videos: full, lite (BlazePose) or movenet.
    #[arg(long, default_value = Params::default().pose.model.as_str())]
    pub model: String,
    /// Only the first N frames of each video.
    #[arg(long)]
    pub max_frames: Option<usize>,
    /// Keep all of the pose model's joints (BlazePose: 33) instead of the COCO-17 body joints.
    #[arg(long)]
    pub all_joints: bool,
    /// How often the pose model runs: all (every frame), auto (12 poses a second: every second frame at 24–30 fps), or N poses a second; the frames between are filled from the motion.
    #[arg(long, value_name = "N|auto|all", default_value_t = Params::default().pose.rate.label())]
    pub pose_fps: String,
    /// Where the pose model runs: auto (the GPU where ONNX Runtime's CUDA build and a GPU are there, else the CPU), cpu, cuda or cuda:N.
    #[arg(long, default_value_t = Params::default().pose.device.label())]
    pub device: String,
}

impl PoseOpts {
    /// Sets the pose parameters of `p`; with `only_given` (a `--params`
    /// file is the base) only those given on the command line.
    pub fn apply(&self, p: &mut Params, only_given: bool) -> Result<()> {
        self.model.apply(p, only_given)?;
        if !only_given || crate::given("threads") {
            p.pose.threads = self.threads;
        }
        Ok(())
    }
}

impl PoseModelOpts {
    /// Sets the pose model, first frames, joints, pose rate and device of
    /// `p`; with `only_given` (a `--params` file is the base) only those given
    /// on the command line.
    pub fn apply(&self, p: &mut Params, only_given: bool) -> Result<()> {
        let set = |id: &str| !only_given || crate::given(id);
        if set("model") {
            p.pose.model = mp_pose::ModelChoice::parse(&self.model)?;
        }
        if set("max_frames") {
            p.pose.max_frames = self.max_frames;
        }
        if set("all_joints") {
            p.pose.all_joints = self.all_joints;
        }
        if set("pose_fps") {
            p.pose.rate = mp_pipeline::PoseRate::parse(&self.pose_fps)?;
        }
        if set("device") {
            p.pose.device = mp_pose::Device::parse(&self.device)?;
        }
        Ok(())
    }
}

/// The parameters of a `--params` file (completed with the defaults and
/// checked), or the defaults.
pub fn params_file(path: Option<&Path>) -> Result<Params> {
    let Some(path) = path else {
        return Ok(Params::default());
    };
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    Params::from_json(&text).with_context(|| format!("{}", path.display()))
}

/// Arguments of `mp params`.
#[derive(Args, Debug)]
pub struct ParamsArgs {
    /// A JSON file of settings, partial or whole: printed completed with the defaults, after its check.
    pub file: Option<PathBuf>,
}

/// `mp params`: every setting of a run as JSON.
pub fn params_cmd(a: &ParamsArgs) -> Result<()> {
    println!("{}", params_file(a.file.as_deref())?.to_json()?);
    Ok(())
}

/// Options for videos with several people.
#[derive(Args, Debug, Clone)]
pub struct PeopleOpts {
    /// Whose motion is analysed: all (everyone seen long enough; the main person's results are the top-level ones), main, or a person's id.
    #[arg(long, default_value = "all")]
    pub person: String,
    /// Most people tracked at once.
    #[arg(long, default_value_t = Params::default().pose.tracker.max_people)]
    pub max_people: usize,
    /// Follow one person with MediaPipe's single-person pipeline instead of tracking everyone.
    #[arg(long)]
    pub single_person: bool,
}

impl PeopleOpts {
    /// Sets the people parameters of `p`; with `only_given` only those
    /// given on the command line.
    pub fn apply(&self, p: &mut Params, only_given: bool) -> Result<()> {
        let set = |id: &str| !only_given || crate::given(id);
        if set("person") {
            p.person.choice = mp_pipeline::PersonChoice::parse(&self.person)?;
        }
        if set("max_people") {
            p.pose.tracker.max_people = self.max_people;
        }
        if set("single_person") {
            p.pose.people = !self.single_person;
        }
        Ok(())
    }
}

/// `mp run`.
pub fn run_cmd(a: &RunArgs) -> Result<()> {
    let mut params = params_file(a.params.as_deref())?;
    let from_file = a.params.is_some();
    a.pose.apply(&mut params, from_file)?;
    a.people.apply(&mut params, from_file)?;
    if !from_file || a.no_video {
        params.output.overlay_video = !a.no_video;
    }
    crate::track_arg::check_out_dir(&a.out)?;
    let input = crate::track_arg::open_input(&a.input, a.frame_size, &a.rate)?;
    let summary = run_or_exit(input, &a.out, &params, a.quiet)?;
    if !a.quiet {
        print_summary(&summary, &a.out);
    }
    Ok(())
}

/// Runs the pipeline with progress bars; at Ctrl-C the run stops, its staging
/// folder is removed and the process exits with status 130.
pub fn run_or_exit(input: Input, out: &Path, params: &Params, quiet: bool) -> Result<RunSummary> {
    let cancel = ctrl_c_token();
    let bars = Bars::new(quiet);
    let res = mp_pipeline::run(input, out, params, &bars, &cancel);
    drop(bars);
    if cancel.is_cancelled() {
        if out.is_dir() {
            eprintln!("\ninterrupted: {} holds only complete files", out.display());
        } else {
            eprintln!("\ninterrupted before anything was written");
        }
        std::process::exit(130);
    }
    Ok(res?)
}

/// Counted intervals `mp run` prints before "and N more".
const PRINTED_INTERVALS: usize = 10;

/// Prints the counts, the programs, the stage timings and the files.
pub fn print_summary(s: &RunSummary, out: &Path) {
    let o = &s.outcome;
    let c = &o.counts;
    let fps = o.keypoints.track.fps();
    match &o.analysis {
        Some(an) => println!(
            "{} frames × {} joints → {} segments ({} primitives); the abstract program has {} program loop{}",
            an.concrete.n_frames(),
            an.concrete.n_joints(),
            an.concrete.n_segments(),
            an.concrete.n_segments() * an.concrete.n_joints(),
            an.loops.len(),
            if an.loops.len() == 1 { "" } else { "s" }
        ),
        None => println!(
            "{} frames: no person found in any frame, so no programs; counted from the frames",
            o.keypoints.track.n_frames()
        ),
    }
    println!(
        "{} repetition{} (from the {}, {}, confidence {:.2})",
        c.total,
        if c.total == 1 { "" } else { "s" },
        c.signal.as_str(),
        c.method.as_str(),
        c.confidence
    );
    for (i, iv) in c.intervals.iter().enumerate().take(PRINTED_INTERVALS) {
        println!(
            "  interval {}: frames {:<11} ({:.2}–{:.2} s)  {} repetition{}, period {:.2} s",
            i + 1,
            mp_geom::frames_label(iv.start_frame, iv.end_frame),
            iv.start_frame as f64 / fps,
            iv.end_frame as f64 / fps,
            iv.count,
            if iv.count == 1 { "" } else { "s" },
            iv.period_frames as f64 / fps
        );
    }
    if c.intervals.len() > PRINTED_INTERVALS {
        println!(
            "  and {} more intervals (every one in loops.json and `mp loops`)",
            c.intervals.len() - PRINTED_INTERVALS
        );
    }
    print_people(o);
    println!();
    println!("{}", stage_table(s));
    if let Some(r) = &s.report {
        println!("Report: {}", r.display());
    }
    println!("All files in {}/: {}", out.display(), file_list(&s.files));
}

/// The files of a run as one line: plots, the report's frames and data, and
/// the other people's programs are named by their folder (an hour with a
/// hundred people writes four hundred files there).
fn file_list(files: &[String]) -> String {
    let mut names: Vec<String> = Vec::new();
    let mut people: Vec<&str> = Vec::new();
    for f in files {
        let name = match f.split_once('/') {
            Some((dir @ ("plots" | "report"), _)) => format!("{dir}/"),
            Some(("people", rest)) => {
                let id = rest.split('/').next().unwrap_or(rest);
                if !people.contains(&id) {
                    people.push(id);
                }
                "people/".to_string()
            }
            _ => f.clone(),
        };
        if !names.contains(&name) {
            names.push(name);
        }
    }
    if let Some(k) = names.iter().position(|n| n == "people/") {
        let who = if people.len() == 1 {
            "person"
        } else {
            "people"
        };
        names[k] = format!("people/ ({} other {who}'s programs)", people.len());
    }
    names.join(", ")
}

/// One line per tracked person (when people were tracked), and the warning
/// about people beyond `max_people`.
pub fn print_people(o: &mp_pipeline::Outcome) {
    if let Some(w) = &o.keypoints.warning {
        eprintln!("note: {w}");
    }
    if o.people.is_empty() {
        return;
    }
    let fps = o.keypoints.track.fps();
    println!(
        "{} {} tracked:",
        o.people.len(),
        if o.people.len() == 1 {
            "person"
        } else {
            "people"
        }
    );
    for p in &o.people {
        let what = match &p.counts {
            Some(c) => format!(
                "{} repetition{} ({}, {}, confidence {:.2})",
                c.total,
                if c.total == 1 { "" } else { "s" },
                c.signal.as_str(),
                c.method.as_str(),
                c.confidence
            ),
            None => "seen too briefly to analyse".to_string(),
        };
        println!(
            "  person {}{}: frames {}–{} ({:.1}–{:.1} s, found in {}) · {}",
            p.id,
            if p.main { " (main)" } else { "" },
            p.first_frame,
            p.last_frame,
            p.first_frame as f64 / fps,
            p.last_frame as f64 / fps,
            p.frames_found,
            what
        );
    }
}

/// The stage-timing table.
pub fn stage_table(s: &RunSummary) -> String {
    let o = &s.outcome;
    let mut t = String::from("stage        time (s)   frames/s   peak MB\n");
    for st in &o.stages {
        let secs = st.time.as_secs_f64();
        let fps = if secs > 0.0 && st.frames > 0 {
            format!("{:9.1}", st.frames as f64 / secs)
        } else {
            format!("{:>9}", "–")
        };
        let peak = st
            .peak_bytes
            .map_or_else(|| "–".to_string(), |b| format!("{:.0}", b as f64 / 1e6));
        t.push_str(&format!(
            "{:<12} {:>8.2}  {}  {:>8}   {}\n",
            st.stage.name(),
            secs,
            fps,
            peak,
            st.stage.note()
        ));
    }
    let total = o.total.as_secs_f64();
    let motion_s = o.motion_s();
    t.push_str(&format!(
        "{:<12} {:>8.2}  {:9.1}   ({:.1} s of motion: {:.2}× real time)\n",
        "total",
        total,
        o.keypoints.track.n_frames() as f64 / total.max(1e-9),
        motion_s,
        motion_s / total.max(1e-9)
    ));
    t
}

#[cfg(test)]
mod tests {
    use super::file_list;

    #[test]
    fn folders_of_many_files_are_named_once() {
        let files: Vec<String> = [
            "track.npz",
            "people/3/program.txt",
            "people/3/abstract.json",
            "people/12/program.txt",
            "plots/a.svg",
            "plots/b.svg",
            "report/data/0.json",
            "overlay.mp4",
        ]
        .map(String::from)
        .to_vec();
        assert_eq!(
            file_list(&files),
            "track.npz, people/ (2 other people's programs), plots/, report/, overlay.mp4"
        );
        let one = ["people/3/program.txt".to_string()];
        assert_eq!(file_list(&one), "people/ (1 other person's programs)");
    }
}
