//! Writes the seed corpora under `crates/mp-fuzz/corpus/<target>/` with the
//! project's own writers (and a few hand-written texts), deterministically.
//!
//! ```text
//! cargo run -p mp-fuzz --example make_corpus
//! ```

use std::path::{Path, PathBuf};

use mp_abstract::LoopParams;
use mp_concrete::{Program, Segment};
use mp_geom::fuzzing::csv::{track_to_csv_string, CsvLayout};
use mp_geom::fuzzing::native::{track_to_bincode, track_to_json_string, track_to_npz_bytes};
use mp_geom::fuzzing::npz::NpzOut;
use mp_geom::fuzzing::people::{people_to_bincode, people_to_json_string, people_to_npz_bytes};
use mp_geom::{People, Person, Primitive, Skeleton, Track, Units};
use ndarray::{Array2, Array3};

type Res<T> = Result<T, Box<dyn std::error::Error>>;

fn put(dir: &Path, target: &str, name: &str, bytes: impl AsRef<[u8]>) -> Res<()> {
    let d = dir.join(target);
    std::fs::create_dir_all(&d)?;
    std::fs::write(d.join(name), bytes)?;
    Ok(())
}

/// A small track: `t` frames of `j` joints in `d` dimensions on smooth curves.
fn track(t: usize, j: usize, d: usize, skeleton: Skeleton, units: Units) -> Res<Track> {
    let pos = Array3::from_shape_fn((t, j, d), |(f, k, a)| {
        let x = f as f64 * 0.25 + k as f64;
        let v = if a % 2 == 0 { x.sin() } else { x.cos() };
        (100.0 * v + 10.0 * k as f64).round() / 4.0
    });
    let conf = Array2::from_shape_fn((t, j), |(f, k)| if (f + k) % 7 == 3 { 0.0 } else { 0.9 });
    Ok(Track::new(pos, Some(conf), 30.0, units, skeleton)?)
}

fn program(dims: usize, joints: &[&str], pattern: &[(usize, usize)]) -> Program {
    let segments = pattern
        .iter()
        .enumerate()
        .map(|(si, &(dur, kind))| Segment {
            duration_frames: dur,
            primitives: (0..joints.len())
                .map(|ji| {
                    let base: Vec<f64> = (0..dims)
                        .map(|a| 10.0 * ji as f64 + a as f64 + 0.5 * si as f64)
                        .collect();
                    match kind {
                        0 => Primitive::Stationary { point: base },
                        1 => Primitive::Line {
                            start: base,
                            velocity: (0..dims).map(|a| 0.25 * a as f64 - 0.5).collect(),
                        },
                        2 => Primitive::Circle {
                            center: base,
                            radius: 12.5,
                            angle_start: 30.0,
                            angle_vel: 4.5,
                            angle_acc: if dims == 2 { 0.0 } else { -0.125 },
                            axes: Vec::new(),
                        },
                        _ => Primitive::Spline {
                            coeffs: (0..dims).map(|a| [base[a], 0.5, -0.25, 0.125]).collect(),
                        },
                    }
                })
                .collect(),
        })
        .collect();
    Program {
        fps: 30.0,
        units: if dims == 2 {
            Units::Pixels
        } else {
            Units::Metres
        },
        dims,
        skeleton: "generic".into(),
        joints: joints.iter().map(|s| s.to_string()).collect(),
        continuity: if dims == 2 {
            mp_concrete::Continuity::None
        } else {
            mp_concrete::Continuity::C0
        },
        segments,
    }
}

fn main() -> Res<()> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("corpus");

    // Concrete programs: DSL, JSON, binary.
    let programs = [
        program(2, &["right_wrist", "neck"], &[(7, 2), (4, 0), (5, 1)]),
        program(3, &["a"], &[(3, 3), (2, 1)]),
        program(
            2,
            &["hand"],
            &[
                (6, 1),
                (6, 0),
                (6, 1),
                (6, 0),
                (6, 1),
                (6, 0),
                (6, 1),
                (6, 0),
            ],
        ),
    ];
    for (i, p) in programs.iter().enumerate() {
        p.validate()?;
        put(&dir, "concrete_dsl", &format!("program{i}.mp"), p.to_dsl())?;
        put(
            &dir,
            "program_json",
            &format!("program{i}.json"),
            p.to_json()?,
        )?;
        put(&dir, "mpb", &format!("program{i}.mpb"), p.to_bincode()?)?;
    }
    put(
        &dir,
        "concrete_dsl",
        "pretty.mp",
        programs[0].to_dsl_pretty(2),
    )?;
    put(
        &dir,
        "concrete_dsl",
        "docs_example.mp",
        "# Anything after '#' is a comment.\n\
         program(fps=30, units=px, dims=2, skeleton=\"penn13\")\n\n\
         joint \"right_wrist\" {\n\
         \x20   circular_motion(center=(220.56, 175.67), radius=108.23, angle=3.17*t + 79.99, duration=7)\n\
         \x20   stationary(x=129.25, y=121.59, duration=4);\n\
         \x20   spline(x=0.5*t^3 + -1*t^2 + 2*t + 3, y=1e-3*t + 4, duration=2)\n\
         }\n",
    )?;

    // Abstract programs from the concrete ones (loops found by the analyser).
    for (i, p) in programs.iter().enumerate() {
        let (a, _, _) = mp_abstract::AbstractProgram::from_concrete(p, &LoopParams::default())?;
        put(
            &dir,
            "abstract_dsl",
            &format!("abstract{i}.mpa"),
            a.to_dsl(),
        )?;
        put(
            &dir,
            "abstract_json",
            &format!("abstract{i}.json"),
            serde_json::to_string_pretty(&a)?,
        )?;
    }

    // Tracks in every format.
    let tracks = [
        track(4, 17, 2, Skeleton::coco17(), Units::Pixels)?,
        track(3, 3, 3, Skeleton::generic(3), Units::Metres)?,
    ];
    for (i, t) in tracks.iter().enumerate() {
        put(
            &dir,
            "npz",
            &format!("track{i}.npz"),
            track_to_npz_bytes(t)?,
        )?;
        put(
            &dir,
            "json_track",
            &format!("track{i}.json"),
            track_to_json_string(t)?,
        )?;
        put(&dir, "mpt", &format!("track{i}.mpt"), track_to_bincode(t)?)?;
        put(
            &dir,
            "csv",
            &format!("wide{i}.csv"),
            track_to_csv_string(t, CsvLayout::Wide)?,
        )?;
        put(
            &dir,
            "csv",
            &format!("long{i}.csv"),
            track_to_csv_string(t, CsvLayout::Long)?,
        )?;
        let mut npy = Vec::new();
        ndarray_npy::WriteNpyExt::write_npy(&t.positions(), &mut npy)?;
        put(&dir, "npy", &format!("positions{i}.npy"), npy)?;
    }
    put(
        &dir,
        "csv",
        "long_indices.csv",
        "# a comment\nframe,joint,x,y,z,score\n0,0,1,2,3,0.5\n0,1,4,5,6,1\n2,1,,nan,7,0.25\n",
    )?;
    // People in the three forms: two people whose spans overlap (one
    // starting after the video's first frame, one ending before its last),
    // two in 3-D with ids that leave gaps, and a video with nobody in it.
    let people = [
        (
            "two_people",
            People::new(
                8,
                30.0,
                vec![
                    Person {
                        id: 1,
                        first_frame: 2,
                        track: track(5, 17, 2, Skeleton::coco17(), Units::Pixels)?,
                    },
                    Person {
                        id: 2,
                        first_frame: 0,
                        track: track(4, 17, 2, Skeleton::coco17(), Units::Pixels)?,
                    },
                ],
            )?,
        ),
        (
            "two_people_3d",
            People::new(
                4,
                30.0,
                vec![
                    Person {
                        id: 3,
                        first_frame: 0,
                        track: track(4, 3, 3, Skeleton::generic(3), Units::Metres)?,
                    },
                    Person {
                        id: 7,
                        first_frame: 3,
                        track: track(1, 3, 3, Skeleton::generic(3), Units::Metres)?,
                    },
                ],
            )?,
        ),
        ("nobody", People::new(5, 25.0, Vec::new())?),
    ];
    for (name, p) in &people {
        put(
            &dir,
            "people",
            &format!("{name}.npz"),
            people_to_npz_bytes(p)?,
        )?;
        put(
            &dir,
            "people",
            &format!("{name}.json"),
            people_to_json_string(p)?,
        )?;
        put(
            &dir,
            "people",
            &format!("{name}.mpt"),
            people_to_bincode(p)?,
        )?;
    }

    // Other npy dtypes and an npz with strings and integers.
    let mut out = NpzOut::new(false);
    out.add("positions", &Array3::<f64>::zeros((2, 2, 2)))?;
    out.add("fps", &ndarray::arr0(25.0f64))?;
    out.add("ints", &ndarray::arr1(&[1i32, -2, 3]))?;
    out.add_strings("joints", &["a".into(), "bé".into()], &[2])?;
    put(&dir, "npz", "stored_mixed.npz", out.finish()?)?;
    let mut npy = Vec::new();
    ndarray_npy::WriteNpyExt::write_npy(&Array3::<f32>::ones((2, 3, 2)), &mut npy)?;
    put(&dir, "npy", "float32.npy", npy)?;
    put(
        &dir,
        "npy",
        "unicode.npy",
        mp_geom::fuzzing::npz::unicode_npy_bytes(&["nose".into(), "hip".into()], &[2])?,
    )?;

    // OpenPose frames (BODY_25, COCO-18) and an AlphaPose result list.
    let kp = |n: usize, s: f64| -> String {
        (0..n)
            .map(|k| format!("{},{},{}", 10 * k, 20 + k, s))
            .collect::<Vec<_>>()
            .join(",")
    };
    put(
        &dir,
        "openpose",
        "body25_keypoints.json",
        format!(
            "{{\"version\":1.3,\"people\":[{{\"person_id\":[-1],\"pose_keypoints_2d\":[{}]}},\
             {{\"pose_keypoints_2d\":[{}]}}]}}",
            kp(25, 0.8),
            kp(25, 0.3)
        ),
    )?;
    put(
        &dir,
        "openpose",
        "coco18_keypoints.json",
        format!("{{\"people\":[{{\"pose_keypoints\":[{}]}}]}}", kp(18, 0.5)),
    )?;
    put(&dir, "openpose", "nobody_keypoints.json", "{\"people\":[]}")?;
    put(
        &dir,
        "openpose",
        "alphapose.json",
        format!(
            "[{{\"image_id\":\"0.jpg\",\"keypoints\":[{}],\"score\":2.5}},\
             {{\"image_id\":\"0.jpg\",\"keypoints\":[{}],\"score\":1.0}},\
             {{\"image_id\":7,\"keypoints\":[{}]}}]",
            kp(17, 0.9),
            kp(17, 0.2),
            kp(26, 0.6)
        ),
    )?;

    // BVH: parsed and written back by the project's writer.
    let bvh_text = "HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 0 0\n\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n\
        \tJOINT Spine\n\t{\n\t\tOFFSET 0 5.5 0\n\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n\
        \t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 3 0\n\t\t}\n\t}\n\
        \tJOINT LeftUpLeg\n\t{\n\t\tOFFSET 1.5 0 0\n\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n\
        \t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 -4 0\n\t\t}\n\t}\n}\n\
        MOTION\nFrames: 2\nFrame Time: 0.0333333\n\
        0 10 0 0 0 0 5 0 0 0 -10 0\n0.5 10.25 0 1 2 3 5 0 0 0 -12.5 0\n";
    put(&dir, "bvh", "small.bvh", bvh_text)?;
    let b = mp_geom::fuzzing::bvh::Bvh::parse(bvh_text, "small.bvh")?;
    put(&dir, "bvh", "small_written.bvh", b.to_bvh_string())?;

    // Grammar rules text and a symbol corpus.
    put(
        &dir,
        "grammar_text",
        "rules.txt",
        "# start symbol first\nS -> A B | A S\nA -> a b\nB → c | ε\n",
    )?;
    put(
        &dir,
        "grammar_text",
        "sentences.txt",
        "she is smart\nshe is tired\n\nab xc d ab yc d\n",
    )?;
    put(&dir, "grammar_text", "symbols.txt", "abxcdabycdabxcd")?;

    // A grammar model learned from a small periodic motion.
    let motion = mp_grammar::Motion {
        track: {
            let t = 240;
            let pos = Array3::from_shape_fn((t, 3, 3), |(f, k, a)| {
                let ph = (f % 30) as f64 / 30.0 * std::f64::consts::TAU;
                (ph + k as f64 + a as f64).sin() * (1.0 + k as f64)
            });
            Track::new(pos, None, 30.0, Units::Metres, Skeleton::generic(3))?
        },
        bvh: None,
        paths: vec![PathBuf::from("periodic.npz")],
        frame_step: 1,
    };
    let mut params = mp_grammar::PipelineParams::default();
    params.symbols.k = 3;
    params.symbols.candidate_step_frames = 10;
    params.symbols.min_segment_frames = 5;
    params.symbols.max_segment_frames = 40;
    match mp_grammar::learn_model(&motion, &params) {
        Ok(m) => put(
            &dir,
            "grammar_json",
            "model.json",
            serde_json::to_string_pretty(&m)?,
        )?,
        Err(e) => return Err(format!("grammar model not learned: {e}").into()),
    }

    // Anchor concepts of two actions.
    let samples: Vec<mp_refine::AnchorSample> = (0..24)
        .map(|i| mp_refine::AnchorSample {
            action: 1 + (i % 2) as u32,
            feature: (0..4)
                .map(|k| ((i * 7 + k * 3) % 11) as f64 * 0.25 + (i % 3) as f64)
                .collect(),
        })
        .collect();
    let params = mp_refine::ConceptParams {
        method: mp_refine::ClusterMethod::kmeans(2),
        ..Default::default()
    };
    let c = mp_refine::learn_concepts(&samples, &params)?;
    put(&dir, "concepts_json", "concepts.json", c.to_json()?)?;
    Ok(())
}
