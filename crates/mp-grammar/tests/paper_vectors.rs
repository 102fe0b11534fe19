//! Test vectors from the motion-grammar paper (Park, Lee & Lee 2011), the
//! ABL reference documentation and the Sequitur documentation.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use mp_grammar::abl::{align_and_cluster, learn, AblParams, Alignment, Corpus, Selection};
use mp_grammar::grammar::Grammar;
use mp_grammar::sentences::{score_partition, search_partition, PartitionParams};

fn chars(s: &str) -> Vec<String> {
    s.chars().map(|c| c.to_string()).collect()
}

/// §5.1: `abxcd|abycd|abxcd` with {S → a b A c d, A → x | y} costs 3 bits.
#[test]
fn mdl_paper_example() {
    let g = Grammar::from_text("S -> a b A c d\nA -> x\nA -> y", None).unwrap();
    let z = g
        .encode_sentences(&[chars("abxcd"), chars("abycd"), chars("abxcd")])
        .unwrap();
    assert_eq!(g.encoding_bits(&z).unwrap(), 3.0);
}

/// The good partition has a lower DL than `abxc|dabycda|bxcd`, with every
/// ABL alignment method, and ABL learns exactly the paper's grammar.
#[test]
fn mdl_prefers_the_paper_partition() {
    let c = Corpus::from_sentences(&[chars("abxcdabycdabxcd")]);
    let s = &c.sentences[0];
    for flag in ["wm", "st3"] {
        let abl = AblParams {
            alignment: Alignment::from_flag(flag).unwrap(),
            ..Default::default()
        };
        let good = score_partition(s, &[5, 10], &c.vocab, &abl).unwrap();
        let bad = score_partition(s, &[4, 11], &c.vocab, &abl).unwrap();
        assert!(
            good.dl.total_bits < bad.dl.total_bits,
            "{flag}: {:?} vs {:?}",
            good.dl,
            bad.dl
        );
        if flag == "wm" {
            let text = good.learned.grammar.to_string();
            assert_eq!(good.learned.grammar.n_rules(), 3, "{text}");
            assert_eq!(good.dl.data_bits, 3.0, "{text}");
            assert!(text.contains("S -> a b X1 c d"), "{text}");
        }
    }
    // The search finds a partition at least as good as the paper's.
    let best = search_partition(
        s,
        &c.vocab,
        &PartitionParams {
            abl: AblParams {
                alignment: Alignment::from_flag("wm").unwrap(),
                ..Default::default()
            },
            ..Default::default()
        },
    )
    .unwrap();
    let good = score_partition(
        s,
        &[5, 10],
        &c.vocab,
        &AblParams {
            alignment: Alignment::from_flag("wm").unwrap(),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(best.dl.total_bits <= good.dl.total_bits + 1e-9);
}

/// ABL reference documentation: `she is smart` / `she is tired`.
#[test]
fn abl_she_is_smart() {
    let c = Corpus::from_lines("she is smart\nshe is tired\n").unwrap();
    for flag in ["wm", "st1", "st3"] {
        let p = AblParams {
            alignment: Alignment::from_flag(flag).unwrap(),
            ..Default::default()
        };
        let (store, _) = align_and_cluster(&c.sentences, &p);
        for s in 0..2 {
            let mut v: Vec<(usize, usize, u32)> = store.sentences[s]
                .iter()
                .map(|h| (h.b, h.e, h.labels[0]))
                .collect();
            v.sort_unstable();
            assert_eq!(v, vec![(0, 3, 0), (2, 3, 1)], "{flag} sentence {s}");
        }
    }
}

/// Paper §7: the grammar learned from the six basketball strings derives
/// all of them and is compact (paper: 5 nonterminals, 11 rules).
#[test]
fn basketball_six_strings() {
    let words = ["rfdpm", "rfdsm", "rdfsm", "rdpm", "rdsm", "rpm"];
    let sentences: Vec<Vec<String>> = words.iter().map(|w| chars(w)).collect();
    let c = Corpus::from_sentences(&sentences);
    for (flag, sel) in [
        ("st3", Selection::Branch),
        ("wm", Selection::Branch),
        ("wm", Selection::First),
    ] {
        let p = AblParams {
            alignment: Alignment::from_flag(flag).unwrap(),
            selection: sel,
            seed: 0,
        };
        let r = learn(&c.sentences, &c.vocab, &p).unwrap();
        let g = &r.grammar;
        for (i, s) in c.sentences.iter().enumerate() {
            let t = g
                .parse(s)
                .unwrap_or_else(|| panic!("{flag}: {} not derivable\n{g}", words[i]));
            assert_eq!(&t.yield_terminals(), s);
            assert_eq!(&r.trees[i].yield_terminals(), s);
        }
        println!(
            "{flag} {sel:?}: {} nonterminals, {} rules\n{g}",
            g.n_nonterminals(),
            g.n_rules()
        );
        // Paper (reference ABL, st3 + branch): 5 nonterminals, 11 rules.
        if flag == "st3" {
            assert!(
                g.n_rules() <= 18 && g.n_nonterminals() <= 8,
                "{flag}: not compact\n{g}"
            );
        }
        assert!(g.n_nonterminals() >= 2, "{flag}: no structure found\n{g}");
    }
}

#[test]
fn bad_input_is_an_error() {
    let c = Corpus::from_sentences(&[chars("ab")]);
    assert!(learn(&[], &c.vocab, &AblParams::default()).is_err());
    assert!(learn(&[vec![]], &c.vocab, &AblParams::default()).is_err());
    assert!(learn(&[vec![7]], &c.vocab, &AblParams::default()).is_err());
    assert!(Corpus::from_lines("\n \n").is_err());
    assert!(search_partition(&[], &c.vocab, &PartitionParams::default()).is_err());
    assert!(score_partition(&c.sentences[0], &[0], &c.vocab, &AblParams::default()).is_err());
    assert!(Alignment::from_flag("xx").is_err());
    assert!(PartitionParams {
        min_sentence_len: 0,
        ..Default::default()
    }
    .validate()
    .is_err());
}
