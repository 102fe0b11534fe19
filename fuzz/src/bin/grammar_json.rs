//! AFL harness for `mp_fuzz::grammar_json`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::grammar_json(data);
    });
}
