//! AFL harness for `mp_fuzz::concepts_json`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::concepts_json(data);
    });
}
