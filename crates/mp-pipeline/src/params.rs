//! The parameters of a whole run, with the libraries' defaults, validated once.

use mp_abstract::{AbstractParams, CountParams};
use mp_concrete::{Scale, SynthParams};
use mp_geom::PersonId;
use mp_pose::ModelChoice;
use serde::{Deserialize, Serialize};

use crate::error::{PipelineError, Result};

/// Keypoints from video.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PoseParams {
    /// The pose model. Default `ModelChoice::default()` (BlazePose full).
    #[serde(with = "as_text::model")]
    pub model: ModelChoice,
    /// ONNX Runtime threads. Default `SessionParams::default()` (2).
    pub threads: usize,
    /// Keep all of the model's joints (BlazePose: 33) instead of the COCO-17
    /// body joints. Default false.
    pub all_joints: bool,
    /// Only the first N frames. Default all.
    pub max_frames: Option<usize>,
    /// Side of the grey frame thumbnails (cells) that counting reads where
    /// no person is found. Default 32.
    pub thumbnail_size: usize,
    /// BlazePose: seconds after a lost person during which the region of
    /// the last pose is tried again (`mp_pose::BlazePoseParams::recover_s`).
    /// Default 0, MediaPipe's tracking.
    pub recover_s: f64,
    /// Track every person in view (BlazePose: `mp_pose::MultiPose`, the
    /// detector over tiles of the frame and a person tracker). Default true.
    /// False runs MediaPipe's single-person pipeline, which follows one
    /// person (the first the detector finds); MoveNet is always single-person.
    pub people: bool,
    /// The person tracker (`max_people`, detection rates, confirmation).
    pub tracker: mp_pose::PeopleParams,
    /// How often the pose model runs; the frames between are filled from
    /// the motion (`crate::pose_rate`). Default every frame.
    #[serde(with = "as_text::rate")]
    pub rate: crate::pose_rate::PoseRate,
    /// Where the pose model runs (`mp_pose::Device`): the GPU
    /// where ONNX Runtime's CUDA build and a GPU are there, else the CPU
    /// (default, `auto`); `cpu`; or a CUDA device, an error where there is none.
    #[serde(with = "as_text::device")]
    pub device: mp_pose::Device,
    /// Pieces of a long video tracked side by side, each with its own
    /// decoder and model, joined where they overlap
    /// (`mp_pose::join_pieces`). 0 (default): one piece per CPU core (at
    /// most [`PoseParams::MAX_PIECES`]) where the video holds at least
    /// `mp_pose::MIN_PIECE_S` of frames for each, on the CPU, with several
    /// people tracked; 1: never.
    pub pieces: usize,
}

impl PoseParams {
    /// Most pieces [`PoseParams::pieces`] chooses by itself (each holds a
    /// model and a decoder).
    pub const MAX_PIECES: usize = 8;

    /// Share of a person's mean box added on every side for their thumbnails
    /// (arms and legs reach past the mean box during a repetition).
    pub const BOX_MARGIN: f64 = 0.25;

    /// Share of the region (the mean box with [`Self::BOX_MARGIN`]) that must lie
    /// inside the picture for the person's own thumbnails to be read: a
    /// region mostly outside it holds too little of the picture to follow
    /// the person (a person whose box the tracker placed above the frame), and
    /// the whole frame is read instead.
    pub const MIN_BOX_INSIDE: f64 = 0.5;

    /// The region of the picture a person's own thumbnails are read from:
    /// their mean box `[x0, y0, x1, y1]` (pixels) widened by
    /// [`Self::BOX_MARGIN`] on every side; `None` where less than
    /// [`Self::MIN_BOX_INSIDE`] of it lies inside a `width` × `height`
    /// picture (or the box is empty or not finite).
    pub fn own_box_region(mean_box: [f64; 4], width: usize, height: usize) -> Option<[f64; 4]> {
        let b = mean_box;
        if b.iter().any(|v| !v.is_finite()) || b[2] <= b[0] || b[3] <= b[1] {
            return None;
        }
        let (mx, my) = (
            Self::BOX_MARGIN * (b[2] - b[0]),
            Self::BOX_MARGIN * (b[3] - b[1]),
        );
        let r = [b[0] - mx, b[1] - my, b[2] + mx, b[3] + my];
        let inside = |a: f64, b: f64, n: usize| (b.min(n as f64) - a.max(0.0)).max(0.0);
        let area = (r[2] - r[0]) * (r[3] - r[1]);
        let seen = inside(r[0], r[2], width) * inside(r[1], r[3], height);
        (seen >= Self::MIN_BOX_INSIDE * area).then_some(r)
    }

    /// The ONNX Runtime session settings of the pose models.
    pub fn session(&self) -> mp_pose::SessionParams {
        mp_pose::SessionParams {
            intra_threads: self.threads.max(1),
            device: self.device,
            ..Default::default()
        }
    }
}

impl Default for PoseParams {
    fn default() -> Self {
        PoseParams {
            model: ModelChoice::default(),
            threads: mp_pose::SessionParams::default().intra_threads,
            all_joints: false,
            max_frames: None,
            thumbnail_size: mp_pose::DEFAULT_THUMBNAIL_SIZE,
            recover_s: mp_pose::BlazePoseParams::default().recover_s,
            people: true,
            tracker: mp_pose::PeopleParams::default(),
            rate: crate::pose_rate::PoseRate::default(),
            device: mp_pose::Device::default(),
            pieces: 0,
        }
    }
}

/// Whose motion is analysed when several people are in view.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum PersonChoice {
    /// Everyone seen long enough; the main person's results are the
    /// top-level ones. Default.
    #[default]
    All,
    /// Only the main person (`mp_geom::People::main_person`).
    Main,
    /// Only this person, whose results are then the top-level ones.
    Id(PersonId),
}

impl PersonChoice {
    /// Parses `all`, `main` or a person's id.
    pub fn parse(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "all" => Ok(PersonChoice::All),
            "main" => Ok(PersonChoice::Main),
            other => other
                .parse::<PersonId>()
                .map(PersonChoice::Id)
                .map_err(|_| {
                    PipelineError::param(
                        "person",
                        format!("expected all, main or a person's id (1, 2, …), got `{s}`"),
                    )
                }),
        }
    }
}

/// Several people: whom to analyse.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PersonParams {
    /// Whose motion is analysed. Default [`PersonChoice::All`]; in JSON
    /// `"all"`, `"main"` or a person's id.
    #[serde(with = "as_text::person")]
    pub choice: PersonChoice,
    /// Seconds a person must be found in for their own program and count
    /// (the main person always gets them). Default 2: two repetitions of most
    /// exercises, and longer than a passer-by crossing the frame.
    pub min_seen_s: f64,
}

impl Default for PersonParams {
    fn default() -> Self {
        PersonParams {
            choice: PersonChoice::All,
            min_seen_s: 2.0,
        }
    }
}

/// What a run writes besides the programs and counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutputParams {
    /// Plots, timeline, contact sheet and the report (`report.html` and its
    /// folder `report/`). Default true.
    pub report: bool,
    /// `overlay.mp4` for video input. Default true.
    pub overlay_video: bool,
    /// Most frames of a video the report shows (a longer video's every
    /// k-th frame, reduced to 480 pixels on the longer side). Default 1200.
    pub report_frames: usize,
}

impl Default for OutputParams {
    fn default() -> Self {
        OutputParams {
            report: true,
            overlay_video: true,
            report_frames: mp_report::FrameStoreParams::default().max_frames,
        }
    }
}

/// Every parameter of a run. `Params::default()` is what `mp run`, `mp fit`,
/// `mp abstract`, `mp loops`, the evaluations and the Python package use.
///
/// `Params` reads and writes JSON ([`Params::from_json`], [`Params::to_json`]):
/// a partial document changes only the fields it names (the others keep
/// their defaults), and a misspelt field of the run's own sections (`pose`,
/// `output`, `person`) is an error that names it.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Params {
    /// Concrete synthesis (λ from the local spread of the keypoints held
    /// for one second, Euclidean C0 refit, joints the model never saw fitted
    /// to their stored positions) and loop detection. The scale rule
    /// ([`SynthParams::scale`]) is replaced per input: the frame size of a
    /// video (or the one given for a track), else the motion's own extent.
    pub analysis: AbstractParams,
    /// Repetition counting.
    pub count: CountParams,
    /// Keypoints from video.
    pub pose: PoseParams,
    /// Pictures, report, overlay.
    pub output: OutputParams,
    /// Whom to analyse when several people are in view.
    pub person: PersonParams,
}

impl Params {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        self.analysis.synth.validate()?;
        self.analysis.loops.validate()?;
        self.count.validate()?;
        if self.pose.threads == 0 {
            return Err(PipelineError::param("pose.threads", "must be at least 1"));
        }
        if self.output.report_frames == 0 {
            return Err(PipelineError::param(
                "output.report_frames",
                "must be at least 1",
            ));
        }
        if self.pose.max_frames == Some(0) {
            return Err(PipelineError::param(
                "pose.max_frames",
                "must be at least 1",
            ));
        }
        if !(self.pose.recover_s.is_finite() && self.pose.recover_s >= 0.0) {
            return Err(PipelineError::param(
                "pose.recover_s",
                format!(
                    "must be a finite number of seconds ≥ 0, got {}",
                    self.pose.recover_s
                ),
            ));
        }
        self.pose.tracker.validate()?;
        self.pose.rate.validate()?;
        if self.pose.pieces > 256 {
            return Err(PipelineError::param(
                "pose.pieces",
                format!("must be at most 256, got {}", self.pose.pieces),
            ));
        }
        if !(self.person.min_seen_s.is_finite() && self.person.min_seen_s >= 0.0) {
            return Err(PipelineError::param(
                "person.min_seen_s",
                format!(
                    "must be a finite number of seconds ≥ 0, got {}",
                    self.person.min_seen_s
                ),
            ));
        }
        if self.person.choice == PersonChoice::Id(0) {
            return Err(PipelineError::param(
                "person",
                "ids start at 1 (people are numbered 1, 2, … in order of appearance)",
            ));
        }
        if !(1..=256).contains(&self.pose.thumbnail_size) {
            return Err(PipelineError::param(
                "pose.thumbnail_size",
                format!("must be in 1..=256, got {}", self.pose.thumbnail_size),
            ));
        }
        Ok(())
    }

    /// The synthesis parameters for a motion seen in a frame whose largest
    /// side is `frame_px` pixels (`None`: the scale comes from the motion's
    /// own extent).
    pub fn synth_for(&self, frame_px: Option<f64>) -> SynthParams {
        SynthParams {
            scale: match frame_px {
                Some(frame_px) => Scale::FrameSize { frame_px },
                None => self.analysis.synth.scale,
            },
            ..self.analysis.synth.clone()
        }
    }
}

impl Params {
    /// Parameters from a JSON document (see [`Params`]), checked.
    pub fn from_json(text: &str) -> Result<Self> {
        let p: Params = serde_json::from_str(text)
            .map_err(|e| PipelineError::param("params", format!("reading the JSON: {e}")))?;
        p.validate()?;
        Ok(p)
    }

    /// Every parameter as pretty JSON (what `mp params` prints).
    pub fn to_json(&self) -> Result<String> {
        Ok(serde_json::to_string_pretty(self)?)
    }
}

/// The fields whose JSON form is their command-line text
/// (`"full"`, `"auto"`, `"cuda:0"`, `"12"`, `"main"`).
mod as_text {
    use serde::{Deserialize, Deserializer, Serializer};

    fn text<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Text {
            S(String),
            N(f64),
        }
        Ok(match Text::deserialize(d)? {
            Text::S(s) => s,
            Text::N(n) => n.to_string(),
        })
    }

    pub(super) mod model {
        use super::*;
        use mp_pose::ModelChoice;

        pub(crate) fn serialize<S: Serializer>(m: &ModelChoice, s: S) -> Result<S::Ok, S::Error> {
            s.serialize_str(m.as_str())
        }

        pub(crate) fn deserialize<'de, D: Deserializer<'de>>(
            d: D,
        ) -> Result<ModelChoice, D::Error> {
            ModelChoice::parse(&text(d)?).map_err(serde::de::Error::custom)
        }
    }

    pub(super) mod rate {
        use super::*;
        use crate::pose_rate::PoseRate;

        pub(crate) fn serialize<S: Serializer>(r: &PoseRate, s: S) -> Result<S::Ok, S::Error> {
            s.serialize_str(&r.label())
        }

        pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<PoseRate, D::Error> {
            PoseRate::parse(&text(d)?).map_err(serde::de::Error::custom)
        }
    }

    pub(super) mod device {
        use super::*;
        use mp_pose::Device;

        pub(crate) fn serialize<S: Serializer>(v: &Device, s: S) -> Result<S::Ok, S::Error> {
            s.serialize_str(&v.label())
        }

        pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Device, D::Error> {
            Device::parse(&text(d)?).map_err(serde::de::Error::custom)
        }
    }

    pub(super) mod person {
        use super::*;
        use crate::params::PersonChoice;

        pub(crate) fn serialize<S: Serializer>(c: &PersonChoice, s: S) -> Result<S::Ok, S::Error> {
            match c {
                PersonChoice::All => s.serialize_str("all"),
                PersonChoice::Main => s.serialize_str("main"),
                PersonChoice::Id(id) => s.serialize_str(&id.to_string()),
            }
        }

        pub(crate) fn deserialize<'de, D: Deserializer<'de>>(
            d: D,
        ) -> Result<PersonChoice, D::Error> {
            PersonChoice::parse(&text(d)?).map_err(serde::de::Error::custom)
        }
    }
}

#[cfg(test)]
mod json_tests {
    use super::*;

    #[test]
    fn a_box_mostly_outside_the_picture_is_not_read() {
        // 100 × 200 box: widened by a quarter on every side to 150 × 300.
        let r = PoseParams::own_box_region([100.0, 50.0, 200.0, 250.0], 640, 360).unwrap();
        assert_eq!(r, [75.0, 0.0, 225.0, 300.0]);
        // Mostly above the frame (half rate of a hidden dancer: y from -90 to 33).
        assert_eq!(
            PoseParams::own_box_region([172.6, -90.8, 498.8, 32.9], 640, 360),
            None
        );
        // A box cut by the edge but mostly inside is still read.
        assert!(PoseParams::own_box_region([237.2, -28.6, 395.7, 431.0], 640, 480).is_some());
        assert_eq!(
            PoseParams::own_box_region([1.0, 1.0, 1.0, 5.0], 640, 360),
            None
        );
        assert_eq!(
            PoseParams::own_box_region([f64::NAN, 1.0, 2.0, 5.0], 640, 360),
            None
        );
    }

    #[test]
    fn the_defaults_go_through_json_unchanged() {
        let p = Params::default();
        let text = p.to_json().unwrap();
        assert_eq!(Params::from_json(&text).unwrap(), p);
        assert!(text.contains("\"model\": \"full\""), "{text}");
    }

    #[test]
    fn a_partial_document_changes_only_what_it_names() {
        let p = Params::from_json(
            r#"{"pose": {"model": "lite", "rate": 12, "tracker": {"max_people": 3}},
                "person": {"choice": "main"},
                "count": {"min_strength": 0.4},
                "analysis": {"synth": {"max_segment_frames": 40}}}"#,
        )
        .unwrap();
        let d = Params::default();
        assert_eq!(p.pose.model, ModelChoice::Lite);
        assert_eq!(p.pose.rate, crate::PoseRate::parse("12").unwrap());
        assert_eq!(p.pose.tracker.max_people, 3);
        assert_eq!(p.pose.tracker.lost_s, d.pose.tracker.lost_s);
        assert_eq!(p.person.choice, PersonChoice::Main);
        assert_eq!(p.analysis.synth.max_segment_frames, 40);
        assert_eq!(p.count.min_strength, 0.4);
        assert_eq!(p.count.period, d.count.period);
        assert_eq!(p.analysis.synth.lambda, d.analysis.synth.lambda);
        assert_eq!(p.output, d.output);
    }

    #[test]
    fn misspelt_fields_and_bad_values_are_named() {
        let e = Params::from_json(r#"{"pose": {"modle": "lite"}}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("modle"), "{e}");
        let e = Params::from_json(r#"{"pose": {"model": "huge"}}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("huge"), "{e}");
        let e = Params::from_json(r#"{"pose": {"threads": 0}}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("threads"), "{e}");
        assert!(Params::from_json("not json").is_err());
    }
}
