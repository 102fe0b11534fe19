//! AFL harness for `mp_fuzz::abstract_json`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::abstract_json(data);
    });
}
