//! Synthesis on real motion (a slice of a CMU salsa take at 30 fps):
//! determinism, shapes, seams, regeneration, BVH output, and the whole
//! pipeline through its JSON files. Skipped where the shared data are absent.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use mp_geom::Track;
use mp_geom::{Bvh, BvhTrackParams};
use mp_grammar::ClusterQuality;
use mp_grammar::{
    learn_model, DeriveParams, Fsm, FsmWeighting, Grammar, GrammarModel, PipelineParams,
    StitchParams, Stitcher,
};
use mp_grammar::{read_motions, subsample_bvh};
use mp_grammar::{SymbolSearchStats, SymbolSegment, SymbolString};

const SEG: usize = 15;

/// The salsa take's first `frames` frames at 30 fps, or `None` (the skip
/// recorded for the running test) where the shared data are absent.
fn salsa_bvh(frames: usize) -> Option<Bvh> {
    let path = mp_geom::test_support::data_file_or_skip(
        "cmu_salsa_bvh/60_01_scaled.bvh",
        &mp_geom::test_support::current_test_name(),
    )?;
    Some(
        subsample_bvh(&Bvh::read(path).unwrap(), 4)
            .unwrap()
            .slice_frames(0, frames)
            .unwrap(),
    )
}

/// Segments of 15 frames labelled a b c d a b c d …
fn round_robin(n_frames: usize, k: usize) -> SymbolString {
    let segments: Vec<SymbolSegment> = (0..n_frames / SEG)
        .map(|i| SymbolSegment {
            start: i * SEG,
            end: if (i + 1) * SEG + SEG > n_frames {
                n_frames
            } else {
                (i + 1) * SEG
            },
            symbol: i % k,
        })
        .collect();
    SymbolString {
        k,
        n_frames,
        fps: 30.0,
        medoids: (0..k).collect(),
        segments,
        quality: ClusterQuality::from_terms(0.5, 0.5, 0.5),
        d_max: 1.0,
        stats: SymbolSearchStats::default(),
    }
}

struct Fixture {
    bvh: Bvh,
    track: Track,
    symbols: SymbolString,
}

fn fixture() -> Option<Fixture> {
    let bvh = salsa_bvh(300)?;
    let track = bvh.to_track(&BvhTrackParams::default()).unwrap();
    let symbols = round_robin(300, 4);
    Some(Fixture {
        bvh,
        track,
        symbols,
    })
}

fn grammar() -> Grammar {
    Grammar::from_text("S -> a X d\nX -> b X | c | b c", None).unwrap()
}

fn stitcher(f: &Fixture, bvh: bool, blend: usize) -> Stitcher {
    Stitcher::new(
        &f.track,
        bvh.then_some(&f.bvh),
        &f.symbols,
        &StitchParams {
            blend_frames: blend,
            ..Default::default()
        },
    )
    .unwrap()
}

#[test]
fn synthesis_is_seeded_and_well_formed() {
    let Some(f) = fixture() else {
        return;
    };
    let g = grammar();
    for bvh in [false, true] {
        let st = stitcher(&f, bvh, 8);
        let d = DeriveParams::default();
        let a = st.synthesize(&g, &d, 12, 7).unwrap();
        let b = st.synthesize(&g, &d, 12, 7).unwrap();
        let c = st.synthesize(&g, &d, 12, 8).unwrap();
        assert_eq!(a.pieces, b.pieces);
        assert_eq!(a.track, b.track);
        assert!(a.pieces != c.pieces || a.track != c.track);
        assert!(a.pieces.len() >= 12);
        assert_eq!(a.track.n_joints(), f.track.n_joints());
        assert_eq!(a.track.dims(), 3);
        assert_eq!(
            a.track.n_frames(),
            a.pieces.iter().map(|p| p.source.len()).sum::<usize>()
        );
        assert!(a.track.positions().iter().all(|v| v.is_finite()));
        // Every sentence of the grammar is a b* c? d style: starts with a, ends with d.
        let names: Vec<usize> = a.symbols.clone();
        assert_eq!(names[0], 0);
        assert_eq!(*names.last().unwrap(), 3);
        assert_eq!(a.bvh.is_some(), bvh);

        // FSM baseline: seeded, same stitching.
        let train: Vec<u32> = f.symbols.segments.iter().map(|s| s.symbol as u32).collect();
        let fsm = Fsm::from_symbols(&train, 4, FsmWeighting::Counts).unwrap();
        let x = st.synthesize_fsm(&fsm, 20, 3).unwrap();
        let y = st.synthesize_fsm(&fsm, 20, 3).unwrap();
        assert_eq!(x.pieces, y.pieces);
        assert_eq!(x.track, y.track);
        assert_eq!(x.pieces.len(), 20);
        // The training string is a b c d a b c d …: so is every FSM string.
        for w in x.symbols.windows(2) {
            assert_eq!(w[1], (w[0] + 1) % 4);
        }
    }
}

#[test]
fn blending_never_widens_seams() {
    let Some(f) = fixture() else {
        return;
    };
    let g = grammar();
    let d = DeriveParams::default();
    for bvh in [false, true] {
        let raw = stitcher(&f, bvh, 0);
        let blended = stitcher(&f, bvh, 8);
        let mut before_sum = 0.0;
        let mut after_sum = 0.0;
        for seed in 0..4 {
            let a = raw.synthesize(&g, &d, 15, seed).unwrap();
            let b = blended.synthesize(&g, &d, 15, seed).unwrap();
            assert_eq!(a.pieces, b.pieces);
            let before = raw.seam_distances(&a).unwrap();
            let after = blended.seam_distances(&b).unwrap();
            // Without blending the seam is the selection gap.
            let segs: Vec<usize> = a.pieces.iter().map(|p| p.segment).collect();
            for (x, y) in before.iter().zip(raw.gaps(&segs)) {
                assert!((x - y).abs() < 1e-5, "{x} vs {y}");
            }
            for (x, y) in before.iter().zip(&after) {
                if !bvh {
                    assert!(*y <= x + 1e-9, "seam {x} became {y}");
                }
            }
            before_sum += before.iter().sum::<f64>();
            after_sum += after.iter().sum::<f64>();
            // The root does not jump at seams: the horizontal root step at a
            // seam is within the largest step inside the source.
            let pos = b.track.positions();
            let src = f.track.positions();
            let step = |p: &ndarray::ArrayView3<f64>, t: usize| {
                ((p[[t, 0, 0]] - p[[t - 1, 0, 0]]).powi(2)
                    + (p[[t, 0, 2]] - p[[t - 1, 0, 2]]).powi(2))
                .sqrt()
            };
            let max_src = (1..src.dim().0).map(|t| step(&src, t)).fold(0.0, f64::max);
            for s in b.seam_frames() {
                assert!(step(&pos, s) <= max_src * 1.01 + 1e-9, "root jump at {s}");
            }
        }
        assert!(
            after_sum < 0.2 * before_sum,
            "bvh {bvh}: {after_sum} vs {before_sum}"
        );
    }
}

#[test]
fn regeneration_changes_only_the_subtree() {
    let Some(f) = fixture() else {
        return;
    };
    let g = grammar();
    let d = DeriveParams::default();
    for bvh in [false, true] {
        let st = stitcher(&f, bvh, 8);
        let old = st.synthesize(&g, &d, 15, 11).unwrap();
        let n = old.pieces.len();
        let mut changed_any = false;
        for (terminal, seed) in [(1usize, 1u64), (n / 2, 2), (n - 2, 3)] {
            let r = st.regenerate(&g, &old, terminal, 0, &d, seed).unwrap();
            let new = &r.synthesis;
            let anc = &r.regeneration.ancestor;
            assert!(anc.terminals.contains(&terminal));
            // The derived string changes only inside the subtree.
            let (ot, nt) = (&old.symbols, &new.symbols);
            let shift = nt.len() as isize - ot.len() as isize;
            assert_eq!(ot[..anc.terminals.start], nt[..anc.terminals.start]);
            assert_eq!(
                ot[anc.terminals.end..],
                nt[(anc.terminals.end as isize + shift) as usize..]
            );
            // Pieces outside keep their source segments.
            assert_eq!(
                old.pieces[..anc.terminals.start],
                new.pieces[..anc.terminals.start]
            );
            // Frames before the region are identical.
            let (op, np) = (old.track.positions(), new.track.positions());
            let fb = r.old_frames.start;
            assert_eq!(r.new_frames.start, fb);
            assert_eq!(
                op.slice(ndarray::s![..fb, .., ..]),
                np.slice(ndarray::s![..fb, .., ..])
            );
            // Frames after it are the old ones moved by one ground-plane offset.
            let (oe, ne) = (r.old_frames.end, r.new_frames.end);
            assert_eq!(op.dim().0 - oe, np.dim().0 - ne);
            if oe < op.dim().0 {
                let off = [
                    np[[ne, 0, 0]] - op[[oe, 0, 0]],
                    np[[ne, 0, 2]] - op[[oe, 0, 2]],
                ];
                for t in 0..op.dim().0 - oe {
                    for j in 0..op.dim().1 {
                        let dx = np[[ne + t, j, 0]] - op[[oe + t, j, 0]];
                        let dy = np[[ne + t, j, 1]] - op[[oe + t, j, 1]];
                        let dz = np[[ne + t, j, 2]] - op[[oe + t, j, 2]];
                        assert!((dx - off[0]).abs() < 1e-9, "frame {t} joint {j}");
                        assert!(dy.abs() < 1e-9);
                        assert!((dz - off[1]).abs() < 1e-9);
                    }
                }
            }
            changed_any |= r.new_frames != r.old_frames
                || np.slice(ndarray::s![fb..ne, .., ..]) != op.slice(ndarray::s![fb..oe, .., ..]);
            assert!(new.track.positions().iter().all(|v| v.is_finite()));
            assert_eq!(new.derivation.as_ref().unwrap().len(), new.pieces.len());
        }
        assert!(changed_any);
    }
}

#[test]
fn bvh_output_parses_back_with_the_input_hierarchy() {
    let Some(f) = fixture() else {
        return;
    };
    let st = stitcher(&f, true, 8);
    let s = st
        .synthesize(&grammar(), &DeriveParams::default(), 10, 5)
        .unwrap();
    let text = s.bvh.as_ref().unwrap().to_bvh_string();
    let back = Bvh::parse(&text, "synth.bvh").unwrap();
    assert_eq!(back.joints(), f.bvh.joints());
    assert_eq!(back.n_frames(), s.track.n_frames());
    assert!((back.frame_time_s() - f.bvh.frame_time_s()).abs() < 1e-12);
    // Its forward kinematics is the synthesised track.
    let t = back.to_track(&BvhTrackParams::default()).unwrap();
    for (a, b) in t.positions().iter().zip(s.track.positions().iter()) {
        assert!((a - b).abs() < 1e-9);
    }
}

/// The whole pipeline on 20 s of salsa at 30 fps with a small search, the
/// JSON round trip of the model, and synthesis from the reloaded model.
#[test]
fn pipeline_on_salsa() {
    let path = mp_geom::data_or_return!("cmu_salsa_bvh/60_01_scaled.bvh");
    let motion = read_motions(&[path], 4).unwrap();
    let mut p = PipelineParams::default();
    p.symbols.k = 6;
    p.symbols.ga.population = 20;
    p.symbols.ga.generations = 15;
    p.symbols.sa.iterations = 100;
    p.symbols.sa.max_iterations = 200;
    p.partition.candidates = 20;
    let m = learn_model(&motion, &p).unwrap();
    assert_eq!(m.symbols.n_frames, motion.track.n_frames());
    assert!(m.grammar.n_rules() >= 1);
    // The grammar derives every training sentence.
    for z in &m.sentences {
        assert!(m.grammar.parse(z).is_some());
    }
    let joined: Vec<u32> = m.sentences.concat();
    let train: Vec<u32> = m.training_string().iter().map(|&s| s as u32).collect();
    assert_eq!(joined, train);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("g.json");
    m.save(&file).unwrap();
    let back = GrammarModel::load(&file).unwrap();
    assert_eq!(back, m);
    assert!(back.rules_text().contains("S -> "));
    let motion2 = back.source.load(None).unwrap();
    let st = back.stitcher(&motion2, &StitchParams::default()).unwrap();
    let s = st
        .synthesize(&back.grammar, &DeriveParams::default(), 10, 1)
        .unwrap();
    assert!(s.pieces.len() >= 10);
    assert!(s.bvh.is_some());
}
