//! Fuzz targets: one function per reader or parser of the project.
//!
//! Each target takes arbitrary bytes, hands them to one reader and, when
//! reading succeeds, exercises the result a little: it writes it back with
//! the project's own writer, reads that again and checks that the round trip
//! gives back the same value, and calls a few of the accessors callers use
//! right after reading. A target returns normally on every input; a panic
//! (an index out of range, an overflow, a failed round trip) is a bug in the
//! reader.
//!
//! The targets are shared by the coverage-guided AFL harness (`fuzz/`, run
//! with `scripts/fuzz.sh`) and the smoke tests (`tests/smoke.rs`), which
//! replay the seed corpora under `corpus/<target>/` and a bounded,
//! deterministic mutation loop.
//!
//! | target | reader |
//! |---|---|
//! | `concrete_dsl` | [`mp_concrete::Program::from_dsl`] |
//! | `abstract_dsl` | [`mp_abstract::AbstractProgram::read_str`] (text form) |
//! | `program_json` | [`mp_concrete::Program::from_json`] |
//! | `abstract_json` | [`mp_abstract::AbstractProgram::read_str`] (JSON) |
//! | `grammar_json` | [`mp_grammar::GrammarModel::from_json`] |
//! | `grammar_text` | [`mp_grammar::Grammar::from_text`], [`mp_grammar::Corpus::from_lines`], [`mp_grammar::fuzzing`] |
//! | `npz` | [`mp_geom::fuzzing::npz::Npz::from_bytes`], [`mp_geom::fuzzing::native::track_from_npz`] |
//! | `npy` | [`mp_geom::fuzzing::npz::NpyArray::from_bytes`], [`mp_geom::fuzzing::native::track_from_npy_bytes`] |
//! | `csv` | [`mp_geom::fuzzing::csv::track_from_csv_str`] |
//! | `json_track` | [`mp_geom::fuzzing::native::track_from_json_str`] |
//! | `openpose` | [`mp_geom::fuzzing::openpose::openpose_from_frames`], [`mp_geom::fuzzing::openpose::alphapose_from_value`] |
//! | `bvh` | [`mp_geom::fuzzing::bvh::Bvh::parse`] |
//! | `mpt` | [`mp_geom::fuzzing::native::track_from_bincode`] |
//! | `mpb` | [`mp_concrete::Program::from_bincode`] |
//! | `concepts_json` | [`mp_refine::Concepts::from_json`] |
//! | `people` | [`mp_geom::fuzzing::people::people_from_npz`], [`mp_geom::fuzzing::people::people_from_json_str`], [`mp_geom::fuzzing::people::people_from_bincode`] |

use mp_abstract::AbstractProgram;
use mp_concrete::Program;
use mp_geom::fuzzing::bvh::{Bvh, BvhTrackParams};
use mp_geom::fuzzing::csv::{track_from_csv_str, track_to_csv_string, CsvLayout};
use mp_geom::fuzzing::native::{
    track_from_bincode, track_from_json_str, track_from_npy_bytes, track_from_npz,
    track_to_bincode, track_to_json_string, track_to_npz_bytes,
};
use mp_geom::fuzzing::npz::{NpyArray, Npz};
use mp_geom::fuzzing::openpose::{alphapose_from_value, openpose_from_frames};
use mp_geom::fuzzing::people::{
    is_people_bincode, is_people_json, is_people_npz, people_from_bincode, people_from_json_str,
    people_from_npz, people_to_bincode, people_to_json_string, people_to_npz_bytes,
};
use mp_geom::ReadOptions;
use mp_geom::{People, Track};
use mp_grammar::{fuzzing as strings, Corpus, Grammar, GrammarModel};
use mp_refine::Concepts;
use std::path::{Path, PathBuf};

/// A fuzz target: takes any bytes, never panics.
pub type Target = fn(&[u8]);

/// Every target by name, in a fixed order.
pub const TARGETS: &[(&str, Target)] = &[
    ("concrete_dsl", concrete_dsl),
    ("abstract_dsl", abstract_dsl),
    ("program_json", program_json),
    ("abstract_json", abstract_json),
    ("grammar_json", grammar_json),
    ("grammar_text", grammar_text),
    ("npz", npz),
    ("npy", npy),
    ("csv", csv),
    ("json_track", json_track),
    ("openpose", openpose),
    ("bvh", bvh),
    ("mpt", mpt),
    ("mpb", mpb),
    ("concepts_json", concepts_json),
    ("people", people),
];

/// The target called `name`.
pub fn target(name: &str) -> Option<Target> {
    TARGETS.iter().find(|(n, _)| *n == name).map(|(_, f)| *f)
}

/// Symbol strings longer than this are not analysed (the suffix array is
/// `O(n log² n)`; the fuzzer's inputs stay far below it anyway).
const MAX_SYMBOLS: usize = 4096;

fn text(data: &[u8]) -> Option<&str> {
    std::str::from_utf8(data).ok()
}

/// Exact equality of two tracks, bit for bit (NaN-safe), through the
/// binary form.
fn same_track(a: &Track, b: &Track) -> bool {
    match (track_to_bincode(a), track_to_bincode(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

/// Writes a concrete program back in all three forms and reads each again.
fn check_program(p: &Program) {
    let dsl = p.to_dsl();
    match Program::from_dsl(&dsl) {
        Ok(q) => assert_eq!(&q, p, "DSL round trip changed the program:\n{dsl}"),
        Err(e) => panic_msg(&format!("printed DSL does not parse: {e}\n{dsl}")),
    }
    let json = p.to_json();
    assert!(json.is_ok(), "program does not serialise to JSON");
    if let Ok(json) = json {
        match Program::from_json(&json) {
            Ok(q) => assert_eq!(&q, p, "JSON round trip changed the program"),
            Err(e) => panic_msg(&format!("written JSON does not read back: {e}\n{json}")),
        }
    }
    match p.to_bincode() {
        Ok(bytes) => match Program::from_bincode(&bytes) {
            Ok(q) => assert_eq!(&q, p, "binary round trip changed the program"),
            Err(e) => panic_msg(&format!("binary form does not read back: {e}")),
        },
        Err(e) => panic_msg(&format!("valid program does not encode: {e}")),
    }
    let _ = (p.n_frames(), p.n_params(), p.boundaries(), p.kind_counts());
    let _ = p.skeleton();
    for j in 0..p.n_joints() {
        let _ = p.joint_statements(j);
    }
}

/// Reports a broken invariant (the fuzzer records the input).
#[allow(clippy::panic)]
fn panic_msg(msg: &str) {
    panic!("{msg}");
}

/// Concrete-program DSL text ([`Program::from_dsl`]).
pub fn concrete_dsl(data: &[u8]) {
    let Some(src) = text(data) else { return };
    if let Ok(p) = Program::from_dsl(src) {
        check_program(&p);
        let _ = p.to_dsl_pretty(2);
    }
}

/// Concrete program JSON ([`Program::from_json`]).
pub fn program_json(data: &[u8]) {
    let Some(src) = text(data) else { return };
    if let Ok(p) = Program::from_json(src) {
        check_program(&p);
    }
}

/// Concrete program binary form `.mpb` ([`Program::from_bincode`]).
pub fn mpb(data: &[u8]) {
    if let Ok(p) = Program::from_bincode(data) {
        check_program(&p);
    }
}

fn check_abstract(p: &AbstractProgram) {
    let printed = p.to_dsl();
    match AbstractProgram::read_str(&printed, Path::new("fuzz.mpa")) {
        Ok(q) => assert_eq!(
            &q, p,
            "text round trip changed the abstract program:\n{printed}"
        ),
        Err(e) => panic_msg(&format!(
            "printed abstract program does not parse: {e}\n{printed}"
        )),
    }
    match serde_json::to_string(p) {
        Ok(json) => match AbstractProgram::read_str(&json, Path::new("fuzz.json")) {
            Ok(q) => assert_eq!(&q, p, "JSON round trip changed the abstract program"),
            Err(e) => panic_msg(&format!("written JSON does not read back: {e}\n{json}")),
        },
        Err(e) => panic_msg(&format!("abstract program does not serialise: {e}")),
    }
    let _ = p.to_dsl_with(&mp_abstract::PrintOptions::summary());
    let _ = (p.loop_indices(), p.expected_frames());
}

/// Abstract-program text form ([`AbstractProgram::from_dsl`] through
/// [`AbstractProgram::read_str`]).
pub fn abstract_dsl(data: &[u8]) {
    let Some(src) = text(data) else { return };
    if let Ok(p) = AbstractProgram::read_str(src, Path::new("fuzz.mpa")) {
        check_abstract(&p);
    }
}

/// Abstract-program JSON ([`AbstractProgram::read_str`] with a `.json` name).
pub fn abstract_json(data: &[u8]) {
    let Some(src) = text(data) else { return };
    if let Ok(p) = AbstractProgram::read_str(src, Path::new("fuzz.json")) {
        check_abstract(&p);
    }
}

/// Grammar model JSON ([`GrammarModel::from_json`]).
pub fn grammar_json(data: &[u8]) {
    let Some(src) = text(data) else { return };
    let path = Path::new("fuzz.grammar.json");
    if let Ok(m) = GrammarModel::from_json(src, path) {
        match serde_json::to_string(&m) {
            Ok(json) => match GrammarModel::from_json(&json, path) {
                Ok(q) => assert_eq!(q, m, "JSON round trip changed the grammar model"),
                Err(e) => panic_msg(&format!("written model does not read back: {e}")),
            },
            Err(e) => panic_msg(&format!("grammar model does not serialise: {e}")),
        }
        let _ = m.rules_text();
        let _ = m.training_string();
        let _ = m.grammar.grammar_bits();
        let _ = m.grammar.used_terminals();
    }
}

/// Grammar rules text ([`Grammar::from_text`]), the same text as a corpus
/// of sentences ([`Corpus::from_lines`]) and the bytes as a symbol string
/// ([`strings`]: suffix array, LCP array, repeats, protected spans).
pub fn grammar_text(data: &[u8]) {
    if let Some(src) = text(data) {
        if let Ok(g) = Grammar::from_text(src, None) {
            assert!(g.validate().is_ok(), "a grammar read from text is invalid");
            let printed = g.to_string();
            let _ = (
                g.grammar_bits(),
                g.used_terminals(),
                g.rules_per_nonterminal(),
            );
            let short: Vec<u32> = (0..g.terminals.len().min(4) as u32).collect();
            let _ = g.parse(&short);
            assert!(!printed.is_empty(), "a grammar with rules prints nothing");
        }
        if let Ok(c) = Corpus::from_lines(src) {
            assert!(
                c.sentences
                    .iter()
                    .flatten()
                    .all(|&w| (w as usize) < c.vocab.len()),
                "corpus sentence refers to a word outside the vocabulary"
            );
        }
    }
    if data.len() <= MAX_SYMBOLS {
        let s: Vec<u32> = data.iter().map(|&b| u32::from(b % 16)).collect();
        let sa = strings::suffix_array(&s);
        let mut seen = vec![false; s.len()];
        for &i in &sa {
            assert!(i < s.len() && !seen[i], "suffix array is not a permutation");
            seen[i] = true;
        }
        for w in sa.windows(2) {
            assert!(s[w[0]..] < s[w[1]..], "suffix array is not sorted");
        }
        let lcp = strings::lcp_array(&s, &sa);
        assert_eq!(lcp.len(), s.len(), "LCP array length");
        let _ = strings::repeat_classes(&s);
        let spans = strings::protected_spans(&s, 2);
        let _ = strings::allowed_cuts(s.len(), &spans);
    }
}

/// `.npz` archives ([`Npz::from_bytes`], every member converted, and
/// [`track_from_npz`]).
pub fn npz(data: &[u8]) {
    let Ok(z) = Npz::from_bytes(data.to_vec(), "fuzz.npz") else {
        return;
    };
    for name in z.names().to_vec() {
        if let Ok(a) = z.array(&name) {
            exercise_npy(&a);
        }
    }
    if let Ok(t) = track_from_npz(&z) {
        match track_to_npz_bytes(&t) {
            Ok(bytes) => {
                match Npz::from_bytes(bytes, "fuzz.npz").and_then(|z| track_from_npz(&z)) {
                    Ok(u) => assert!(same_track(&t, &u), "npz round trip changed the track"),
                    Err(e) => panic_msg(&format!("written npz does not read back: {e}")),
                }
            }
            Err(e) => panic_msg(&format!("track does not encode as npz: {e}")),
        }
    }
}

fn exercise_npy(a: &NpyArray) {
    let _ = a.to_f64();
    let _ = a.to_i64();
    let _ = a.to_strings();
    let _ = a.scalar_f64();
    let _ = a.scalar_string();
    let _ = a.expect_shape("fuzz", &[None, None, None]);
}

/// `.npy` arrays ([`NpyArray::from_bytes`] and [`track_from_npy_bytes`]).
pub fn npy(data: &[u8]) {
    if let Ok(a) = NpyArray::from_bytes(data, "fuzz.npy") {
        exercise_npy(&a);
    }
    let opts = ReadOptions::default();
    if let Ok(t) = track_from_npy_bytes(data, Path::new("fuzz.npy"), &opts) {
        let _ = (t.n_frames(), t.n_joints(), t.dims());
    }
}

/// CSV tracks, long and wide ([`track_from_csv_str`]); a track read is
/// written as wide CSV and read again.
pub fn csv(data: &[u8]) {
    let Some(src) = text(data) else { return };
    let opts = ReadOptions::default();
    let path = Path::new("fuzz.csv");
    if let Ok(t) = track_from_csv_str(src, path, &opts) {
        for layout in [CsvLayout::Wide, CsvLayout::Long] {
            match track_to_csv_string(&t, layout) {
                Ok(out) => match track_from_csv_str(&out, path, &opts) {
                    Ok(u) => assert_eq!(
                        u.positions().dim(),
                        t.positions().dim(),
                        "{layout:?} CSV round trip changed the shape:\n{out}"
                    ),
                    Err(e) => panic_msg(&format!(
                        "written {layout:?} CSV does not read back: {e}\n{out}"
                    )),
                },
                Err(e) => panic_msg(&format!("track does not write as {layout:?} CSV: {e}")),
            }
        }
    }
}

/// The project's JSON tracks ([`track_from_json_str`]).
pub fn json_track(data: &[u8]) {
    let Some(src) = text(data) else { return };
    let path = Path::new("fuzz.json");
    if let Ok(t) = track_from_json_str(src, path) {
        match track_to_json_string(&t) {
            Ok(out) => match track_from_json_str(&out, path) {
                Ok(u) => assert!(same_track(&t, &u), "JSON round trip changed the track"),
                Err(e) => panic_msg(&format!("written JSON track does not read back: {e}")),
            },
            Err(e) => panic_msg(&format!("track does not write as JSON: {e}")),
        }
    }
}

/// OpenPose frames and AlphaPose result lists
/// ([`openpose_from_frames`], [`alphapose_from_value`]).
pub fn openpose(data: &[u8]) {
    let Ok(v) = serde_json::from_slice::<serde_json::Value>(data) else {
        return;
    };
    let opts = ReadOptions::default();
    let path = PathBuf::from("fuzz_keypoints.json");
    let t = if v.is_array() {
        alphapose_from_value(&v, &path, &opts)
    } else {
        // The same frame twice: a two-frame folder.
        openpose_from_frames(&[(path.clone(), v.clone()), (path, v)], &opts)
    };
    if let Ok(t) = t {
        let _ = (t.n_frames(), t.n_joints(), t.dims());
        assert!(
            t.confidence().iter().all(|c| c.is_finite()),
            "non-finite confidence in a track read from keypoints"
        );
    }
}

/// BVH text ([`Bvh::parse`]), written back ([`Bvh::to_bvh_string`]) and
/// read again, then forward kinematics.
pub fn bvh(data: &[u8]) {
    let Some(src) = text(data) else { return };
    let Ok(b) = Bvh::parse(src, "fuzz.bvh") else {
        return;
    };
    let out = b.to_bvh_string();
    match Bvh::parse(&out, "fuzz.bvh") {
        Ok(c) => assert_eq!(c, b, "BVH round trip changed the file:\n{out}"),
        Err(e) => panic_msg(&format!("written BVH does not read back: {e}\n{out}")),
    }
    let _ = (b.n_frames(), b.n_channels(), b.fps(), b.root_channels(0));
    let _ = b.to_track(&BvhTrackParams::default());
    let _ = b.world_positions(1.0, true);
    let _ = b.skeleton(true);
    if b.n_frames() > 1 {
        let _ = b.slice_frames(0, 1);
        let _ = b.concat(&b);
    }
}

/// The binary track form `.mpt` ([`track_from_bincode`]).
pub fn mpt(data: &[u8]) {
    if let Ok(t) = track_from_bincode(data) {
        match track_to_bincode(&t).map(|bytes| track_from_bincode(&bytes)) {
            Ok(Ok(u)) => assert!(same_track(&t, &u), "binary round trip changed the track"),
            Ok(Err(e)) => panic_msg(&format!("written binary track does not read back: {e}")),
            Err(e) => panic_msg(&format!("track does not encode: {e}")),
        }
    }
}

/// Anchor concepts JSON ([`Concepts::from_json`]), written back and scored.
pub fn concepts_json(data: &[u8]) {
    let Some(src) = text(data) else { return };
    let Ok(c) = Concepts::from_json(src) else {
        return;
    };
    match c.to_json() {
        Ok(json) => match Concepts::from_json(&json) {
            Ok(d) => assert_eq!(d, c, "JSON round trip changed the concepts"),
            Err(e) => panic_msg(&format!("written concepts do not read back: {e}")),
        },
        Err(e) => panic_msg(&format!("concepts do not serialise: {e}")),
    }
    if c.dim <= MAX_SYMBOLS {
        let x = vec![0.0; c.dim];
        for (&a, ac) in &c.actions {
            let _ = c.score(a, &x);
            let _ = ac.nearest(&x);
        }
    }
}

/// Values (`n_frames × joints × dims`, summed over people) above which the
/// `people` target does not call the accessors that build whole-video
/// arrays ([`People::full_track`], [`People::main_track`] and the npz
/// writer). The readers accept any `n_frames` that [`People::new`] accepts,
/// so a small JSON or `.mpt` file can declare a video of 10¹⁸ frames around
/// a one-frame person, and those arrays cannot be allocated (ndarray panics
/// or the allocation aborts, in `People::full_track`). Until the readers
/// bound the video's size, the target skips those calls above the bound.
const MAX_PEOPLE_VALUES: usize = 1 << 20;

/// Exact equality of two [`People`], bit for bit (NaN-safe), through the
/// binary form.
fn same_people(a: &People, b: &People) -> bool {
    match (people_to_bincode(a), people_to_bincode(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

/// The first broken invariant of [`People`] (those [`People::new`]
/// documents), if any.
fn people_violation(p: &People) -> Option<String> {
    let n = p.n_frames();
    if n == 0 {
        return Some("a video of 0 frames".into());
    }
    if !(p.fps().is_finite() && p.fps() > 0.0) {
        return Some(format!("fps {}", p.fps()));
    }
    if p.len() != p.people().len() || p.is_empty() != p.people().is_empty() {
        return Some("len/is_empty disagree with people()".into());
    }
    if let Some(w) = p.people().windows(2).find(|w| w[0].id >= w[1].id) {
        return Some(format!("ids {} then {}: not ascending", w[0].id, w[1].id));
    }
    let first = p.people().first()?;
    for q in p.people() {
        let t = &q.track;
        let end = q.first_frame.checked_add(t.n_frames());
        if t.n_frames() == 0 || end.is_none_or(|e| e > n) {
            return Some(format!(
                "person {}: frames {} + {} outside the video's {n}",
                q.id,
                q.first_frame,
                t.n_frames()
            ));
        }
        if q.last_frame() >= n || q.last_frame() < q.first_frame {
            return Some(format!("person {}: last frame {}", q.id, q.last_frame()));
        }
        if t.fps() != p.fps() {
            return Some(format!(
                "person {}: {} fps, video {}",
                q.id,
                t.fps(),
                p.fps()
            ));
        }
        let f = &first.track;
        if t.skeleton() != f.skeleton() || t.units() != f.units() || t.dims() != f.dims() {
            return Some(format!("person {}: skeleton, units or dims differ", q.id));
        }
        if t.positions().dim() != (t.n_frames(), t.n_joints(), t.dims())
            || t.confidence().dim() != (t.n_frames(), t.n_joints())
        {
            return Some(format!("person {}: array shapes", q.id));
        }
        if !t.confidence().iter().all(|c| (0.0..=1.0).contains(c)) {
            return Some(format!("person {}: confidence outside 0..=1", q.id));
        }
        if q.frames_found() > t.n_frames() {
            return Some(format!(
                "person {}: found on more frames than its span",
                q.id
            ));
        }
        if p.get(q.id).map(|r| r.first_frame) != Some(q.first_frame) {
            return Some(format!("person {}: get() does not find them", q.id));
        }
    }
    None
}

/// Checks what a reader gave (`form`): the invariants of [`People`], a
/// round trip through each of the three forms, and the accessors callers
/// use (the main person, whole-video tracks when they are small enough).
fn check_people(p: &People, form: &str) {
    if let Some(v) = people_violation(p) {
        panic_msg(&format!("{form} reader returned invalid people: {v}"));
    }
    match people_to_bincode(p).map(|b| people_from_bincode(&b)) {
        Ok(Ok(q)) => assert!(same_people(p, &q), "binary round trip of {form} people"),
        Ok(Err(e)) => panic_msg(&format!("binary people from {form} do not read back: {e}")),
        Err(e) => panic_msg(&format!("people from {form} do not encode: {e}")),
    }
    let path = Path::new("fuzz.json");
    match people_to_json_string(p).map(|j| people_from_json_str(&j, path)) {
        Ok(Ok(q)) => assert!(same_people(p, &q), "JSON round trip of {form} people"),
        Ok(Err(e)) => panic_msg(&format!("JSON people from {form} do not read back: {e}")),
        Err(e) => panic_msg(&format!("people from {form} do not write as JSON: {e}")),
    }
    for q in p.people() {
        let _ = (q.activity(), q.mean_box(), q.box_at(q.first_frame));
    }
    let main = p.main_person();
    assert_eq!(main.is_none(), p.is_empty(), "main person of {form} people");
    let values = p.people().iter().try_fold(0usize, |acc, q| {
        let t = &q.track;
        p.n_frames()
            .checked_mul(t.n_joints().max(1))?
            .checked_mul(t.dims())?
            .checked_add(acc)
    });
    if values.is_none_or(|v| v > MAX_PEOPLE_VALUES) {
        return;
    }
    if let Some(m) = main {
        match p.main_track() {
            Ok(t) => assert!(
                t.n_frames() == p.n_frames() && t.n_joints() == m.track.n_joints(),
                "main track of {form} people does not cover the video"
            ),
            Err(e) => panic_msg(&format!("main track of {form} people: {e}")),
        }
    }
    match people_to_npz_bytes(p).map(|b| Npz::from_bytes(b, "fuzz.npz")) {
        Ok(Ok(z)) => match people_from_npz(&z) {
            Ok(q) => assert!(same_people(p, &q), "npz round trip of {form} people"),
            Err(e) => panic_msg(&format!("npz people from {form} do not read back: {e}")),
        },
        Ok(Err(e)) => panic_msg(&format!("written people npz does not open: {e}")),
        Err(e) => panic_msg(&format!("people from {form} do not encode as npz: {e}")),
    }
}

/// The people formats ([`mp_geom::fuzzing::people`]), every input through all
/// three readers: npz ([`people_from_npz`]), JSON ([`people_from_json_str`])
/// and binary ([`people_from_bincode`]). What one of them reads must also be
/// recognised by the test `read_people` dispatches on ([`is_people_npz`],
/// [`is_people_json`], [`is_people_bincode`]), keep the invariants of
/// [`People`], and read back the same from each of the three writers.
pub fn people(data: &[u8]) {
    if let Ok(z) = Npz::from_bytes(data.to_vec(), "fuzz.npz") {
        let marked = is_people_npz(&z);
        if let Ok(p) = people_from_npz(&z) {
            assert!(
                marked,
                "people read from an npz without `mp_people_version`"
            );
            check_people(&p, "npz");
        }
    }
    if let Some(src) = text(data) {
        if let Ok(p) = people_from_json_str(src, Path::new("fuzz.json")) {
            // `read_people` routes JSON to this reader by `is_people_json`.
            let routed = serde_json::from_str(src).is_ok_and(|v| is_people_json(&v));
            assert!(routed, "JSON people without `\"format\": \"mp-people\"`");
            check_people(&p, "JSON");
        }
    }
    let marked = is_people_bincode(data);
    if let Ok(p) = people_from_bincode(data) {
        assert!(marked, "binary people without the `mp-people` magic");
        check_people(&p, "binary");
    }
}
