//! AFL harness for `mp_fuzz::grammar_text`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::grammar_text(data);
    });
}
