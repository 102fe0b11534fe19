//! Properties of random derivation on grammars learned by ABL from random
//! corpora: every derived sentence is in the grammar's language, the same
//! seed gives the same derivation, and regeneration keeps everything outside
//! the regenerated subtree.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use mp_grammar::{derive_at_least, regenerate, DeriveParams};
use mp_grammar::{learn, AblParams, Alignment};
use proptest::prelude::*;

fn corpus() -> impl Strategy<Value = Vec<Vec<u32>>> {
    prop::collection::vec(prop::collection::vec(0u32..5, 2..8), 2..7)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn derived_sentences_parse(c in corpus(), seed in 0u64..1000, st in any::<bool>()) {
        let names: Vec<String> = (0..5).map(|i| format!("t{i}")).collect();
        let p = AblParams {
            alignment: Alignment::from_flag(if st { "st3" } else { "wm" }).unwrap(),
            ..Default::default()
        };
        let g = learn(&c, &names, &p).unwrap().grammar;
        let dp = DeriveParams { max_depth: 6, max_terminals: 40, ..Default::default() };
        let d = derive_at_least(&g, &dp, 10, seed).unwrap();
        prop_assert_eq!(&d, &derive_at_least(&g, &dp, 10, seed).unwrap());
        prop_assert!(d.len() >= 10);
        for t in &d.sentences {
            let s = t.yield_terminals();
            prop_assert!(g.parse(&s).is_some(), "not derivable: {:?}\n{}", s, g);
        }
        let all = d.terminals();
        let i = (seed as usize) % all.len();
        let r = regenerate(&g, &d, i, 0, &dp, seed + 1).unwrap();
        let new = r.derivation.terminals();
        let old = &r.ancestor.terminals;
        prop_assert!(old.contains(&i));
        prop_assert_eq!(&new[..old.start], &all[..old.start]);
        prop_assert_eq!(&new[r.new_terminals.end..], &all[old.end..]);
        for t in &r.derivation.sentences {
            prop_assert!(g.parse(&t.yield_terminals()).is_some());
        }
    }
}
